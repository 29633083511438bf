/* The integrator a scene renders with: a closed set of kinds, chosen by the
 * scene's Integrator directive and built once its geometry, lights and media
 * exist. "volpath" (pbrt-v4's default, integrator/volpath.h) when the scene
 * names it; "singlescatter" (integrator/singlescatter.h) when it names that or
 * names no Integrator at all: haze's default. */
#ifndef HAZE_INTEGRATOR_INTEGRATOR_H
#define HAZE_INTEGRATOR_INTEGRATOR_H

#include <stdio.h>

#include "core/error.h"
#include "core/ray.h"
#include "integrator/path.h"
#include "film/film.h"
#include "integrator/singlescatter.h"
#include "integrator/volpath.h"
#include "sampler/sampler.h"
#include "scene/scene_desc.h"

typedef enum { INTEGRATOR_SINGLESCATTER, INTEGRATOR_VOLPATH } integrator_kind;

/* The Integrator directive's settings, read before the scene is built. */
typedef struct {
    integrator_kind kind;
    union {
        singlescatter_settings singlescatter;
        volpath_settings volpath;
    };
} integrator_params;

/* What a scene that names no Integrator renders with: "singlescatter",
 * haze's default, unless it declares a material or a medium only "volpath"
 * renders (a "conductor", "dielectric" or "thindielectric"; a "cloud" or an
 * "rgbgrid"): then pbrt-v4's default, "volpath" with maxdepth 5. `*why`
 * receives that type and `*what` "material" or "medium" (NULL otherwise). */
integrator_kind integrator_default_kind(const scene_desc *sd, const char **why, const char **what);

/* Reads the Integrator entity of `sd` (warnings to `warn` when not NULL) and
 * checks that every parameter was used; errors name its place. */
hz_status integrator_params_from_scene(scene_desc *sd, FILE *warn, integrator_params *out,
                                       hz_error *err);

typedef struct {
    integrator_kind kind;
    union {
        singlescatter_scene singlescatter;
        volpath_scene volpath;
    };
} integrator;

hz_status integrator_init(integrator *out, const integrator_params *p,
                          const integrator_inputs *in, hz_error *err);
void integrator_free(integrator *it);
/* The footprint scale of integrator_inputs, which the renderer knows once
 * it has the samples per pixel (set before rendering, not during). */
void integrator_set_footprint_scale(integrator *it, double scale);

/* Radiance along the camera ray `r` (unit direction): RGB, or with `sp`
 * (spectral rendering) the lanes at its wavelengths. `depth` receives the
 * distance to the first opaque surface (INFINITY when none); `vs` (NULL when
 * not wanted: it costs an albedo estimate) what that surface is, when the
 * ray met it before any scattering (vs->hit). Thread-safe; allocates
 * nothing. */
rgb integrator_li(const integrator *it, const ray_differential *rd, const spectral_ctx *sp,
                  sampler_state *st, double *depth, film_surface *vs,
                  integrator_counters *counters);

#endif
