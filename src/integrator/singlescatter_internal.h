/* Private to the media walk (singlescatter_media.c, singlescatter_grid.c):
 * helpers both halves use, and the grid-medium estimators
 * singlescatter_media.c dispatches to. */
#ifndef HAZE_INTEGRATOR_SINGLESCATTER_INTERNAL_H
#define HAZE_INTEGRATOR_SINGLESCATTER_INTERNAL_H

#include <math.h>

#include "integrator/singlescatter_media.h"

/* A walk never places more in-scattering strata than this on one segment: it
 * bounds the work of absurd step sizes (the step grows instead). */
#define SINGLESCATTER_MAX_STRATA 1000000

/* Russian roulette on a walk's throughput: below SINGLESCATTER_RR_THRESHOLD it survives
 * with probability max(beta)/threshold and is scaled up to compensate. Returns
 * false when the walk ends (beta is then 0). */
bool singlescatter_roulette(rgb *beta, rng *r);

/* Light of every lamp scattered at x toward wo in medium mi, shadow rays
 * included (phase function applied; sigma_s and transmittance to x not). */
rgb singlescatter_inscattered(const singlescatter_scene *vs, int mi, vec3 x, vec3 wo,
                              sampler_state *u, media_walk *walk);

/* Grid media (singlescatter_grid.c): transmittance of [t0, t1] with the shadow
 * estimator, and a camera-ray segment with in-scattering. */
rgb singlescatter_grid_transmittance(const singlescatter_scene *vs, const medium *m, vec3 o, vec3 w,
                                     double t0, double t1, media_walk *walk);
void singlescatter_grid_segment(const singlescatter_scene *vs, int mi, vec3 o, vec3 w, double t0,
                                double t1, rgb *beta, rgb *L, sampler_state *u, media_walk *walk);

#endif
