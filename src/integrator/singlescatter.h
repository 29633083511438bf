/* haze's single-scattering integrator (Integrator "singlescatter"): along a
 * camera ray, the medium segments between surfaces (in-scattering and
 * transmittance, integrator/singlescatter_media.h), then emitted light and one
 * sample of every light at the first opaque surface, with shadow rays
 * attenuated by the media they cross. Interface surfaces are stepped through,
 * switching the ray's medium. A scene without media never enters the media
 * code: shadow rays are plain occlusion tests. */
#ifndef HAZE_INTEGRATOR_SINGLESCATTER_H
#define HAZE_INTEGRATOR_SINGLESCATTER_H

#include "core/ray.h"
#include "film/film.h"
#include "integrator/path.h"
#include "integrator/singlescatter_scene.h"
#include "sampler/sampler.h"

/* `r->d` must be unit. With `sp` (spectral rendering) the radiance is the
 * lanes at its wavelengths. */
rgb singlescatter_li(const singlescatter_scene *sc, const ray_differential *rd,
                     const spectral_ctx *sp, sampler_state *st, double *depth, film_surface *vs,
                     integrator_counters *counters);

#endif
