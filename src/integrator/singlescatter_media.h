/* Single scattering in participating media: the part of haze's integrator that
 * walks a ray through media. Only scenes with media reach this code.
 *
 * Along a ray segment [t0, t1] inside one medium it estimates, jointly,
 *   the transmittance T(t0, t1) and
 *   the in-scattered radiance  ∫ T(t0, t) σ_s(t) Σ_lights p(wo, wi) L_i T_shadow dt.
 *
 * Homogeneous media use closed-form transmittance and sample scattering
 * distances: exponentially (by transmittance), and for point and spot lights
 * also equiangularly around the light (Kulla & Fajardo 2012), the two combined
 * with the balance heuristic. Grid media place in-scattering samples on
 * `stepsize`-voxel strata of the segment and estimate transmittance by
 *   TRANSMITTANCE_RAYMARCH   fixed steps (midpoint; biased, error shrinks with the step),
 *   TRANSMITTANCE_JITTERED   steps with one random offset per ray (banding becomes noise),
 *   TRANSMITTANCE_RATIO      ratio tracking against each majorant-grid cell's bound (unbiased),
 *   TRANSMITTANCE_RESIDUAL   residual ratio tracking: the cell's lower bound as an exact
 *                            control, collisions only for the residual (unbiased).
 * Every estimator walks the medium's majorant grid (media/majorant.h): empty
 * cells cost no density lookup.
 * Shadow rays use the same estimator with `shadowstepsize`. Low transmittance
 * ends a walk by Russian roulette, never by a cutoff. Moving grids (animated
 * placement, velocity grids) are looked up at the walk's time everywhere:
 * camera rays, shadow rays, every estimator. */
#ifndef HAZE_INTEGRATOR_SINGLESCATTER_MEDIA_H
#define HAZE_INTEGRATOR_SINGLESCATTER_MEDIA_H

#include "core/vec.h"
#include "integrator/path.h"
#include "integrator/singlescatter_scene.h"
#include "sampler/sampler.h"

/* The segment [t0, t1] (t1 may be INFINITY) of the unit-direction ray o + t w in
 * medium `m`: adds beta × (in-scattered radiance) to *L and multiplies beta by
 * the segment's transmittance (estimated; may become 0 by Russian roulette).
 * `u` supplies the sampler's dimensions for distance sampling. */
void singlescatter_segment(const singlescatter_scene *vs, int m, vec3 o, vec3 w, double t0,
                           double t1, rgb *beta, rgb *L, sampler_state *u, media_walk *walk);

#endif
