/* Surface direct lighting (haze's single-scattering integrator without media):
 * emitted light seen directly plus one sample of every light at the first
 * surface, with shadow rays; interface surfaces are stepped through. */
#ifndef HAZE_RENDER_INTEGRATOR_H
#define HAZE_RENDER_INTEGRATOR_H

#include <stddef.h>

#include "core/ray.h"
#include "render/geometry.h"
#include "render/lights.h"
#include "render/render_scene.h"
#include "sampler/sampler.h"

typedef struct {
    const geometry *geom;
    const light *lights;
    size_t light_count;
} integrator_scene;

/* A camera ray crossing more interfaces than this is treated as lost (black):
 * it bounds the work of pathological nested boundaries. */
#define INTEGRATOR_MAX_CROSSINGS 64

/* Shadow rays to a point stop this fraction short of it (pbrt-v4's
 * ShadowEpsilon), so the light's own surface is not counted as a blocker. */
#define INTEGRATOR_SHADOW_EPSILON 1e-4

rgb integrator_li(const integrator_scene *sc, const ray *r, sampler_state *st, double *depth,
                  render_counters *counters);

#endif
