#define _POSIX_C_SOURCE 200809L
#include "render/renderer.h"

#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
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
    atomic_int stop;
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
static void render_black_pixel(render_job *job, int px, int py, integrator_counters *counters)
{
    const sampler *smp = render_scene_sampler(job->rs);
    const filter *flt = render_scene_filter(job->rs);
    film *f = render_scene_film(job->rs);
    film_surface vs;
    vs.hit = false;
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
}

static void render_pixel(render_job *job, int px, int py, integrator_counters *counters)
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
        uint64_t t0 = counters->timed ? hz_clock_ns() : 0;
        film_add_sample(f, px, py, L, cs.filter_weight, depth);
        if (job->surfaces)
            film_add_surface(f, px, py, cs.filter_weight, &vs);
        if (counters->timed)
            counters->film_ns += hz_clock_ns() - t0;
    }
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

static void *worker_main(void *p)
{
    worker_arg *arg = p;
    render_job *job = arg->job;
    flush_denormals();
    /* Counted on this thread's stack, not in the shared array: neighbouring
     * threads' counters would share cache lines. */
    integrator_counters local = job->counters[arg->index];
    integrator_counters *counters = &local;
    uint64_t start = hz_clock_ns();
    long rendered = 0;
    for (;;) {
        if (atomic_load_explicit(&job->stop, memory_order_relaxed))
            break; /* claimed tiles stay a prefix: every one of them is finished */
        int t = job->tile_source ? job->tile_source(job->tile_ctx)
                               : atomic_fetch_add(&job->next_tile, 1);
        if (t < 0 || t >= job->tile_count)
            break;
        int x0 = job->bounds.x0 + (t % job->tiles_x) * TILE_SIZE;
        int y0 = job->bounds.y0 + (t / job->tiles_x) * TILE_SIZE;
        int x1 = x0 + TILE_SIZE < job->bounds.x1 ? x0 + TILE_SIZE : job->bounds.x1;
        int y1 = y0 + TILE_SIZE < job->bounds.y1 ? y0 + TILE_SIZE : job->bounds.y1;
        int w = job->bounds.x1 - job->bounds.x0;
        bool black = tile_black(job, x0, y0, x1, y1);
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                if (!job->active ||
                    job->active[(size_t)(y - job->bounds.y0) * w + (x - job->bounds.x0)]) {
                    if (black)
                        render_black_pixel(job, x, y, counters);
                    else
                        render_pixel(job, x, y, counters);
                    ++rendered;
                }
        atomic_fetch_add(&job->tiles_done, 1);
    }
    job->busy_ns[arg->index] = hz_clock_ns() - start;
    job->rendered[arg->index] = rendered;
    job->counters[arg->index] = local;
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

/* Each thread's counters, and the threads' ids and arguments. */
static hz_status job_alloc_workers(render_job *job, int threads, bool timed, pthread_t **tids,
                                   worker_arg **args)
{
    job->counters = calloc((size_t)threads, sizeof *job->counters);
    job->busy_ns = calloc((size_t)threads, sizeof *job->busy_ns);
    job->rendered = calloc((size_t)threads, sizeof *job->rendered);
    *tids = calloc((size_t)threads, sizeof **tids);
    *args = calloc((size_t)threads, sizeof **args);
    if (!job->counters || !job->busy_ns || !job->rendered || !*tids || !*args)
        return HZ_ERROR;
    for (int i = 0; i < threads; ++i)
        job->counters[i].timed = timed;
    return HZ_OK;
}

static void job_free(render_job *job, pthread_t *tids, worker_arg *args)
{
    free(job->counters);
    free(job->busy_ns);
    free(job->rendered);
    free(tids);
    free(args);
    pthread_cond_destroy(&job->wake);
    pthread_mutex_destroy(&job->lock);
}

/* Returns how many of `threads` workers started. */
static int start_workers(render_job *job, pthread_t *tids, worker_arg *args, int threads)
{
    /* Workers inherit a mask without SIGINT/SIGTERM: a handler then runs on
     * this thread, whose nap it interrupts. */
    sigset_t block, old;
    sigemptyset(&block);
    sigaddset(&block, SIGINT);
    sigaddset(&block, SIGTERM);
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
 * cancel or at the deadline. */
static void wait_for_workers(render_job *job, const renderer_options *opt, progress_bar *bar,
                             double t0)
{
    progress_begin(bar, opt->progress, job->tile_count, t0);
    pthread_mutex_lock(&job->lock);
    while (atomic_load(&job->running) > 0) {
        double now = now_seconds();
        if ((job->cancel && *job->cancel) || (opt->deadline > 0 && now >= opt->deadline)) {
            atomic_store(&job->stop, 1);
            break;
        }
        progress_update(bar, opt->tiles_shown ? opt->tiles_shown(opt->tile_ctx)
                                              : atomic_load(&job->tiles_done),
                        now);
        /* Up to 100 ms or to the deadline; the last worker's signal, or a
         * cancel noticed then (workers stop claiming tiles on their own),
         * ends it. */
        double nap = 0.1;
        if (opt->deadline > 0 && opt->deadline - now < nap)
            nap = opt->deadline - now;
        struct timespec until = monotonic_after(nap);
        pthread_cond_timedwait(&job->wake, &job->lock, &until);
    }
    pthread_mutex_unlock(&job->lock);
}

/* The pixels of the first `done` tiles (row-major over a w x h image). */
static long tiles_pixels(const render_job *job, int done, int w, int h)
{
    long pixels = 0;
    for (int t = 0; t < done; ++t) {
        int x0 = (t % job->tiles_x) * TILE_SIZE, y0 = (t / job->tiles_x) * TILE_SIZE;
        pixels += (long)(w - x0 < TILE_SIZE ? w - x0 : TILE_SIZE) *
                  (h - y0 < TILE_SIZE ? h - y0 : TILE_SIZE);
    }
    return pixels;
}

static void fill_stats(render_stats *stats, const render_job *job, int started, int threads,
                       int done, double t0)
{
    int w = job->bounds.x1 - job->bounds.x0, h = job->bounds.y1 - job->bounds.y0;
    memset(stats, 0, sizeof *stats);
    stats->threads = started;
    stats->spp = job->sample_end - job->sample_begin;
    stats->passes = 1;
    stats->pixels_total = (long)w * h;
    stats->tile_count = job->tile_count;
    stats->tiles_done = done;
    stats->interrupted = done < job->tile_count;
    stats->pixels = tiles_pixels(job, done, w, h);
    stats->wall_seconds = now_seconds() - t0;
    for (int i = 0; i < threads; ++i) {
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
    render_job job;
    job_init(&job, rs, opt);
    int threads = worker_count(opt->threads, job.tile_count);
    pthread_t *tids = NULL;
    worker_arg *args = NULL;
    if (job_alloc_workers(&job, threads, opt->timing, &tids, &args) != HZ_OK) {
        job_free(&job, tids, args);
        return hz_fail(err, "out of memory starting %d render threads", threads);
    }
    double t0 = now_seconds();
    int started = start_workers(&job, tids, args, threads);
    hz_status status = HZ_OK;
    progress_bar bar;
    if (started == 0)
        status = hz_fail(err, "could not start any render thread");
    else
        wait_for_workers(&job, opt, &bar, t0);
    for (int i = 0; i < started; ++i)
        pthread_join(tids[i], NULL);
    int done = atomic_load(&job.tiles_done);
    if (started > 0)
        progress_end(&bar, opt->tiles_shown ? opt->tiles_shown(opt->tile_ctx) : done,
                     now_seconds());
    if (stats)
        fill_stats(stats, &job, started, threads, done, t0);
    job_free(&job, tids, args);
    return status;
}
