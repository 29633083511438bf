/* The error estimate and sample allocation of --target-error: how far the
 * image is from its converged value, and which pixels take the next pass. */
#ifndef HAZE_RENDER_PROGRESSIVE_ERROR_H
#define HAZE_RENDER_PROGRESSIVE_ERROR_H

#include <stdbool.h>

#include "core/error.h"
#include "film/film.h"
#include "render/progressive_goal.h"

/* Samples before the passes are sized by the image's estimate (before, they
 * double): 4, after the second pass, the first whose convergence is read
 * (with 8 the bench cloud at E = 1e-3 doubled from 4 to 8 samples where 5
 * met E). The tuning of the estimates, measured on the benchmark scenes
 * (docs/progressive.md): the image stops at SAFETY * E; every pixel takes at
 * least MIN_SCALE / sqrt(E) samples; LOWER_BOUND_K, SINGLE_SAMPLE_SPP and
 * SINGLE_SAMPLE_SD: see progressive_error;
 * from a convergence of DOUBLING_CONVERGENCE (progressive_error) on, passes
 * double (progressive_error_next_end). TILE_SUMS: the sums per tile of
 * progressive_error. */
enum {
    PROGRESSIVE_TRUST_SPP = 4,
    PROGRESSIVE_SINGLE_SAMPLE_SPP = 16,
    PROGRESSIVE_TILE_SUMS = 7
};
#define PROGRESSIVE_SAFETY 1.0
#define PROGRESSIVE_DOUBLING_CONVERGENCE 2.2
#define PROGRESSIVE_MIN_SCALE 0.2
#define PROGRESSIVE_LOWER_BOUND_K 0.7
#define PROGRESSIVE_SINGLE_SAMPLE_SD 0.9

/* The error estimates behind --target-error. A pixel's relative error is
 * haze diff's relMSE term, Var / (b + 0.01)^2 with b the converged value;
 * for b haze takes m_lo = max(0, |m| - K sqrt(Var[m])), K =
 * PROGRESSIVE_LOWER_BOUND_K, because a pixel's own mean m is high exactly when
 * a rare bright sample also raised its variance (with m itself the estimate
 * was 3x too low at 4 spp on smoke.pbrt; with K = 0.5, 0.82-0.86 of the
 * estimate over the converged value on cloud-volpath.pbrt, whose renders
 * then missed E = 1e-2 by 16-31%); from
 * PROGRESSIVE_SINGLE_SAMPLE_SPP samples on, m_lo = 0 where the mean is one
 * sample's (sd(m) >= PROGRESSIVE_SINGLE_SAMPLE_SD m: a firefly; before, a
 * single bright sample is common in sparse pixels and the bound stays: at 8
 * samples fog-dof took 28% more at E = 1e-2). Channel mean. Neighbourhoods end at
 * tile edges, so a tile's figures depend on its own pixels only (under MPI
 * each rank measures the tiles it owns).
 * - Allocation, per pixel: e_i from the film's variance of the mean (s^2/n,
 *   the variance per sample at least the spread of the 3x3 neighbours'
 *   means: first samples that agree show none at a partly covered edge),
 *   the larger of its own and its 3x3 neighbours' mean (few samples
 *   underestimate a variance). The fewest samples reaching a mean error E
 *   give pixel i n_i proportional to sqrt(r_i), r_i = e_i n_i the error of
 *   one sample: n*_i = sqrt(r_i) mean(sqrt(r)) / E, at least
 *   PROGRESSIVE_MIN_SCALE / sqrt(E) (samples that agree may still miss an
 *   edge or a rare path); a pixel with n_i >= n*_i takes no more samples.
 * - When to stop, for the image: the mean over pixels of the "halves"
 *   estimate: the squared change of a pixel's value over its last pass,
 *   scaled to the variance of its mean, against PROGRESSIVE_SAFETY * E.
 *   Unlike s^2/n it follows the faster-than-1/n convergence of stratified
 *   (Sobol') samples, and over a pass that doubled them it is corrected for
 *   that convergence, read from the passes' changes (`convergence`: for
 *   independent samples the squared change scaled so is the variance of the
 *   mean, for stratified ones up to 3x it). */
typedef struct {
    int x0, y0, w, h, tiles_x, tile_count;
    int samples;       /* of the pixels rendered in the last pass */
    double estimate;   /* the image's relMSE, by the last progressive_error_select */
    double *e;         /* per pixel */
    double *halves;    /* per pixel: the halves estimate of its last pass */
    /* Per pixel, the squared changes (per channel) of its last two passes,
     * the last first: the convergence of the passes (progressive_error_select). */
    float *changes;
    /* The last three measured passes, the last first: each from n0 to n0 + k
     * samples (k = 0: none). */
    int pass_n0[3], pass_k[3];
    bool unfolded;     /* the last measure's halves are not yet corrected */
    /* The factor by which the variance of the image's mean fell over the
     * last pass, as progressive_error_select read it (2: as for independent
     * samples). */
    double convergence;
    /* Per tile, in tile order, PROGRESSIVE_TILE_SUMS doubles (to be summed
     * across ranks): over the pixels with samples, the sums of the halves
     * estimates (before the correction for their convergence), of sqrt(r_i)
     * and the pixels; then over the pixels the last pass rendered, of their
     * halves, and of the relative squared changes of the last three passes
     * (the last first, over the current denominators). */
    double *tile_sums;
    /* The same sums of this process's film, kept between measures: a tile
     * the last pass did not render is not measured again. */
    double *tile_own;
} progressive_error;

hz_status progressive_error_init(progressive_error *pe, const film *f, hz_error *err);
void progressive_error_free(progressive_error *pe);
/* Measures e_i of every pixel and the sums of each tile (tiles without
 * samples sum to exactly 0), tiles on `threads` threads (<= 0: every core),
 * after a pass that took the active pixels from n0 to n samples. `before`:
 * the film before that pass; unused after the first pass (n0 = 0, two
 * samples), whose halves estimate is the film's own variance.
 * Tiles with no pixel in `active` (the pixels the last pass rendered) keep
 * the figures of the previous measure: the first must have all active. */
void progressive_error_measure(progressive_error *pe, const film *f, const film_snapshot *before,
                               const unsigned char *active, int n0, int n,
                               double imaging_ratio, int threads);
/* Clears active[i] of each pixel that has its share (above; its least count
 * from goal->target_error), or of all when the image's estimate is at most
 * progressive_noise_target(goal); the tile sums may first have been summed
 * across ranks. The first call after a measure corrects the last pass's
 * halves estimates for the passes' convergence (in the tile sums too, and
 * the same on every rank). `active`: the pixels of the last measure's pass.
 * Returns the pixels left active; *estimate (may be NULL): the image's
 * estimated relMSE. */
long progressive_error_select(progressive_error *pe, const film *f,
                              const progressive_goal *goal, unsigned char *active,
                              double *estimate);

/* The factor x = V(n/2) / V(n) (2 to 4) read from the squared changes of
 * the last three doubling passes over the image, c0 = H(n), c1 = H(n/2),
 * c2 = H(n/4) (c2 <= 0: no third pass): the slower of the alternating and
 * the mixed model (progressive_error.c; the mixed one only where it can
 * hold, 2 <= c1 / c0 <= 4); 2 without two passes' changes. */
double progressive_read_convergence(double c0, double c1, double c2);

/* The end of the next pass of a render with a target error: the first
 * (done = 0) as progressive_first_end; from PROGRESSIVE_TRUST_SPP samples
 * on, unless the passes converge at PROGRESSIVE_DOUBLING_CONVERGENCE or
 * faster, the count at which the estimate (falling as 1/n) reaches the noise
 * target, at least a quarter more and at most twice `done`; else
 * progressive_pass_end. */
int progressive_error_next_end(const progressive_error *pe, int done, int spp,
                               const progressive_goal *goal);

#endif
