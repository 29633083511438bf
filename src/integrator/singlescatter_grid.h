/* Camera-ray segments of single scattering in density-grid media:
 * transmittance and in-scattering on strata of `stepsize` voxels, with the
 * camera rays' estimator (integrator/singlescatter_tracking.h). */
#ifndef HAZE_INTEGRATOR_SINGLESCATTER_GRID_H
#define HAZE_INTEGRATOR_SINGLESCATTER_GRID_H

#include "core/vec.h"
#include "integrator/path.h"
#include "integrator/singlescatter_scene.h"
#include "sampler/sampler.h"

/* `raymarch` camera rays end where their transmittance falls below this
 * fraction of their throughput at entry (what is left behind is at most that
 * fraction of the light beyond): deterministic, unlike roulette. */
#define SINGLESCATTER_MARCH_CUTOFF 1e-4

/* The segment [t0, t1] of camera ray o + t w in grid medium mi: adds
 * beta x (in-scattered and emitted radiance) to *L and multiplies beta by
 * its transmittance. */
void singlescatter_grid_segment(const singlescatter_scene *vs, int mi, vec3 o, vec3 w, double t0,
                                double t1, rgb *beta, rgb *L, sampler_state *u, media_walk *walk);

#endif
