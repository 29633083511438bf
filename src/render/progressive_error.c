/* The error estimate and sample allocation of --target-error
 * (progressive_error.h). */
#include <assert.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/big_alloc.h"
#include "core/parallel.h"
#include "render/progressive_error.h"
#include "render/renderer.h"

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
    pe->changes = hz_big_calloc(n ? 6 * n : 1, sizeof *pe->changes);
    size_t sums = pe->tile_count ? (size_t)PROGRESSIVE_TILE_SUMS * pe->tile_count : 1;
    pe->tile_sums = calloc(sums, sizeof(double));
    pe->tile_own = calloc(sums, sizeof(double));
    pe->convergence = 2.0;
    if (!pe->e || !pe->halves || !pe->changes || !pe->tile_sums || !pe->tile_own) {
        progressive_error_free(pe);
        return hz_fail(err, "out of memory for the error estimate (--target-error)");
    }
    return HZ_OK;
}

void progressive_error_free(progressive_error *pe)
{
    free(pe->e);
    free(pe->halves);
    free(pe->changes);
    free(pe->tile_sums);
    free(pe->tile_own);
    memset(pe, 0, sizeof *pe);
}

/* The squared denominators of a pixel's relative error, (m_lo + 0.01)^2 per
 * channel, with m_lo = max(0, |m| - k sqrt(var_m)): the denominator of
 * relMSE is the converged value, and a pixel's own mean is high exactly when
 * a rare bright sample also raised its variance. From
 * PROGRESSIVE_SINGLE_SAMPLE_SPP samples (n) on, a mean that is one sample's
 * (sd of the mean at least PROGRESSIVE_SINGLE_SAMPLE_SD of it: exactly 1
 * for one non-zero sample among zeros, 0.71 for two) has m_lo = 0: without
 * that sample its value could be anything below. */
static void error_denominators(rgb m, rgb var_m, long n, double d2[3])
{
    double mm[3] = {m.r, m.g, m.b}, vm[3] = {var_m.r, var_m.g, var_m.b};
    for (int c = 0; c < 3; ++c) {
        double sd = sqrt(vm[c]), lo = fabs(mm[c]) - PROGRESSIVE_LOWER_BOUND_K * sd;
        if (n >= PROGRESSIVE_SINGLE_SAMPLE_SPP && sd >= PROGRESSIVE_SINGLE_SAMPLE_SD * fabs(mm[c]))
            lo = 0.0;
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
 * none (docs/progressive.md). */
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

/* Adds a pixel of the last pass to its tile's sums (progressive_error):
 * its halves estimate, and the changes of the last three passes relative to
 * its current denominators: d2c (this one's squared change) and the two
 * before it in `last` (as before this measure). */
static void pass_sums(double *sums, double halves, rgb d2c, const float *last, const double d2[3])
{
    double c0 = relative_error(d2c, d2), c1 = relative_error(rgb_make(last[0], last[1], last[2]), d2),
           c2 = relative_error(rgb_make(last[3], last[4], last[5]), d2);
    sums[3] += halves;
    sums[4] += c0;
    sums[5] += c1;
    sums[6] += c2;
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

/* The e_i of a tile's pixels, each the larger of its own relative error
 * (`own`) and the mean of its 3x3 neighbours' within the tile, and the
 * tile's sums over its pixels with samples. */
static void tile_errors(progressive_error *pe, const double *own, const long *counts, int tx,
                        int ty, int tw, int th, double *sums)
{
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
            size_t i = (size_t)(ty + y) * pe->w + tx + x;
            pe->e[i] = e;
            long samples = counts[y * T + x];
            if (samples > 0) {
                sums[0] += pe->halves[i];
                sums[1] += sqrt(e * (double)samples);
                sums[2] += 1.0;
            }
        }
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
    double *sums = pe->tile_own + PROGRESSIVE_TILE_SUMS * (size_t)t;
    if (!tile_rendered(pe, job->active, tx, ty, tw, th)) {
        for (int k = 3; k < PROGRESSIVE_TILE_SUMS; ++k)
            sums[k] = 0.0; /* no pixel of it in the last pass */
        return;
    }
    double pass[PROGRESSIVE_TILE_SUMS] = {0}; /* the sums over the last pass's pixels */
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
            error_denominators(m, var, n, d2);
            own[y * T + x] = relative_error(var, d2);
            size_t i = (size_t)(ty + y) * w + tx + x;
            if (job->active[i]) { /* rendered in the last pass: a new halves estimate */
                /* After the first pass (two samples, no copy before it) the
                 * halves of the pixel are its two samples, and their squared
                 * change scaled as below is the film's own s^2 / n. */
                rgb sq = film_var, d2c = film_var; /* d2c: the squared change */
                if (job->before) {
                    rgb d = rgb_sub(m, film_snapshot_pixel(job->before, f, px, py, ratio));
                    d2c = rgb_mul(d, d);
                    sq = rgb_scale(d2c, job->half_scale);
                }
                pe->halves[i] = relative_error(sq, d2);
                if (n > 0)
                    pass_sums(pass, pe->halves[i], d2c, pe->changes + 6 * i, d2);
                /* The last two passes' changes, the last first (after the
                 * first pass: as from one sample to two, (x1 - x2)^2 / 4). */
                float *c = pe->changes + 6 * i;
                c[3] = job->before ? c[0] : 0.0f;
                c[4] = job->before ? c[1] : 0.0f;
                c[5] = job->before ? c[2] : 0.0f;
                c[0] = (float)d2c.r;
                c[1] = (float)d2c.g;
                c[2] = (float)d2c.b;
            }
        }
    for (int k = 0; k < PROGRESSIVE_TILE_SUMS; ++k)
        sums[k] = pass[k];
    tile_errors(pe, own, counts, tx, ty, tw, th, sums);
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
    for (int p = 2; p > 0; --p) {
        pe->pass_n0[p] = n0 > 0 ? pe->pass_n0[p - 1] : 0;
        pe->pass_k[p] = n0 > 0 ? pe->pass_k[p - 1] : 0;
    }
    /* The first pass, two samples: as a pass from one to two. */
    pe->pass_n0[0] = n0 > 0 ? n0 : 1;
    pe->pass_k[0] = n0 > 0 ? n - n0 : 1;
    pe->unfolded = true;
    /* Each tile's figures depend on its own pixels only: the same for any
     * thread count. */
    hz_parallel_run(threads, measure_worker, &job);
    /* tile_sums may be summed across ranks next: each rank's own sums stay
     * in tile_own. */
    memcpy(pe->tile_sums, pe->tile_own,
           PROGRESSIVE_TILE_SUMS * (size_t)pe->tile_count * sizeof(double));
}

/* Whether the pass `p` (0: the last) doubled its pixels' samples. */
static bool pass_doubled(const progressive_error *pe, int p)
{
    return pe->pass_k[p] > 0 && pe->pass_k[p] == pe->pass_n0[p];
}

/* The factor x = V(n/2) / V(n) by which the variance of the image's mean
 * fell over the last pass (n/2 to n samples), from 2 (independent samples)
 * to 4. For nested halves, each as well stratified as the other, the halves
 * estimate H(n) is V(n/2) - V(n) (its covariance term is 2 V(n) - V(n/2)):
 * V(n) = H(n) / (x - 1), where taking H(n) for V(n) assumes x = 2. It is
 * read from the sums over the image of the last passes' changes c0, c1, c2
 * (the last first, over the same pixels and denominators: `s`), which are
 * H(n), H(n/2), H(n/4), under two models, each exact for its kind, and the
 * slower of the two taken (the mixed one only where it can hold):
 * - Scrambled Sobol' points converge unevenly (in 2D better at powers of 4
 *   than between them), so x alternates from pass to pass: with r1 = c1 /
 *   c0 = x (x' - 1) / (x - 1) and r2 = c2 / c1 = x' (x - 1) / (x' - 1), x'
 *   the factor of the pass before, x = r1 (r2 + 1) / (r1 + 1) (without a
 *   third pass, r2 = 2);
 * - a stratified part and one that is not converge at different rates,
 *   V(n) = A / n^2 + B / n, the second taking over as n grows: H(n) = 3 A /
 *   n^2 + B / n, H(n/2) = 12 A / n^2 + 2 B / n, and V(n) = (5 c0 - c1) / 3.
 * convergence_factor: 2 unless the last two passes doubled their samples. */
double progressive_read_convergence(double c0, double c1, double c2)
{
    if (!(c0 > 0.0) || !(c1 > 0.0))
        return 2.0;
    double r1 = c1 / c0, r2 = c2 > 0.0 ? c2 / c1 : 2.0;
    double alternating = r1 * (r2 + 1.0) / (r1 + 1.0);
    /* Under the mixed model 2 <= c1 / c0 <= 4; outside, it does not hold
     * and does not vote (fog-dof at 8 samples: c1 / c0 = 1.92 after the
     * slow pass from 2 to 4, where the noise fell 3.2x in the next). */
    double mixed_variance = (5.0 * c0 - c1) / 3.0, mixed = 1.0 + c0 / mixed_variance;
    if (!(mixed_variance > 0.0) || c1 < 2.0 * c0)
        mixed = 4.0;
    double x = alternating < mixed ? alternating : mixed;
    return x > 2.0 ? (x < 4.0 ? x : 4.0) : 2.0; /* a NaN: 2 */
}

static double convergence_factor(const progressive_error *pe, const double *s)
{
    if (!pass_doubled(pe, 0) || !pass_doubled(pe, 1))
        return 2.0;
    return progressive_read_convergence(s[4], s[5], pass_doubled(pe, 2) ? s[6] : 0.0);
}

long progressive_error_select(progressive_error *pe, const film *f,
                              const progressive_goal *goal, unsigned char *active,
                              double *estimate)
{
    double target = progressive_noise_target(goal);
    if (pe->unfolded) {
        /* The last pass's halves, from H(n) as V(n) to H(n) / (x - 1). */
        double s[PROGRESSIVE_TILE_SUMS] = {0};
        for (int t = 0; t < pe->tile_count; ++t) /* in tile order: the same on every rank */
            for (int k = 0; k < PROGRESSIVE_TILE_SUMS; ++k)
                s[k] += pe->tile_sums[PROGRESSIVE_TILE_SUMS * (size_t)t + k];
        pe->convergence = convergence_factor(pe, s);
        double factor = 1.0 / (pe->convergence - 1.0) - 1.0;
        for (int t = 0; t < pe->tile_count; ++t)
            for (int r = 0; r < 2; ++r) {
                double *sums = (r ? pe->tile_own : pe->tile_sums) + PROGRESSIVE_TILE_SUMS * (size_t)t;
                sums[0] += factor * sums[3];
                sums[3] = 0.0;
            }
        for (size_t i = 0, n = (size_t)pe->w * pe->h; factor != 0.0 && i < n; ++i)
            if (active[i])
                pe->halves[i] *= 1.0 + factor;
        pe->unfolded = false;
    }
    double e_sum = 0.0, root_sum = 0.0, pixels = 0.0;
    for (int t = 0; t < pe->tile_count; ++t) { /* in tile order: the same sum on every rank */
        const double *sums = pe->tile_sums + PROGRESSIVE_TILE_SUMS * (size_t)t;
        e_sum += sums[0];
        root_sum += sums[1];
        pixels += sums[2];
    }
    double image = pixels > 0.0 ? e_sum / pixels : 0.0;
    pe->estimate = image;
    if (estimate)
        *estimate = image;
    size_t n = (size_t)pe->w * pe->h;
    if (!(image > PROGRESSIVE_SAFETY * target)) {
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
    /* While the passes converge clearly faster than independent samples,
     * they double: the convergence of a pass of another size is not read,
     * and its estimate is not corrected for it. */
    if (pe->samples < PROGRESSIVE_TRUST_SPP || !(pe->estimate > 0.0) ||
        pe->convergence >= PROGRESSIVE_DOUBLING_CONVERGENCE)
        return progressive_pass_end(done, spp);
    /* The count where the estimate, falling as 1/n, reaches the target. */
    double want = ceil((double)done * pe->estimate / (PROGRESSIVE_SAFETY * target));
    double lo = done + (done / 4 > 1 ? done / 4 : 1), hi = 2.0 * done;
    double end = want < lo ? lo : want > hi ? hi : want;
    return end < spp ? (int)end : spp;
}
