#define _POSIX_C_SOURCE 200809L
#include "render/renderer.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "core/clock.h"
#include "core/parallel.h"
#include "render/progress.h"

enum { TILE_SIZE = RENDERER_TILE_SIZE };

/* A worker's flags, a cache line each (a worker writes in_film per
 * sample). */
typedef struct {
    atomic_int in_film;  /* 1 while it adds to the film (film_enter) */
    atomic_int finished; /* 1 once its figures are written */
    char pad[64 - 2 * sizeof(atomic_int)];
} worker_slot;

typedef struct {
    render_scene *rs;
    pixel_bounds bounds;
    int tiles_x, tile_count;
    int sample_begin, sample_end;
    const unsigned char *active; /* NULL: every pixel */
    /* Textures are filtered: camera rays carry differentials, scaled by
     * max(1/8, 1/sqrt(spp)) as pbrt-v4's (unless the pixel jitter is off),
     * spp the sampler's count (the same in every progressive pass);
     * 0 = no differentials (the same main rays). */
    double diff_scale;
    bool surfaces; /* the film wants each sample's visible surface (gbuffer) */
    atomic_int next_tile;
    atomic_int tiles_done;
    atomic_int running; /* workers not yet finished */
    /* The last worker to finish wakes the calling thread (which otherwise
     * naps between progress updates): a short render is not held up by a nap. */
    pthread_mutex_t lock;
    pthread_cond_t wake;
    int (*tile_source)(void *); /* NULL: the counter next_tile */
    void *tile_ctx;
    /* Read only by the calling thread, where the signal handler that sets it
     * runs (render threads block the signals); it passes the request on to
     * the workers through `stop`, an atomic. */
    const volatile sig_atomic_t *cancel; /* NULL: never */
    atomic_int stop;    /* no further tile is claimed */
    /* The calling thread gave up on the workers still running (a cancel
     * they did not finish their tiles for): they add no further sample to
     * the film (film_enter) and end at their next one. */
    atomic_int abandon;
    atomic_uchar *tile_done; /* per tile: 1 once its last pixel is on the film */
    worker_slot *slots;      /* one per thread */
    camera_sample_needs needs;
    /* Raster rectangle outside which camera rays hit nothing and bring
     * black (render_scene_black_outside), grown by the reach of a pixel's
     * samples; its tiles skip the integrator. */
    bool black_outside;
    double raster_bounds[4];
    integrator_counters *counters; /* one per thread */
    uint64_t *busy_ns;         /* one per thread */
    long *rendered;            /* pixels rendered, one per thread */
} render_job;

typedef struct {
    render_job *job;
    int index;
} worker_arg;

camera_sample renderer_camera_sample(const filter *flt, sampler_state *st, int px, int py)
{
    return renderer_camera_sample_needs(flt, st, px, py, (camera_sample_needs){true, true, true});
}

camera_sample renderer_camera_sample_needs(const filter *flt, sampler_state *st, int px, int py,
                                           camera_sample_needs needs)
{
    /* As pbrt-v4's GetCameraSample; the pixel dimension has its own tag, so
     * not drawing it moves no other dimension. */
    filter_sample fs = needs.jitter ? filter_sample_offset(flt, sampler_pixel_2d(st))
                                    : (filter_sample){v2(0.0, 0.0), 1.0};
    camera_sample cs;
    cs.p_film = v2(px + 0.5 + fs.p.x, py + 0.5 + fs.p.y);
    cs.filter_weight = fs.weight;
    if (needs.time) {
        cs.time = sampler_1d(st);
    } else {
        sampler_skip(st, 1);
        cs.time = 0.5;
    }
    if (needs.lens) {
        cs.p_lens = sampler_2d(st);
    } else {
        sampler_skip(st, 1);
        cs.p_lens = v2(0.5, 0.5);
    }
    return cs;
}

/* A worker adds to the film only between film_enter and film_leave, so the
 * calling thread can stop it from touching the film without waiting for the
 * radiance it is computing (a sample may take seconds): it sets
 * job->abandon, then waits until each in_film reads 0
 * (abandon_slow_workers). Both sides store their own flag, then load the
 * other's, sequentially consistent: either the worker sees `abandon` and
 * stays out for good, or the calling thread sees it inside and waits the
 * few instructions of its film update. */
static bool film_enter(render_job *job, worker_slot *slot)
{
    atomic_store(&slot->in_film, 1);
    if (!atomic_load(&job->abandon))
        return true;
    atomic_store_explicit(&slot->in_film, 0, memory_order_release);
    return false;
}

static void film_leave(worker_slot *slot)
{
    atomic_store_explicit(&slot->in_film, 0, memory_order_release);
}

/* Whether every sample of the tile [x0, x1) x [y0, y1) lies outside the
 * job's raster bounds. */
static bool tile_black(const render_job *job, int x0, int y0, int x1, int y1)
{
    const double *b = job->raster_bounds;
    return job->black_outside && (x1 < b[0] || x0 > b[1] || y1 < b[2] || y0 > b[3]);
}

/* A pixel of a black tile (tile_black): its camera rays hit nothing and
 * bring black. They exist (a perspective or orthographic camera without a
 * lens makes every ray it is asked for), so the film gets the samples it
 * would get: black, with each sample's filter weight (1 at pixel centres,
 * drawn as render_pixel draws it otherwise). Neither the rays nor the
 * integrator are made. */
static bool render_black_pixel(render_job *job, int px, int py, worker_slot *slot,
                               integrator_counters *counters)
{
    const sampler *smp = render_scene_sampler(job->rs);
    const filter *flt = render_scene_filter(job->rs);
    film *f = render_scene_film(job->rs);
    film_surface vs;
    vs.hit = false;
    /* Its samples are quick: the film is entered once for all of them. */
    if (!film_enter(job, slot))
        return false;
    for (int i = job->sample_begin; i < job->sample_end; ++i) {
        double weight = 1.0;
        if (job->needs.jitter) {
            sampler_state st;
            sampler_start(smp, px, py, i, &st);
            weight = filter_sample_offset(flt, sampler_pixel_2d(&st)).weight;
        }
        counters->camera_rays++;
        uint64_t t0 = counters->timed ? hz_clock_ns() : 0;
        film_add_black(f, px, py, weight);
        if (job->surfaces)
            film_add_surface(f, px, py, weight, &vs);
        if (counters->timed)
            counters->film_ns += hz_clock_ns() - t0;
    }
    film_leave(slot);
    return true;
}

/* All the pixel's samples onto the film; false when the worker was
 * abandoned before the last (the pixel is then incomplete). */
static bool render_pixel(render_job *job, int px, int py, worker_slot *slot,
                         integrator_counters *counters)
{
    const camera *cam = render_scene_camera(job->rs);
    const sampler *smp = render_scene_sampler(job->rs);
    const filter *flt = render_scene_filter(job->rs);
    film *f = render_scene_film(job->rs);

    for (int i = job->sample_begin; i < job->sample_end; ++i) {
        sampler_state st;
        sampler_start(smp, px, py, i, &st);
        camera_sample cs = renderer_camera_sample_needs(flt, &st, px, py, job->needs);

        /* Set field by field: zeroing these structs (some 170 bytes each)
         * for every sample cost 5% of a render with nothing to march. */
        ray_differential rd;
        rd.has_differentials = false;
        /* pbrt-v4's camera ray weight; 0: no ray (a realistic camera's
         * vignetted sample), black at its filter weight as in pbrt-v4. */
        double cw = job->diff_scale > 0.0 ? camera_generate_ray_differential_weighted(cam, cs, &rd)
                                          : camera_generate_ray_weighted(cam, cs, &rd.r);
        if (cw > 0.0 && rd.has_differentials)
            ray_scale_differentials(&rd, job->diff_scale);
        double depth = INFINITY;
        film_surface vs; /* visible_surface_at sets every field of a hit */
        vs.hit = false;
        rgb L = cw > 0.0 ? render_scene_li_surface(job->rs, &rd, &st, &depth,
                                                   job->surfaces ? &vs : NULL, counters)
                         : rgb_grey(0.0);
        if (cw != 1.0)
            L = rgb_scale(L, cw);
        if (!film_enter(job, slot))
            return false;
        uint64_t t0 = counters->timed ? hz_clock_ns() : 0;
        film_add_sample(f, px, py, L, cs.filter_weight, depth);
        if (job->surfaces)
            film_add_surface(f, px, py, cs.filter_weight, &vs);
        if (counters->timed)
            counters->film_ns += hz_clock_ns() - t0;
        film_leave(slot);
    }
    return true;
}

/* Denormals flushed to zero on render threads (FTZ and DAZ): a transmittance
 * or weight that small is noise far below a pixel's precision, and denormal
 * arithmetic costs some hundred cycles per operation on x86. */
static void flush_denormals(void)
{
#if defined(__SSE2__)
    _mm_setcsr(_mm_getcsr() | 0x8040u);
#endif
}

/* Tile t's pixels onto the film (those of job->active); false when the
 * worker was abandoned inside it. *rendered counts its complete pixels. */
static bool render_tile(render_job *job, int t, worker_slot *slot, integrator_counters *counters,
                        long *rendered)
{
    int x0 = job->bounds.x0 + (t % job->tiles_x) * TILE_SIZE;
    int y0 = job->bounds.y0 + (t / job->tiles_x) * TILE_SIZE;
    int x1 = x0 + TILE_SIZE < job->bounds.x1 ? x0 + TILE_SIZE : job->bounds.x1;
    int y1 = y0 + TILE_SIZE < job->bounds.y1 ? y0 + TILE_SIZE : job->bounds.y1;
    int w = job->bounds.x1 - job->bounds.x0;
    bool black = tile_black(job, x0, y0, x1, y1);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            if (job->active &&
                !job->active[(size_t)(y - job->bounds.y0) * w + (x - job->bounds.x0)])
                continue;
            if (!(black ? render_black_pixel(job, x, y, slot, counters)
                        : render_pixel(job, x, y, slot, counters)))
                return false;
            ++*rendered;
        }
    return true;
}

static void *worker_main(void *p)
{
    worker_arg *arg = p;
    render_job *job = arg->job;
    worker_slot *slot = &job->slots[arg->index];
    flush_denormals();
    /* Counted on this thread's stack, not in the shared array: neighbouring
     * threads' counters would share cache lines. */
    integrator_counters local = job->counters[arg->index];
    integrator_counters *counters = &local;
    uint64_t start = hz_clock_ns();
    long rendered = 0;
    for (;;) {
        if (atomic_load_explicit(&job->stop, memory_order_relaxed))
            break; /* claimed tiles stay a prefix: they are finished unless abandoned */
        int t = job->tile_source ? job->tile_source(job->tile_ctx)
                               : atomic_fetch_add(&job->next_tile, 1);
        if (t < 0 || t >= job->tile_count)
            break;
        if (!render_tile(job, t, slot, counters, &rendered))
            break; /* abandoned: the tile stays not done */
        atomic_store_explicit(&job->tile_done[t], 1, memory_order_release);
        atomic_fetch_add(&job->tiles_done, 1);
    }
    job->busy_ns[arg->index] = hz_clock_ns() - start;
    job->rendered[arg->index] = rendered;
    job->counters[arg->index] = local;
    /* An abandoned worker may get here while the calling thread sums the
     * figures: it reads only those of finished workers. */
    atomic_store_explicit(&slot->finished, 1, memory_order_release);
    pthread_mutex_lock(&job->lock);
    atomic_fetch_sub(&job->running, 1);
    pthread_cond_signal(&job->wake);
    pthread_mutex_unlock(&job->lock);
    return NULL;
}

static double now_seconds(void) { return hz_clock_seconds(); }

/* The sync the workers and the calling thread share; the condition's clock
 * is the monotonic one of the naps' deadlines (wait_for_workers). */
static void job_init_sync(render_job *job)
{
    atomic_init(&job->next_tile, 0);
    atomic_init(&job->tiles_done, 0);
    atomic_init(&job->running, 0);
    atomic_init(&job->stop, 0);
    atomic_init(&job->abandon, 0);
    pthread_mutex_init(&job->lock, NULL);
    pthread_condattr_t cattr;
    pthread_condattr_init(&cattr);
    pthread_condattr_setclock(&cattr, CLOCK_MONOTONIC);
    pthread_cond_init(&job->wake, &cattr);
    pthread_condattr_destroy(&cattr);
}

/* What camera rays need and carry, and where they bring black (tile_black). */
static void job_init_camera_rays(render_job *job, const renderer_options *opt, int spp)
{
    render_scene *rs = job->rs;
    render_motion motion = render_scene_motion(rs);
    job->surfaces = film_wants_surface(render_scene_film(rs));
    if (render_scene_has_textures(rs))
        job->diff_scale = opt->disable_pixel_jitter ? 1.0 : fmax(0.125, 1.0 / sqrt(spp));
    render_scene_set_footprint_scale(rs, job->diff_scale);
    job->needs = (camera_sample_needs){!opt->disable_pixel_jitter,
                                       motion.camera || motion.surfaces || motion.media > 0,
                                       camera_has_lens(render_scene_camera(rs))};
    job->black_outside = render_scene_black_outside(rs, job->raster_bounds);
    if (job->black_outside) {
        /* A pixel's samples lie within the filter's radius of its centre
         * (at it without jitter): one pixel more for rounding. */
        vec2 r = opt->disable_pixel_jitter ? v2(0.0, 0.0)
                                           : filter_radius(render_scene_filter(rs));
        job->raster_bounds[0] -= r.x + 1.0;
        job->raster_bounds[1] += r.x + 1.0;
        job->raster_bounds[2] -= r.y + 1.0;
        job->raster_bounds[3] += r.y + 1.0;
    }
}

static void job_init(render_job *job, render_scene *rs, const renderer_options *opt)
{
    const film_params *fp = film_get_params(render_scene_film(rs));
    memset(job, 0, sizeof *job);
    job->rs = rs;
    job->bounds = fp->bounds;
    int w = fp->bounds.x1 - fp->bounds.x0, h = fp->bounds.y1 - fp->bounds.y0;
    job->tiles_x = (w + TILE_SIZE - 1) / TILE_SIZE;
    job->tile_count = job->tiles_x * ((h + TILE_SIZE - 1) / TILE_SIZE);
    int spp = render_scene_sampler(rs)->spp;
    job->sample_begin = opt->sample_begin;
    job->sample_end = opt->sample_end > 0 ? opt->sample_end : spp;
    assert(0 <= job->sample_begin && job->sample_begin <= job->sample_end &&
           job->sample_end <= spp);
    job_init_sync(job);
    job->active = opt->active;
    job->tile_source = opt->next_tile;
    job->tile_ctx = opt->tile_ctx;
    job->cancel = opt->cancel;
    job_init_camera_rays(job, opt, spp);
}

/* `threads` (<= 0: every core), but no more than there are tiles. */
static int worker_count(int threads, int tile_count)
{
    if (threads <= 0)
        threads = hz_core_count();
    if (threads > tile_count)
        threads = tile_count > 0 ? tile_count : 1;
    return threads;
}

/* Each thread's counters and flags, the tiles' flags, and the threads' ids
 * and arguments. */
static hz_status job_alloc_workers(render_job *job, int threads, bool timed, pthread_t **tids,
                                   worker_arg **args)
{
    job->counters = calloc((size_t)threads, sizeof *job->counters);
    job->busy_ns = calloc((size_t)threads, sizeof *job->busy_ns);
    job->rendered = calloc((size_t)threads, sizeof *job->rendered);
    job->slots = calloc((size_t)threads, sizeof *job->slots);
    job->tile_done = calloc(job->tile_count > 0 ? (size_t)job->tile_count : 1,
                            sizeof *job->tile_done);
    *tids = calloc((size_t)threads, sizeof **tids);
    *args = calloc((size_t)threads, sizeof **args);
    if (!job->counters || !job->busy_ns || !job->rendered || !job->slots || !job->tile_done ||
        !*tids || !*args)
        return HZ_ERROR;
    for (int i = 0; i < threads; ++i) {
        job->counters[i].timed = timed;
        atomic_init(&job->slots[i].in_film, 0);
        atomic_init(&job->slots[i].finished, 0);
    }
    for (int t = 0; t < job->tile_count; ++t)
        atomic_init(&job->tile_done[t], 0);
    return HZ_OK;
}

static void job_free(render_job *job, pthread_t *tids, worker_arg *args)
{
    free(job->counters);
    free(job->busy_ns);
    free(job->rendered);
    free(job->slots);
    free(job->tile_done);
    free(tids);
    free(args);
    pthread_cond_destroy(&job->wake);
    pthread_mutex_destroy(&job->lock);
    free(job);
}

/* Returns how many of `threads` workers started. */
static int start_workers(render_job *job, pthread_t *tids, worker_arg *args, int threads)
{
    /* Workers inherit a mask without SIGINT/SIGTERM/SIGHUP: a handler then
     * runs on this thread, whose nap it interrupts. */
    sigset_t block, old;
    sigemptyset(&block);
    sigaddset(&block, SIGINT);
    sigaddset(&block, SIGTERM);
    sigaddset(&block, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &block, &old);
    int started = 0;
    for (; started < threads; ++started) {
        args[started] = (worker_arg){job, started};
        atomic_fetch_add(&job->running, 1);
        if (pthread_create(&tids[started], NULL, worker_main, &args[started]) != 0) {
            atomic_fetch_sub(&job->running, 1);
            break;
        }
    }
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    return started;
}

/* The CLOCK_MONOTONIC time `seconds` from now. */
static struct timespec monotonic_after(double seconds)
{
    struct timespec until;
    clock_gettime(CLOCK_MONOTONIC, &until);
    until.tv_nsec += (long)(seconds * 1e9);
    while (until.tv_nsec >= 1000000000L) {
        until.tv_sec += 1;
        until.tv_nsec -= 1000000000L;
    }
    return until;
}

/* Shows progress until the workers finish, or tells them to stop on a
 * cancel or at the deadline. True when a cancel stopped them. */
static bool wait_for_workers(render_job *job, const renderer_options *opt, progress_bar *bar,
                             double t0)
{
    progress_begin(bar, opt->progress, job->tile_count, t0);
    bool cancelled = false;
    pthread_mutex_lock(&job->lock);
    while (atomic_load(&job->running) > 0) {
        double now = now_seconds();
        cancelled = job->cancel && *job->cancel;
        if (cancelled || (opt->deadline > 0 && now >= opt->deadline)) {
            atomic_store(&job->stop, 1);
            break;
        }
        progress_update(bar, opt->tiles_shown ? opt->tiles_shown(opt->tile_ctx)
                                              : atomic_load(&job->tiles_done),
                        now);
        /* Up to 100 ms or to the deadline; the last worker's signal, or a
         * cancel noticed then, ends it. */
        double nap = 0.1;
        if (opt->deadline > 0 && opt->deadline - now < nap)
            nap = opt->deadline - now;
        struct timespec until = monotonic_after(nap);
        pthread_cond_timedwait(&job->wake, &job->lock, &until);
    }
    pthread_mutex_unlock(&job->lock);
    return cancelled;
}

/* After a cancel the workers get RENDERER_CANCEL_GRACE_S to finish their
 * tiles (16x16 pixels of an ordinary scene take a fraction of a second);
 * a tile can take minutes, so then the workers still running are abandoned:
 * told to add nothing more to the film, and waited for only while they are
 * inside it. They may go on computing a sample, reading the scene and `job`
 * (which then outlive them). */
static void abandon_slow_workers(render_job *job, int started)
{
    struct timespec until = monotonic_after(RENDERER_CANCEL_GRACE_S);
    pthread_mutex_lock(&job->lock);
    int rc = 0;
    while (atomic_load(&job->running) > 0 && rc != ETIMEDOUT)
        rc = pthread_cond_timedwait(&job->wake, &job->lock, &until);
    bool late = atomic_load(&job->running) > 0;
    pthread_mutex_unlock(&job->lock);
    if (!late)
        return;
    atomic_store(&job->abandon, 1);
    for (int i = 0; i < started; ++i)
        while (atomic_load(&job->slots[i].in_film))
            sched_yield(); /* a film update: some instructions */
}

/* Joins the workers that finished and detaches the others (abandoned:
 * they end on their own, or with the process). Returns how many were
 * left running. */
static int end_workers(render_job *job, pthread_t *tids, int started)
{
    int left = 0;
    for (int i = 0; i < started; ++i) {
        /* Without an abandon every worker ends after its tile: wait for it. */
        if (!atomic_load(&job->abandon) ||
            atomic_load_explicit(&job->slots[i].finished, memory_order_acquire)) {
            pthread_join(tids[i], NULL);
        } else {
            pthread_detach(tids[i]);
            ++left;
        }
    }
    return left;
}

/* Tile t's pixel rectangle, relative to the bounds. */
static void tile_rect(const render_job *job, int t, int *x0, int *y0, int *x1, int *y1)
{
    int w = job->bounds.x1 - job->bounds.x0, h = job->bounds.y1 - job->bounds.y0;
    *x0 = (t % job->tiles_x) * TILE_SIZE;
    *y0 = (t / job->tiles_x) * TILE_SIZE;
    *x1 = *x0 + TILE_SIZE < w ? *x0 + TILE_SIZE : w;
    *y1 = *y0 + TILE_SIZE < h ? *y0 + TILE_SIZE : h;
}

/* Appends tile range [a, b] ("a-b", or "a" alone) to `buf` of `size`
 * bytes, which holds *len: false, and nothing appended, when it does not
 * fit. */
static bool append_range(char *buf, size_t size, size_t *len, int a, int b)
{
    char item[32];
    int n = a == b ? snprintf(item, sizeof item, "%s%d", *len ? "," : "", a)
                   : snprintf(item, sizeof item, "%s%d-%d", *len ? "," : "", a, b);
    if (n < 0 || *len + (size_t)n >= size)
        return false;
    memcpy(buf + *len, item, (size_t)n + 1);
    *len += (size_t)n;
    return true;
}

/* The done tiles of a stopped render as stats->tile_ranges, with their count
 * and pixels. A range that does not fit in the text counts as not done (its
 * done[] cleared), so the text always names exactly the tiles kept. */
static void describe_done_tiles(const render_job *job, unsigned char *done, render_stats *stats)
{
    size_t len = 0;
    bool full = false;
    stats->tile_ranges[0] = '\0';
    stats->tiles_done = 0;
    stats->pixels = 0;
    for (int t = 0; t < job->tile_count; ++t) {
        if (!done[t])
            continue;
        int e = t;
        while (e + 1 < job->tile_count && done[e + 1])
            ++e;
        full = full || !append_range(stats->tile_ranges, sizeof stats->tile_ranges, &len, t, e);
        for (; t <= e; ++t) {
            done[t] = !full;
            int x0, y0, x1, y1;
            tile_rect(job, t, &x0, &y0, &x1, &y1);
            stats->tiles_done += !full;
            stats->pixels += full ? 0 : (long)(x1 - x0) * (y1 - y0);
        }
    }
}

/* Zeroes the film's accumulators in the claimed tiles that are not done,
 * where abandoned workers left some of their samples: the film then holds
 * the done tiles alone, as a film that never saw the others (every
 * accumulator +0, its sample count 0). */
static void clear_undone_tiles(render_job *job, const unsigned char *done)
{
    film_accumulators acc;
    film_get_accumulators(render_scene_film(job->rs), &acc);
    size_t w = (size_t)(job->bounds.x1 - job->bounds.x0);
    size_t npix = w * (size_t)(job->bounds.y1 - job->bounds.y0);
    int claimed = job->tile_source ? job->tile_count : atomic_load(&job->next_tile);
    for (int t = 0; t < claimed && t < job->tile_count; ++t) {
        if (done[t])
            continue;
        int x0, y0, x1, y1;
        tile_rect(job, t, &x0, &y0, &x1, &y1);
        size_t n = (size_t)(x1 - x0);
        for (int y = y0; y < y1; ++y) {
            size_t i = (size_t)y * w + (size_t)x0;
            for (int k = 0; k < FILM_DOUBLE_ARRAYS; ++k) {
                size_t per = acc.doubles[k] ? acc.double_count[k] / npix : 0;
                if (per)
                    memset(acc.doubles[k] + i * per, 0, n * per * sizeof(double));
            }
            if (acc.counts)
                memset(acc.counts + i, 0, n * sizeof *acc.counts);
        }
    }
}

/* A render stopped before its last tile: which tiles are done (a tile
 * whose worker was abandoned inside it is not), and, for a render that
 * began on an empty film (sample_begin 0), the others cleared. */
static hz_status keep_done_tiles(render_job *job, render_stats *stats)
{
    unsigned char *done = malloc(job->tile_count > 0 ? (size_t)job->tile_count : 1);
    if (!done)
        return HZ_ERROR;
    for (int t = 0; t < job->tile_count; ++t)
        done[t] = atomic_load_explicit(&job->tile_done[t], memory_order_acquire);
    describe_done_tiles(job, done, stats);
    /* A late worker may have finished a tile since the count was read. */
    stats->interrupted = stats->tiles_done < job->tile_count;
    if (atomic_load(&job->abandon) && job->sample_begin == 0)
        clear_undone_tiles(job, done);
    free(done);
    return HZ_OK;
}

/* The figures of the workers that finished (an abandoned one's are its
 * own until it ends). */
static void fill_stats(render_stats *stats, const render_job *job, int started, int threads,
                       double t0)
{
    int w = job->bounds.x1 - job->bounds.x0, h = job->bounds.y1 - job->bounds.y0;
    memset(stats, 0, sizeof *stats);
    stats->threads = started;
    stats->spp = job->sample_end - job->sample_begin;
    stats->passes = 1;
    stats->pixels_total = (long)w * h;
    stats->tile_count = job->tile_count;
    stats->tiles_done = atomic_load(&job->tiles_done);
    stats->interrupted = stats->tiles_done < job->tile_count;
    stats->pixels = stats->pixels_total;
    stats->wall_seconds = now_seconds() - t0;
    for (int i = 0; i < threads; ++i) {
        if (i >= started ||
            !atomic_load_explicit(&job->slots[i].finished, memory_order_acquire))
            continue;
        stats->camera_rays += job->counters[i].camera_rays;
        stats->shadow_rays += job->counters[i].shadow_rays;
        stats->density_lookups += job->counters[i].density_lookups;
        stats->majorant_steps += job->counters[i].majorant_steps;
        stats->lost_paths += job->counters[i].lost_paths;
        stats->time_busy_s += job->busy_ns[i] * 1e-9;
        stats->samples += (double)job->rendered[i] * stats->spp;
        stats->time_media_s += job->counters[i].media_ns * 1e-9;
        stats->time_film_s += job->counters[i].film_ns * 1e-9;
    }
}

hz_status renderer_run(render_scene *rs, const renderer_options *opt, render_stats *stats,
                       hz_error *err)
{
    if (stats)
        memset(stats, 0, sizeof *stats); /* stats.abandoned 0 on every early return */
    /* On the heap: abandoned workers keep reading it after this returns. */
    render_job *job = calloc(1, sizeof *job);
    if (!job)
        return hz_fail(err, "out of memory starting the render");
    job_init(job, rs, opt);
    int threads = worker_count(opt->threads, job->tile_count);
    pthread_t *tids = NULL;
    worker_arg *args = NULL;
    if (job_alloc_workers(job, threads, opt->timing, &tids, &args) != HZ_OK) {
        job_free(job, tids, args);
        return hz_fail(err, "out of memory starting %d render threads", threads);
    }
    double t0 = now_seconds();
    int started = start_workers(job, tids, args, threads);
    hz_status status = HZ_OK;
    progress_bar bar;
    if (started == 0)
        status = hz_fail(err, "could not start any render thread");
    else if (wait_for_workers(job, opt, &bar, t0))
        abandon_slow_workers(job, started);
    int abandoned = end_workers(job, tids, started);
    if (started > 0)
        progress_end(&bar, opt->tiles_shown ? opt->tiles_shown(opt->tile_ctx)
                                            : atomic_load(&job->tiles_done),
                     now_seconds());
    render_stats local;
    render_stats *st = stats ? stats : &local;
    fill_stats(st, job, started, threads, t0);
    st->abandoned = abandoned;
    if (status == HZ_OK && st->interrupted && keep_done_tiles(job, st) != HZ_OK)
        status = hz_fail(err, "out of memory listing the rendered tiles");
    if (abandoned == 0)
        job_free(job, tids, args);
    return status;
}
