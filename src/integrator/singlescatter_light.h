/* Light arriving at points of single scattering: shadow rays through
 * surfaces and media (one walk, integrator/walk.h, with the shadow
 * estimator of integrator/singlescatter_tracking.h per medium segment) and
 * the light of every lamp scattered at a point of a medium. */
#ifndef HAZE_INTEGRATOR_SINGLESCATTER_LIGHT_H
#define HAZE_INTEGRATOR_SINGLESCATTER_LIGHT_H

#include "core/vec.h"
#include "integrator/path.h"
#include "integrator/singlescatter_scene.h"
#include "lights/lights.h"
#include "sampler/sampler.h"

/* Transmittance from `o` along unit `w` to distance `tmax` (INFINITY: to the end
 * of the scene), starting in `medium` (-1 vacuum): every medium segment
 * attenuates, interfaces switch the medium, any other surface blocks (black).
 * Surfaces are searched from `tmin` on (past the surface `o` lies on, if any);
 * media fill the whole span from 0. */
rgb singlescatter_shadow_transmittance(const singlescatter_scene *vs, vec3 o, vec3 w, double tmin,
                                       double tmax, int medium, media_walk *walk);

/* p(wo, wi) L_i T_shadow / pdf of light `l` at point x in medium `mi`,
 * averaged over its samples (phase function applied; sigma_s and the
 * transmittance to x not). */
rgb singlescatter_light_inscattered(const singlescatter_scene *vs, int mi, const light *l, vec3 x,
                                    vec3 wo, sampler_state *u, media_walk *walk);

/* Light of every lamp scattered at x toward wo in medium mi, shadow rays
 * included (phase function applied; sigma_s and transmittance to x not). */
rgb singlescatter_inscattered(const singlescatter_scene *vs, int mi, vec3 x, vec3 wo,
                              sampler_state *u, media_walk *walk);

#endif
