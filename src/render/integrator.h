/* haze's single-scattering integrator: along a camera ray, the medium segments
 * between surfaces (in-scattering and transmittance, render/volume.h), then
 * emitted light and one sample of every light at the first opaque surface, with
 * shadow rays attenuated by the media they cross. Interface surfaces are
 * stepped through, switching the ray's medium. A scene without media never
 * enters the media code: shadow rays are plain occlusion tests. */
#ifndef HAZE_RENDER_INTEGRATOR_H
#define HAZE_RENDER_INTEGRATOR_H

#include <stddef.h>

#include "core/ray.h"
#include "render/render_scene.h"
#include "render/volume.h"
#include "sampler/sampler.h"

typedef volume_scene integrator_scene;

/* `r->d` must be unit. */
rgb integrator_li(const integrator_scene *sc, const ray *r, sampler_state *st, double *depth,
                  render_counters *counters);

#endif
