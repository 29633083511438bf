/* Null-scattering tracking through one medium for the volpath integrator
 * (pbrt-v4's SampleT_maj): tentative collisions are sampled along a ray
 * segment at the rate of the majorant sigma_maj in the path's hero channel;
 * at each one the caller decides (absorb, scatter, null) with the medium's
 * coefficients there. Homogeneous media have sigma_maj = sigma_t; grid media
 * walk their majorant grid (media/majorant.h) with sigma_maj = sigma_t times
 * each cell's density bound, so empty cells cost no lookup and no random
 * number. Random numbers come from the walk's rng (thread-count independent). */
#ifndef HAZE_INTEGRATOR_VOLPATH_MEDIA_H
#define HAZE_INTEGRATOR_VOLPATH_MEDIA_H

#include <stdbool.h>

#include "core/vec.h"
#include "media/medium.h"
#include "integrator/path.h"

/* One tentative collision at distance t: the coefficients there, the
 * majorant, the majorant transmittance since the previous collision (or
 * the segment's start), and the emission. */
typedef struct {
    double t;
    rgb sigma_a, sigma_s, sigma_maj, T_maj;
    rgb emission; /* the source term there, per unit length: sigma_a Le (pbrt-v4's
                   * absorbing emission) plus a free emission grid's; 0 when the
                   * walk does not gather emission */
} volpath_event;

/* Returns false to end the walk. */
typedef bool (*volpath_event_fn)(void *ctx, const volpath_event *ev);

/* A walk gives up after this many tentative collisions on one segment: a grid
 * at an absurd density scale (1e12) whose majorant cell covers empty voxels
 * would otherwise take ~1e12 null collisions per unit length (pbrt-v4 hangs
 * there). Such a segment counts as opaque (see docs/media.md); real scenes
 * stay many orders of magnitude below (a few hundred per segment). */
#define VOLPATH_MAX_COLLISIONS (1u << 16)

/* Walks o + t w (unit w) over [t0, t1] (t1 may be INFINITY) in medium m at the
 * walk's time, calling `fn` at each tentative collision. The first
 * collision's exponential deviate is -log(1 - u) for u in [0, 1) (a pixel
 * sampler dimension, as pbrt-v4's SampleT_maj takes one: stratified over a
 * pixel's samples), the rest come from the walk's rng (all of them for
 * u < 0). Returns the majorant
 * transmittance from the last collision to t1, (1, 1, 1) when `fn` ended the
 * walk, or (0, 0, 0) past VOLPATH_MAX_COLLISIONS. `hero` in 0..2 is the
 * channel whose majorant sets the rate. With `emission` (a path's segment,
 * not a shadow ray's) the events carry the emission, and cells where a free
 * emission grid glows but there is no density get tentative collisions too
 * (two expected per cell). */
rgb volpath_track(const medium *m, vec3 o, vec3 w, double t0, double t1, int hero, bool emission,
                  double u, media_walk *walk, volpath_event_fn fn, void *ctx);

/* pbrt-v4's roulette of a shadow ray's ratio tracking: once its estimate
 * (T over the mean of r_l + r_u, largest lane) is below 0.05, the ray ends
 * with probability 0.75 and survives with its estimate times 4. The factor
 * to apply: 0 (ended), 4 or 1. */
static inline double volpath_shadow_roulette(double estimate, rng *r)
{
    if (!(estimate < 0.05))
        return 1.0;
    return rng_uniform(r) < 0.75 ? 0.0 : 4.0;
}

/* Grey media: density grids that neither move nor carry emission or colour
 * grids, whose sigma_a and sigma_s are the same in every lane (as the path
 * sees them: m may be a spectral copy). There the hero's majorant is every
 * lane's, so the ratios volpath_track's callers form from T_maj are all 1:
 * delta tracking changes no weight at a null collision and ratio tracking
 * multiplies every lane by the same 1 - density / bound. The two walks below
 * do that with scalars and no exponential; in expectation they are
 * volpath_track with path_event and shadow_event (tests/unit/
 * test_integrator_volpath_grey.c checks both against the closed forms). */
bool volpath_grey(const medium *m);

typedef enum {
    VOLPATH_PASSED, /* no real collision on the segment */
    VOLPATH_REAL,   /* a real collision at *t, density *density there */
    VOLPATH_OPAQUE  /* past VOLPATH_MAX_COLLISIONS: the segment counts as opaque */
} volpath_flight;

/* Delta tracking of grey medium m (volpath_grey) along o + t w over [t0, t1]:
 * the first real collision (u as volpath_track's). */
volpath_flight volpath_grey_flight(const medium *m, vec3 o, vec3 w, double t0, double t1,
                                   double u, media_walk *walk, double *t, double *density);

/* Marching (Integrator "volpath" "float stepsize", Cycles' way through
 * volumes): density grids whose coefficients are a density times constants
 * (no colour or emission grid) and that do not move. Along a segment, strata
 * of about `step` voxels each hold the density at one point (one offset per
 * ray, from the walk's rng) over their whole length; empty majorant cells
 * are skipped. In that piecewise-constant field a flight's distance and a
 * shadow ray's transmittance are exact: biased by the strata, not noisy. */
bool volpath_marches(const medium *m);

/* A flight through marchable medium m (volpath_marches) along o + t w over
 * [t0, t1]: the first point where the strata's density integral reaches
 * `stop` (an Exp(1) deviate over the hero channel's sigma_t; INFINITY: none).
 * *D gets the integral up to there or to t1; at a VOLPATH_REAL collision *t
 * and *density are its place and its stratum's density. Never OPAQUE. */
volpath_flight volpath_march(const medium *m, vec3 o, vec3 w, double t0, double t1, double step,
                             double stop, media_walk *walk, double *D, double *t,
                             double *density);

/* Ratio tracking of a shadow ray through grey medium m over [t0, t1] with
 * volpath_shadow_roulette, whose estimate needs the ray's state so far:
 * t_max, rl_avg, ru_avg are its T's largest lane and the means of its r_l
 * and r_u. Sets *T and *r_u to the factors every lane of the ray's T and r_u
 * is to be multiplied by (1 where the ray misses the density; r_l is
 * unchanged). False when the estimate ended at 0 (roulette, or past
 * VOLPATH_MAX_COLLISIONS). */
bool volpath_grey_ratio(const medium *m, vec3 o, vec3 w, double t0, double t1, media_walk *walk,
                        double t_max, double rl_avg, double ru_avg, double *T, double *r_u);

#endif
