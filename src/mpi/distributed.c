/* One image across MPI ranks: launch detection, agreement, render and gather
 * (the tile hand-out is in tile_service.c). MPI itself is called through the
 * MPI module (mpi_module.h), loaded only when mpirun launched this process;
 * a build without MPI (HAZE_HAVE_MPI undefined) has no module to load. */
#define _POSIX_C_SOURCE 200809L
#include "mpi/distributed.h"

#include "core/hash.h"
#include "core/module.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "mpi/mpi_module.h"
#include "mpi/tile_service.h"
#include "render/progressive.h"
#include "render/progressive_error.h"

/* Set by the build: the module's file name and its absolute path in the build tree. */
#ifndef HAZE_MPI_MODULE_NAME
#define HAZE_MPI_MODULE_NAME "libhaze_mpi.so"
#endif
#ifndef HAZE_MPI_MODULE_BUILD_PATH
#define HAZE_MPI_MODULE_BUILD_PATH ""
#endif

/* Per-rank figures gathered on rank 0 after a render (as doubles). */
enum {
    FIG_TILES,
    FIG_THREADS,
    FIG_CLAIMS,
    FIG_LATE,
    FIG_CLAIM_SECONDS,
    FIG_MAX_WAIT,
    FIG_RENDER_SECONDS,
    FIG_COUNT
};

struct distributed {
    int rank, size;
    const haze_mpi_api *mpi; /* MPI_Init_thread succeeded: MPI_Finalize at the end */
    char host[256];
    /* Rank 0 after distributed_render: FIG_COUNT figures per rank. */
    double *figures;
    double wait_seconds, gather_seconds, service_cpu_seconds;
};

bool distributed_launched(void)
{
    return getenv("OMPI_COMM_WORLD_SIZE") != NULL || getenv("PMIX_RANK") != NULL;
}

hz_status distributed_create(distributed **out, hz_error *err)
{
    *out = NULL;
    distributed *d = calloc(1, sizeof *d);
    if (!d)
        return hz_fail(err, "out of memory");
    d->size = 1;
    if (gethostname(d->host, sizeof d->host - 1) != 0)
        snprintf(d->host, sizeof d->host, "?");
    if (distributed_launched()) {
#ifdef HAZE_HAVE_MPI
        static const hz_module_spec spec = {
            "HAZE_MPI_MODULE", HAZE_MPI_MODULE_NAME, HAZE_MPI_MODULE_BUILD_PATH,
            HAZE_MPI_ENTRY,    HAZE_MPI_ABI,         sizeof(haze_mpi_api),
            "MPI"};
        char path[HZ_MODULE_PATH_MAX], reasons[2 * HZ_MODULE_PATH_MAX + 8];
        int tried = 0;
        const haze_mpi_api *api =
            hz_module_open(&spec, path, sizeof path, reasons, sizeof reasons, &tried);
        if (!api) {
            free(d);
            return hz_fail(err, "launched by mpirun, but cannot load the MPI module (tried %s); "
                                "set HAZE_MPI_MODULE to the module's path",
                           tried ? reasons : "no path");
        }
        int provided = 0, serialized = 0;
        char name[256];
        if (api->init(&d->rank, &d->size, name, (int)sizeof name, &provided, &serialized) != 0) {
            free(d);
            return hz_fail(err, "MPI_Init_thread failed");
        }
        d->mpi = api;
        if (name[0])
            snprintf(d->host, sizeof d->host, "%s", name);
        if (!serialized) {
            distributed_destroy(d);
            return hz_fail(err, "the MPI library offers thread level %d; haze needs "
                                "MPI_THREAD_SERIALIZED",
                           provided);
        }
#else
        const char *n = getenv("OMPI_COMM_WORLD_SIZE");
        if (n && atoi(n) > 1) {
            free(d);
            return hz_fail(err, "launched by mpirun with %s ranks, but this haze was built "
                                "without MPI (HAZE_MPI=OFF): every rank would render the "
                                "whole image",
                           n);
        }
#endif
    }
    *out = d;
    return HZ_OK;
}

void distributed_destroy(distributed *d)
{
    if (!d)
        return;
    if (d->mpi)
        d->mpi->finalize();
    free(d->figures);
    free(d);
}

int distributed_rank(const distributed *d) { return d->rank; }
int distributed_size(const distributed *d) { return d->size; }

uint64_t distributed_fingerprint(uint64_t inputs_hash, const render_scene *rs)
{
    uint64_t h = inputs_hash;
    /* Not the file name: only rank 0 writes. */
    const film_params *fp = film_get_params(render_scene_film((render_scene *)rs));
    HASH_FIELD(h, fp->xres);
    HASH_FIELD(h, fp->yres);
    HASH_FIELD(h, fp->bounds.x0);
    HASH_FIELD(h, fp->bounds.y0);
    HASH_FIELD(h, fp->bounds.x1);
    HASH_FIELD(h, fp->bounds.y1);
    HASH_FIELD(h, fp->savefp16);
    HASH_FIELD(h, fp->write_z);
    HASH_FIELD(h, fp->write_variance);
    HASH_FIELD(h, fp->gbuffer);
    HASH_FIELD(h, fp->gbuffer_world);
    HASH_FIELD(h, fp->write_sample_count);
    HASH_FIELD(h, fp->iso);
    HASH_FIELD(h, fp->max_component_value);
    HASH_FIELD(h, fp->diagonal);
    return sampler_fingerprint(h, render_scene_sampler(rs));
}

/* What each rank tells rank 0 at an agreement point. */
typedef struct {
    int32_t status;
    int32_t check_fingerprint;
    uint64_t fingerprint;
    char host[256];
    char message[sizeof(((hz_error *)0)->message)];
} verdict;

static const char mismatch_text[] =
    "parsed a different scene or options than rank 0 (the scene file's bytes, the film, the "
    "sampler, spp or seed differ)";

/* Gathers every rank's verdict on rank 0, which calls `on_failure` for each
 * failing rank (in rank order); returns the common outcome on every rank. */
static hz_status agree_all(distributed *d, hz_status local, const char *message,
                           uint64_t fingerprint, bool check_fingerprint,
                           void (*on_failure)(void *ctx, int rank, const verdict *v,
                                              const char *why),
                           void *ctx)
{
    verdict mine;
    memset(&mine, 0, sizeof mine);
    mine.status = local == HZ_OK ? 0 : 1;
    mine.check_fingerprint = check_fingerprint;
    mine.fingerprint = fingerprint;
    snprintf(mine.host, sizeof mine.host, "%s", d->host);
    if (local != HZ_OK)
        snprintf(mine.message, sizeof mine.message, "%s", message ? message : "failed");
    verdict *all = NULL;
    int ok = 1;
    if (d->rank == 0) {
        all = malloc((size_t)d->size * sizeof *all);
        if (!all)
            d->mpi->abort(1);
    }
    d->mpi->gather(&mine, (int)sizeof mine, HAZE_MPI_BYTE, all, 0);
    if (d->rank == 0) {
        for (int r = 0; r < d->size; ++r) {
            const char *why = NULL;
            if (all[r].status != 0)
                why = all[r].message;
            else if (check_fingerprint && all[0].status == 0 &&
                     all[r].fingerprint != all[0].fingerprint)
                why = mismatch_text;
            if (why) {
                ok = 0;
                on_failure(ctx, r, &all[r], why);
            }
        }
        free(all);
    }
    d->mpi->bcast(&ok, 1, HAZE_MPI_INT, 0);
    return ok ? HZ_OK : HZ_ERROR;
}

static void report_line(void *ctx, int rank, const verdict *v, const char *why)
{
    fprintf((FILE *)ctx, "haze: rank %d on host %s: %s\n", rank, v->host, why);
}

/* The first failure goes into the caller's hz_error, later ones to stderr. */
static void keep_first(void *ctx, int rank, const verdict *v, const char *why)
{
    hz_error *err = ctx;
    if (err->message[0] == '\0')
        hz_fail(err, "rank %d on host %s: %s", rank, v->host, why);
    else
        fprintf(stderr, "haze: rank %d on host %s: %s\n", rank, v->host, why);
}

hz_status distributed_agree(distributed *d, hz_status local, const hz_error *local_err,
                            uint64_t fingerprint, FILE *report)
{
    if (d->size == 1) {
        if (local != HZ_OK)
            hz_error_print(report, local_err);
        return local;
    }
    return agree_all(d, local, local_err->message, fingerprint, true, report_line, report);
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Element-wise sum onto rank 0, in chunks that fit MPI's int counts. */
static void reduce_sum(const haze_mpi_api *mpi, void *buf, size_t count, haze_mpi_type type,
                       size_t elem_size)
{
    const size_t chunk = (size_t)1 << 24;
    for (size_t off = 0; off < count; off += chunk) {
        int n = (int)(count - off < chunk ? count - off : chunk);
        mpi->reduce((char *)buf + off * elem_size, n, type, HAZE_MPI_SUM, 0);
    }
}

/* Element-wise sum on every rank, in chunks that fit MPI's int counts. */
static void reduce_all_chunked(const haze_mpi_api *mpi, double *buf, size_t count)
{
    const size_t chunk = (size_t)1 << 24;
    for (size_t off = 0; off < count; off += chunk) {
        int n = (int)(count - off < chunk ? count - off : chunk);
        mpi->allreduce(buf + off, n, HAZE_MPI_DOUBLE, HAZE_MPI_SUM);
    }
}

static int tile_count_of(const film_params *fp)
{
    int w = fp->bounds.x1 - fp->bounds.x0, h = fp->bounds.y1 - fp->bounds.y0;
    return ((w + RENDERER_TILE_SIZE - 1) / RENDERER_TILE_SIZE) *
           ((h + RENDERER_TILE_SIZE - 1) / RENDERER_TILE_SIZE);
}

/* The tiles one rank rendered in the first pass of a progressive render,
 * recorded as its threads claim them, and handed out again in each later
 * pass (so a pixel's samples all land on one rank's film, in order). */
typedef struct {
    tile_service *ts;
    int *tiles;
    atomic_int count, next;
} tile_log;

static int tile_log_claim(void *p)
{
    tile_log *l = p;
    int t = tile_service_next(l->ts);
    if (t >= 0)
        l->tiles[atomic_fetch_add(&l->count, 1)] = t;
    return t;
}

static int tile_log_replay(void *p)
{
    tile_log *l = p;
    int i = atomic_fetch_add(&l->next, 1);
    return i < atomic_load(&l->count) ? l->tiles[i] : -1;
}

/* progressive_error_measure of this rank's tiles after a pass from n0 to n
 * samples (the others' sum to 0); the sums of every tile then reach every
 * rank, which selects its own pixels. Returns the pixels left active. */
static long measure_ranks(const haze_mpi_api *mpi, progressive_error *pe, const film *f,
                          const film_snapshot *before, unsigned char *active, int n0, int n,
                          double ratio, int threads, const progressive_goal *goal)
{
    progressive_error_measure(pe, f, before, active, n0, n, ratio, threads);
    reduce_all_chunked(mpi, pe->tile_sums, PROGRESSIVE_TILE_SUMS * (size_t)pe->tile_count);
    return progressive_error_select(pe, f, goal, active, NULL);
}

/* The passes after the first of a progressive render across ranks: a pass
 * starts when every rank expects to finish it by the deadline and some rank
 * has pixels above the target error. */
static hz_status later_passes(const haze_mpi_api *mpi, render_scene *rs,
                              const renderer_options *o, tile_log *log,
                              const progressive_goal *goal, double first_seconds,
                              render_stats *mine, hz_error *err)
{
    film *f = render_scene_film(rs);
    const film_params *fp = film_get_params(f);
    double ratio = camera_imaging_ratio(render_scene_camera(rs), fp);
    int spp = render_scene_sampler(rs)->spp;
    double deadline = goal->deadline > 0 ? goal->deadline : INFINITY;
    size_t npix = (size_t)(fp->bounds.x1 - fp->bounds.x0) * (fp->bounds.y1 - fp->bounds.y0);
    unsigned char *active = NULL;
    progressive_error pe = {0};
    film_snapshot *snap = NULL; /* the film before the last pass */
    long left = (long)npix;
    if (goal->target_error > 0) {
        if (progressive_error_init(&pe, f, err) != HZ_OK)
            return HZ_ERROR;
        if (!(active = malloc(npix ? npix : 1)) || !(snap = film_snapshot_alloc(f, err))) {
            free(active);
            progressive_error_free(&pe);
            return hz_fail(err, "out of memory for the pixel mask (--target-error)");
        }
        memset(active, 1, npix);
    }
    int done = mine->spp;
    double last_seconds = first_seconds, last_work = (double)done * (double)npix;
    renderer_options po = *o;
    po.next_tile = tile_log_replay;
    po.tiles_shown = NULL;
    po.tile_ctx = log;
    po.progress = NULL;
    po.active = active;
    hz_status st = HZ_OK;
    if (active)
        mine->estimate = -1.0; /* until the first measure */
    if (active && done >= PROGRESSIVE_MIN_SPP) { /* the first pass took every pixel to `done` */
        left = measure_ranks(mpi, &pe, f, NULL, active, 0, done, ratio, po.threads, goal);
        mine->estimate = pe.estimate;
    }
    while (done < spp) {
        int end = active ? progressive_error_next_end(&pe, done, spp, goal)
                         : progressive_pass_end(done, spp);
        double work = (double)(end - done) * (double)left;
        /* {every rank fits, every rank is done}: go on when all fit and not all are done */
        int flags[2] = {progressive_pass_fits(now_seconds(), deadline, last_seconds, last_work,
                                              work),
                        left == 0};
        mpi->allreduce(flags, 2, HAZE_MPI_INT, HAZE_MPI_MIN);
        if (!flags[0] || flags[1])
            break;
        double start = now_seconds();
        if (snap)
            film_snapshot_save_pixels(snap, f, active);
        atomic_store(&log->next, 0);
        po.sample_begin = done;
        po.sample_end = end;
        render_stats pass;
        if ((st = renderer_run(rs, &po, &pass, err)) != HZ_OK)
            break;
        render_stats_add_work(mine, &pass);
        mine->samples += pass.samples;
        last_seconds = now_seconds() - start;
        last_work = work > 0.0 ? work : 1.0;
        done = end;
        mine->spp = done;
        mine->passes++;
        if (active && done >= PROGRESSIVE_MIN_SPP) {
            left = measure_ranks(mpi, &pe, f, snap, active, po.sample_begin, done, ratio,
                                 po.threads, goal);
            mine->estimate = pe.estimate; /* the same on every rank */
        }
        if (o->progress)
            fprintf(o->progress, "pass %d: %d of %d spp\n", mine->passes, done, spp);
    }
    free(active);
    progressive_error_free(&pe);
    film_snapshot_destroy(snap);
    return st;
}

/* This render's tile service. Without it (rank 0) or its requests (others)
 * the run cannot go on, nor can the ranks agree on it: the job ends. */
static tile_service *start_tile_service(distributed *d, const film_params *fp, hz_error *local)
{
    tile_service *ts = NULL;
    if (tile_service_create(d->mpi, d->rank, d->size, tile_count_of(fp), &ts, local) != HZ_OK) {
        fprintf(stderr, "haze: rank %d on host %s: %s\n", d->rank, d->host, local->message);
        d->mpi->abort(1);
    }
    return ts;
}

/* The first pass's options: tiles from the service (a progressive render's
 * first pass, progressive_first_end, with its tiles recorded in `log`),
 * progress on rank 0 only, no cancel (under mpirun a signal ends the job). */
static void first_pass_options(const distributed *d, render_scene *rs,
                               const renderer_options *opt, const progressive_goal *goal,
                               tile_log *log, renderer_options *o)
{
    *o = *opt;
    o->cancel = NULL;
    o->next_tile = tile_service_next;
    o->tiles_shown = d->rank == 0 ? tile_service_shown : NULL;
    o->tile_ctx = log->ts;
    if (d->rank != 0)
        o->progress = NULL;
    if (goal) {
        const film_params *fp = film_get_params(render_scene_film(rs));
        log->tiles = malloc((size_t)tile_count_of(fp) * sizeof *log->tiles);
        if (!log->tiles) {
            fprintf(stderr, "haze: rank %d on host %s: out of memory\n", d->rank, d->host);
            d->mpi->abort(1);
        }
        o->next_tile = tile_log_claim;
        o->tile_ctx = log;
        o->sample_end = progressive_first_end(goal, render_scene_sampler(rs)->spp);
    }
}

/* Ends the tile hand-out (rank 0: once every rank is done). Tiles handed to
 * this rank but not rendered fail it. */
static hz_status finish_tile_service(distributed *d, tile_service *ts, hz_status st,
                                     tile_claim_stats *claims, hz_error *local)
{
    int lost = tile_service_finish(ts);
    if (lost > 0 && st == HZ_OK)
        st = hz_fail(local, "%d tile%s handed to this rank were not rendered", lost,
                     lost == 1 ? "" : "s");
    *claims = tile_service_claims(ts);
    d->service_cpu_seconds = claims->service_cpu_seconds;
    tile_service_destroy(ts);
    return st;
}

/* A progressive render's passes after the first, once every rank agrees the
 * first went well (`st` is this rank's first pass). */
static hz_status progressive_passes(distributed *d, render_scene *rs, const renderer_options *o,
                                    tile_log *log, const progressive_goal *goal,
                                    double first_seconds, hz_status st, render_stats *mine,
                                    hz_error *local)
{
    int ok = st == HZ_OK;
    d->mpi->allreduce(&ok, 1, HAZE_MPI_INT, HAZE_MPI_MIN);
    if (ok && o->progress)
        fprintf(o->progress, "pass 1: %d of %d spp\n", mine->spp, render_scene_sampler(rs)->spp);
    if (ok && later_passes(d->mpi, rs, o, log, goal, first_seconds, mine, local) != HZ_OK)
        st = HZ_ERROR; /* renderer_run fails only before any thread starts */
    free(log->tiles);
    return st;
}

/* Every rank's film summed onto rank 0's. */
static void reduce_film(const haze_mpi_api *mpi, film *f)
{
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    for (int i = 0; i < FILM_DOUBLE_ARRAYS; ++i)
        if (acc.doubles[i])
            reduce_sum(mpi, acc.doubles[i], acc.double_count[i], HAZE_MPI_DOUBLE,
                       sizeof(double));
    if (acc.counts)
        reduce_sum(mpi, acc.counts, acc.count_count, HAZE_MPI_UINT32, sizeof(uint32_t));
}

/* This rank's figures for distributed_print_report, gathered on rank 0. */
static void gather_figures(distributed *d, const render_stats *mine,
                           const tile_claim_stats *claims, double render_seconds)
{
    double fig[FIG_COUNT] = {0};
    fig[FIG_TILES] = mine->tiles_done;
    fig[FIG_THREADS] = mine->threads;
    fig[FIG_CLAIMS] = (double)claims->claims;
    fig[FIG_LATE] = (double)claims->late;
    fig[FIG_CLAIM_SECONDS] = claims->wait_seconds;
    fig[FIG_MAX_WAIT] = claims->max_wait;
    fig[FIG_RENDER_SECONDS] = render_seconds;
    free(d->figures);
    d->figures = NULL;
    if (d->rank == 0) {
        d->figures = calloc((size_t)d->size * FIG_COUNT, sizeof *d->figures);
        if (!d->figures)
            d->mpi->abort(1);
    }
    d->mpi->gather(fig, FIG_COUNT, HAZE_MPI_DOUBLE, d->figures, 0);
}

/* Rank 0's stats of the whole image: the ranks' counts (`sums`, reduce_ranks'
 * order) and times summed, their threads added, every tile rendered. */
static void whole_image_stats(const distributed *d, film *f, const uint64_t sums[6],
                              const double times[4], long own_nonfinite, double t0,
                              render_stats *stats)
{
    film_add_nonfinite(f, (long)sums[3] - own_nonfinite);
    stats->camera_rays = sums[0];
    stats->shadow_rays = sums[1];
    stats->density_lookups = sums[2];
    stats->majorant_steps = sums[4];
    stats->lost_paths = sums[5];
    stats->time_busy_s = times[0];
    stats->time_media_s = times[1];
    stats->time_film_s = times[2];
    stats->samples = times[3];
    stats->threads = 0;
    for (int r = 0; r < d->size; ++r)
        stats->threads += (int)d->figures[r * FIG_COUNT + FIG_THREADS];
    stats->tiles_done = stats->tile_count;
    stats->pixels = stats->pixels_total;
    /* spp and passes: every rank took the same (the decisions are collective) */
    stats->interrupted = false;
    stats->wall_seconds = now_seconds() - t0;
}

/* Sums the film, counts and times of every rank onto rank 0 and gathers the
 * ranks' figures there; `stats` are then this rank's own, or on rank 0 the
 * whole image's. */
static void reduce_ranks(distributed *d, film *f, const render_stats *mine,
                         const tile_claim_stats *claims, double render_seconds, double t0,
                         render_stats *stats)
{
    double t_gather = now_seconds();
    reduce_film(d->mpi, f);
    long own_nonfinite = film_nonfinite_count(f);
    uint64_t sums[6] = {mine->camera_rays, mine->shadow_rays, mine->density_lookups,
                        (uint64_t)own_nonfinite, mine->majorant_steps, mine->lost_paths};
    reduce_sum(d->mpi, sums, 6, HAZE_MPI_UINT64, sizeof(uint64_t));
    double times[4] = {mine->time_busy_s, mine->time_media_s, mine->time_film_s, mine->samples};
    reduce_sum(d->mpi, times, 4, HAZE_MPI_DOUBLE, sizeof(double));
    gather_figures(d, mine, claims, render_seconds);
    d->gather_seconds = now_seconds() - t_gather;
    *stats = *mine;
    if (d->rank == 0)
        whole_image_stats(d, f, sums, times, own_nonfinite, t0, stats);
}

static hz_status render_mpi(distributed *d, render_scene *rs, const renderer_options *opt,
                            const progressive_goal *goal, render_stats *stats, hz_error *err)
{
    double t0 = now_seconds();
    film *f = render_scene_film(rs);
    hz_error local = {0};
    tile_log log = {.ts = start_tile_service(d, film_get_params(f), &local)};
    atomic_init(&log.count, 0);
    atomic_init(&log.next, 0);
    renderer_options o;
    first_pass_options(d, rs, opt, goal, &log, &o);
    render_stats mine;
    memset(&mine, 0, sizeof mine);
    hz_status st = renderer_run(rs, &o, &mine, &local);
    double render_seconds = now_seconds() - t0;
    double t_wait = now_seconds();
    tile_claim_stats claims;
    st = finish_tile_service(d, log.ts, st, &claims, &local);
    if (goal) {
        st = progressive_passes(d, rs, &o, &log, goal, render_seconds, st, &mine, &local);
        render_seconds = now_seconds() - t0;
        t_wait = now_seconds();
    }

    err->message[0] = '\0';
    st = agree_all(d, st, local.message, 0, false, keep_first, err);
    d->wait_seconds = now_seconds() - t_wait;
    if (st != HZ_OK) {
        if (d->rank != 0)
            hz_fail(err, "%s", local.message[0] ? local.message : "another rank failed");
        return HZ_ERROR;
    }
    reduce_ranks(d, f, &mine, &claims, render_seconds, t0, stats);
    return HZ_OK;
}

hz_status distributed_render(distributed *d, render_scene *rs, const renderer_options *opt,
                             const progressive_goal *goal, render_stats *stats, hz_error *err)
{
    if (d->size > 1)
        return render_mpi(d, rs, opt, goal, stats, err);
    if (goal)
        return renderer_run_progressive(rs, opt, goal, stats, err);
    return renderer_run(rs, opt, stats, err);
}

void distributed_print_report(const distributed *d, FILE *out)
{
    if (d->size == 1 || d->rank != 0 || !d->figures)
        return;
    char tiles[512];
    size_t len = 0;
    long claims = 0, late = 0;
    double waited = 0.0, max_wait = 0.0;
    for (int r = 0; r < d->size && len < sizeof tiles; ++r) {
        const double *fg = d->figures + (size_t)r * FIG_COUNT;
        len += (size_t)snprintf(tiles + len, sizeof tiles - len, "%s%.0f", r ? " + " : "",
                                fg[FIG_TILES]);
        if (r > 0) {
            claims += (long)fg[FIG_CLAIMS];
            late += (long)fg[FIG_LATE];
            waited += fg[FIG_CLAIM_SECONDS];
            max_wait = fg[FIG_MAX_WAIT] > max_wait ? fg[FIG_MAX_WAIT] : max_wait;
        }
    }
    fprintf(out,
            "%d ranks: tiles %s (rank 0 first); remote tile claims %ld, %ld late, mean wait "
            "%.1f us, max %.1f ms; service thread %.3f CPU s; rank 0 waited %.3f s for the "
            "other ranks, gather %.3f s\n",
            d->size, tiles, claims, late, claims > 0 ? waited / (double)claims * 1e6 : 0.0,
            max_wait * 1e3, d->service_cpu_seconds, d->wait_seconds, d->gather_seconds);
}
