/* Private to the media walk (volume.c, volume_grid.c): helpers both halves
 * use, and the grid-medium estimators volume.c dispatches to. */
#ifndef HAZE_RENDER_VOLUME_INTERNAL_H
#define HAZE_RENDER_VOLUME_INTERNAL_H

#include <math.h>

#include "render/volume.h"

/* A walk never places more in-scattering strata than this on one segment: it
 * bounds the work of absurd step sizes (the step grows instead). */
#define VOLUME_MAX_STRATA 1000000

static inline double volume_ch(rgb c, int i) { return i == 0 ? c.r : i == 1 ? c.g : c.b; }

/* e^{-sigma d} per channel; a channel that does not attenuate stays 1 (0 * INFINITY is NaN). */
static inline rgb rgb_exp_neg(rgb sigma, double d)
{
    return rgb_make(sigma.r > 0.0 ? exp(-sigma.r * d) : 1.0,
                    sigma.g > 0.0 ? exp(-sigma.g * d) : 1.0,
                    sigma.b > 0.0 ? exp(-sigma.b * d) : 1.0);
}

/* Russian roulette on a walk's throughput: below VOLUME_RR_THRESHOLD it survives
 * with probability max(beta)/threshold and is scaled up to compensate. Returns
 * false when the walk ends (beta is then 0). */
bool volume_roulette(rgb *beta, rng *r);

/* Light of every lamp scattered at x toward wo in medium mi, shadow rays
 * included (phase function applied; sigma_s and transmittance to x not). */
rgb volume_inscattered(const volume_scene *vs, int mi, vec3 x, vec3 wo, sampler_state *u,
                       volume_walk *walk);

/* Grid media (volume_grid.c): transmittance of [t0, t1] with the shadow
 * estimator, and a camera-ray segment with in-scattering. */
rgb volume_grid_transmittance(const volume_scene *vs, const medium *m, vec3 o, vec3 w, double t0,
                              double t1, volume_walk *walk);
void volume_grid_segment(const volume_scene *vs, int mi, vec3 o, vec3 w, double t0, double t1,
                         rgb *beta, rgb *L, sampler_state *u, volume_walk *walk);

#endif
