/* The error estimate and sample allocation of --target-error
 * (progressive_error in progressive.h). */
#include <assert.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/big_alloc.h"
#include "core/parallel.h"
#include "render/progressive.h"

enum { T = RENDERER_TILE_SIZE };

hz_status progressive_error_init(progressive_error *pe, const film *f, hz_error *err)
{
    assert(film_keeps_statistics(f));
    const film_params *fp = film_get_params(f);
    memset(pe, 0, sizeof *pe);
    pe->x0 = fp->bounds.x0;
    pe->y0 = fp->bounds.y0;
    pe->w = fp->bounds.x1 - fp->bounds.x0;
    pe->h = fp->bounds.y1 - fp->bounds.y0;
    pe->tiles_x = (pe->w + T - 1) / T;
    pe->tile_count = pe->tiles_x * ((pe->h + T - 1) / T);
    size_t n = (size_t)pe->w * pe->h;
    pe->e = hz_big_malloc((n ? n : 1) * sizeof *pe->e);
    pe->halves = hz_big_calloc(n ? n : 1, sizeof *pe->halves);
    pe->tile_sums = calloc((size_t)(pe->tile_count ? 3 * pe->tile_count : 1), sizeof(double));
    pe->tile_own = calloc((size_t)(pe->tile_count ? 3 * pe->tile_count : 1), sizeof(double));
    if (!pe->e || !pe->halves || !pe->tile_sums || !pe->tile_own) {
        progressive_error_free(pe);
        return hz_fail(err, "out of memory for the error estimate (--target-error)");
    }
    return HZ_OK;
}

void progressive_error_free(progressive_error *pe)
{
    free(pe->e);
    free(pe->halves);
    free(pe->tile_sums);
    free(pe->tile_own);
    memset(pe, 0, sizeof *pe);
}

/* The squared denominators of a pixel's relative error, (m_lo + 0.01)^2 per
 * channel, with m_lo = max(0, |m| - k sqrt(var_m)): the denominator of
 * relMSE is the converged value, and a pixel's own mean is high exactly when
 * a rare bright sample also raised its variance. */
static void error_denominators(rgb m, rgb var_m, double d2[3])
{
    double mm[3] = {m.r, m.g, m.b}, vm[3] = {var_m.r, var_m.g, var_m.b};
    for (int c = 0; c < 3; ++c) {
        double lo = fabs(mm[c]) - PROGRESSIVE_LOWER_BOUND_K * sqrt(vm[c]);
        double d = (lo > 0.0 ? lo : 0.0) + 0.01;
        d2[c] = d * d;
    }
}

/* Var / (m_lo + 0.01)^2, channel mean. */
static double relative_error(rgb var, const double d2[3])
{
    return (var.r / d2[0] + var.g / d2[1] + var.b / d2[2]) / 3.0;
}

typedef struct {
    progressive_error *pe;
    const film *f;
    const film_snapshot *before;
    const unsigned char *active;
    double half_scale, imaging_ratio;
    atomic_int next; /* the next tile to measure */
} measure_job;

/* The variance over the 3x3 neighbourhood (within the tile) of the pixel
 * means around (x, y), per channel: the pixel filter reaches into the
 * neighbours, so a pixel's samples vary at least as much as their means do.
 * A floor under a pixel's own variance per sample: a few samples that agree
 * (all missing a partly covering edge, or a quantised path contribution) show
 * none (docs/performance.md). */
static rgb spread_of_means(const rgb *means, int x, int y, int tw, int th)
{
    rgb sum = rgb_grey(0.0), sq = rgb_grey(0.0);
    int k = 0;
    for (int yy = y - 1; yy <= y + 1; ++yy)
        for (int xx = x - 1; xx <= x + 1; ++xx)
            if (yy >= 0 && yy < th && xx >= 0 && xx < tw) {
                rgb m = means[yy * T + xx];
                sum = rgb_add(sum, m);
                sq = rgb_add(sq, rgb_mul(m, m));
                ++k;
            }
    rgb mean = rgb_scale(sum, 1.0 / k), v = rgb_sub(rgb_scale(sq, 1.0 / k), rgb_mul(mean, mean));
    return rgb_make(fmax(v.r, 0.0), fmax(v.g, 0.0), fmax(v.b, 0.0));
}

/* Whether the last pass rendered some pixel of the tile at (tx, ty). */
static bool tile_rendered(const progressive_error *pe, const unsigned char *active, int tx,
                          int ty, int tw, int th)
{
    for (int y = 0; y < th; ++y) {
        const unsigned char *row = active + (size_t)(ty + y) * pe->w + tx;
        for (int x = 0; x < tw; ++x)
            if (row[x])
                return true;
    }
    return false;
}

/* One tile: its pixels' e_i and halves estimates, and its sums. A tile that
 * the last pass did not render keeps them: they depend on its own pixels
 * only, which have not changed. */
static void measure_tile(const measure_job *job, int t)
{
    progressive_error *pe = job->pe;
    const film *f = job->f;
    double ratio = job->imaging_ratio;
    int w = pe->w, h = pe->h;
    int tx = (t % pe->tiles_x) * T, ty = (t / pe->tiles_x) * T;
    int tw = w - tx < T ? w - tx : T, th = h - ty < T ? h - ty : T;
    if (!tile_rendered(pe, job->active, tx, ty, tw, th))
        return;
    double own[T * T];
    rgb means[T * T];
    long counts[T * T];
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x)
            means[y * T + x] = film_get_pixel(f, pe->x0 + tx + x, pe->y0 + ty + y, ratio);
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x) {
            int px = pe->x0 + tx + x, py = pe->y0 + ty + y;
            rgb m = means[y * T + x], film_var = film_get_variance(f, px, py, ratio), var = film_var;
            long n = counts[y * T + x] = film_get_sample_count(f, px, py);
            if (n > 0) {
                rgb floor = rgb_scale(spread_of_means(means, x, y, tw, th), 1.0 / (double)n);
                var = rgb_make(fmax(var.r, floor.r), fmax(var.g, floor.g), fmax(var.b, floor.b));
            }
            double d2[3];
            error_denominators(m, var, d2);
            own[y * T + x] = relative_error(var, d2);
            size_t i = (size_t)(ty + y) * w + tx + x;
            if (job->active[i]) { /* rendered in the last pass: a new halves estimate */
                /* After the first pass (two samples, no copy before it) the
                 * halves of the pixel are its two samples, and their squared
                 * change scaled as below is the film's own s^2 / n. */
                rgb sq = film_var;
                if (job->before) {
                    rgb d = rgb_sub(m, film_snapshot_pixel(job->before, f, px, py, ratio));
                    sq = rgb_mul(d, rgb_scale(d, job->half_scale));
                }
                pe->halves[i] = relative_error(sq, d2);
            }
        }
    double *sums = pe->tile_own + 3 * (size_t)t;
    sums[0] = sums[1] = sums[2] = 0.0;
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x) {
            double sum = 0.0;
            int k = 0;
            for (int yy = y - 1; yy <= y + 1; ++yy)
                for (int xx = x - 1; xx <= x + 1; ++xx)
                    if (yy >= 0 && yy < th && xx >= 0 && xx < tw) {
                        sum += own[yy * T + xx];
                        ++k;
                    }
            double self = own[y * T + x], e = sum / k > self ? sum / k : self;
            size_t i = (size_t)(ty + y) * w + tx + x;
            pe->e[i] = e;
            long samples = counts[y * T + x];
            if (samples > 0) {
                sums[0] += pe->halves[i];
                sums[1] += sqrt(e * (double)samples);
                sums[2] += 1.0;
            }
        }
}

static void *measure_worker(void *arg)
{
    measure_job *job = arg;
    for (int t; (t = atomic_fetch_add(&job->next, 1)) < job->pe->tile_count;)
        measure_tile(job, t);
    return NULL;
}

void progressive_error_measure(progressive_error *pe, const film *f, const film_snapshot *before,
                               const unsigned char *active, int n0, int n,
                               double imaging_ratio, int threads)
{
    /* Var of an n-sample mean from the difference D of the means of the
     * first n0 and the last k = n - n0 samples, D^2 n0 k / n^2, where the
     * film shows d = m_n - m_n0 = D k / n: d^2 n0 / k. */
    measure_job job = {.pe = pe, .f = f, .before = n0 > 0 ? before : NULL, .active = active,
                       .half_scale = (double)n0 / (double)(n - n0),
                       .imaging_ratio = imaging_ratio};
    atomic_init(&job.next, 0);
    pe->samples = n;
    /* Each tile's figures depend on its own pixels only: the same for any
     * thread count. */
    hz_parallel_run(threads, measure_worker, &job);
    /* tile_sums may be summed across ranks next: each rank's own sums stay
     * in tile_own. */
    memcpy(pe->tile_sums, pe->tile_own, 3 * (size_t)pe->tile_count * sizeof(double));
}

double progressive_noise_target(const progressive_goal *goal)
{
    double left = goal->target_error - goal->bias, least = 0.5 * goal->target_error;
    return left > least ? left : least; /* a NaN bias: the least */
}

long progressive_error_select(const progressive_error *pe, const film *f,
                              const progressive_goal *goal, unsigned char *active,
                              double *estimate)
{
    double target = progressive_noise_target(goal);
    double e_sum = 0.0, root_sum = 0.0, pixels = 0.0;
    for (int t = 0; t < pe->tile_count; ++t) { /* in tile order: the same sum on every rank */
        const double *sums = pe->tile_sums + 3 * (size_t)t;
        e_sum += sums[0];
        root_sum += sums[1];
        pixels += sums[2];
    }
    double image = pixels > 0.0 ? e_sum / pixels : 0.0;
    ((progressive_error *)pe)->estimate = image;
    if (estimate)
        *estimate = image;
    size_t n = (size_t)pe->w * pe->h;
    double stop = pe->samples >= PROGRESSIVE_TRUST_SPP ? PROGRESSIVE_SAFETY * target
                                                       : PROGRESSIVE_EARLY_SAFETY * target;
    if (!(image > stop)) {
        /* reached (a NaN estimate goes on) */
        memset(active, 0, n);
        return 0;
    }
    double scale = root_sum / pixels / target; /* n*_i = sqrt(r_i) * scale */
    double min_samples = ceil(PROGRESSIVE_MIN_SCALE / sqrt(goal->target_error));
    long left = 0;
    for (int y = 0; y < pe->h; ++y)
        for (int x = 0; x < pe->w; ++x) {
            size_t i = (size_t)y * pe->w + x;
            if (!active[i])
                continue;
            double samples = (double)film_get_sample_count(f, pe->x0 + x, pe->y0 + y);
            double want = sqrt(pe->e[i] * samples) * scale;
            /* Every pixel goes on to min_samples: one whose samples agree may
             * still miss an edge or a rare light path. */
            if (want < min_samples)
                want = min_samples;
            if (samples >= want)
                active[i] = 0;
            left += active[i] != 0;
        }
    return left;
}

int progressive_error_next_end(const progressive_error *pe, int done, int spp,
                               const progressive_goal *goal)
{
    double target = progressive_noise_target(goal);
    if (done <= 0)
        return progressive_first_end(goal, spp);
    if (pe->samples < PROGRESSIVE_TRUST_SPP || !(pe->estimate > 0.0))
        return progressive_pass_end(done, spp);
    /* The count where the estimate, falling as 1/n, reaches the target. */
    double want = ceil((double)done * pe->estimate / (PROGRESSIVE_SAFETY * target));
    double lo = done + (done / 4 > 1 ? done / 4 : 1), hi = 2.0 * done;
    double end = want < lo ? lo : want > hi ? hi : want;
    return end < spp ? (int)end : spp;
}
