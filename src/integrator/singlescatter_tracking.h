/* Single scattering's transmittance estimators (Integrator "singlescatter"):
 * the transmittance of one medium segment, and the pieces the camera-ray
 * segments of grid media share with it: strata of marching samples,
 * per-cell collision rates, Russian roulette. Grid media are walked over
 * their majorant segments (media/medium.h): empty cells cost no lookup.
 *   raymarch, jittered  strata of `stepsize` voxels over the segment, sampled
 *                       at one offset (0.5, or one uniform per ray); strata
 *                       whose sample lies in an empty cell are skipped, which
 *                       changes no result (their density is exactly 0).
 *   ratio               ratio tracking with each cell's own majorant.
 *   residual            residual ratio tracking (Novák et al. 2014): each
 *                       cell's lower bound is a control whose transmittance is
 *                       exact, and tentative collisions at the rate of the
 *                       residual (max - min) correct for the rest.
 * Ratio and residual tracking are unbiased; a cell that expects more than
 * `maxcollisions` tentative collisions is marched instead (jittered).
 * Homogeneous media have closed forms. */
#ifndef HAZE_INTEGRATOR_SINGLESCATTER_TRACKING_H
#define HAZE_INTEGRATOR_SINGLESCATTER_TRACKING_H

#include <math.h>

#include "core/rng.h"
#include "integrator/strata.h"
#include "integrator/path.h"
#include "integrator/singlescatter_scene.h"
#include "media/medium.h"

/* Below this largest transmittance component a walk plays Russian roulette. */
#define SINGLESCATTER_RR_THRESHOLD 1e-2

/* Russian roulette on a walk's throughput: below SINGLESCATTER_RR_THRESHOLD it survives
 * with probability max(beta)/threshold and is scaled up to compensate. Returns
 * false when the walk ends (beta is then 0). */
bool singlescatter_roulette(rgb *beta, rng *r);

/* Transmittance of [t0, t1] of o + t w in medium m with the shadow rays'
 * estimator. */
rgb singlescatter_segment_transmittance(const singlescatter_scene *vs, const medium *m, vec3 o,
                                        vec3 w, double t0, double t1, media_walk *walk);

/* Counts density and velocity lookups alike (media_walk.lookups). */
static inline double grid_ray_density(medium_ray *gr, double t, media_walk *walk)
{
    return medium_ray_density(gr, t, &walk->lookups);
}

static inline bool next_cell(medium_ray *gr, majorant_segment *seg, media_walk *walk)
{
    return medium_ray_next(gr, seg, &walk->majorant_steps);
}

/* ---- per cell ---- */

/* The rate of tentative collisions in a cell and the density of its control
 * (residual tracking: the cell's lower bound; ratio tracking: none). */
typedef struct {
    double lo;    /* control density */
    double mu;    /* majorant of sigma_t (density - lo), largest channel */
    bool march;   /* more collisions expected than max_collisions: march instead */
} cell_rates;

static inline cell_rates cell_rates_make(const singlescatter_settings *set, transmittance_mode mode,
                                  const majorant_segment *seg, double sigma_max)
{
    cell_rates c;
    c.lo = mode == TRANSMITTANCE_RESIDUAL ? seg->min : 0.0;
    c.mu = sigma_max * (seg->max - c.lo);
    c.march = set->max_collisions > 0.0 && c.mu * (seg->t1 - seg->t0) > set->max_collisions;
    return c;
}

/* T times 1 - sigma_t (dens - lo) / mu per channel: one tentative collision. */
static inline rgb collide(rgb T, rgb sigma_t, double d, double mu)
{
    return rgb_mul(T, (rgb){1.0 - sigma_t.r * d / mu, 1.0 - sigma_t.g * d / mu,
                            1.0 - sigma_t.b * d / mu, 1.0 - sigma_t.w * d / mu});
}

#endif
