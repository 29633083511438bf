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
#include "integrator/path.h"
#include "integrator/singlescatter_scene.h"
#include "media/medium.h"

/* Below this largest transmittance component a walk plays Russian roulette. */
#define SINGLESCATTER_RR_THRESHOLD 1e-2
/* A walk never places more in-scattering strata than this on one segment: it
 * bounds the work of absurd step sizes (the step grows instead). */
#define SINGLESCATTER_MAX_STRATA 1000000

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

/* ---- strata: sample points t0 + (i + offset) dt, i < n ---- */

typedef struct {
    double t0, dt;
    int n, i;
    double offset; /* < 0: a uniform of its own per stratum */
    uint64_t key;  /* ... the i-th number of the stream that starts at key */
    double t;      /* sample point of stratum i (INFINITY once i == n) */
} strata;

/* Per-stratum offsets are read at random from a counter-based stream, not
 * drawn in turn: skipping strata then draws nothing, so where cell
 * boundaries fall (up to rounding) does not shift any later random number. */
static inline void strata_load(strata *s)
{
    double u = s->offset;
    if (u < 0.0) {
        rng at = rng_seeded(s->key + (uint64_t)s->i * 0x9e3779b97f4a7c15ull);
        u = rng_uniform(&at);
    }
    s->t = s->i < s->n ? s->t0 + (s->i + u) * s->dt : INFINITY;
}

/* Strata of about `step` voxels over [t0, t1], positioned at stratum 0. */
static inline void strata_make(strata *s, const medium_ray *gr, double t0, double t1, double step,
                        double offset, rng *r)
{
    double n = ceil((t1 - t0) * gr->voxels_per_t / step);
    if (!(n >= 1.0))
        n = 1.0;
    if (n > SINGLESCATTER_MAX_STRATA)
        n = SINGLESCATTER_MAX_STRATA;
    s->t0 = t0;
    s->n = (int)n;
    s->dt = (t1 - t0) / n;
    s->i = 0;
    s->offset = offset;
    s->key = offset < 0.0 ? rng_bits(r) : 0;
    strata_load(s);
}

static inline bool strata_before(const strata *s, double b) { return s->i < s->n && s->t < b; }

static inline void strata_next(strata *s)
{
    ++s->i;
    strata_load(s);
}

/* Moves past every stratum whose sample lies before b (the end of an empty
 * cell), jumping over those that end before it. */
static inline void strata_skip_to(strata *s, double b)
{
    while (strata_before(s, b)) {
        double k = floor((b - s->t0) / s->dt); /* strata before k end before b */
        s->i = k > s->i + 1.0 ? (k >= s->n ? s->n : (int)k) : s->i + 1;
        strata_load(s);
    }
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
