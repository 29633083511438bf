/* The volpath integrator (Integrator "volpath"): multiple scattering by
 * null-scattering path tracing, as pbrt-v4's VolPathIntegrator. Along each
 * path, media are crossed by delta tracking against their majorants (one
 * hero channel per path, picked uniformly; the other channels ride along
 * through pbrt-v4's rescaled path probabilities r_u, r_l, which make the
 * estimate a one-sample MIS over the three hero choices); at surfaces and at
 * real scattering events, one light is sampled (light_sampler.h) with a
 * shadow ray through media by ratio tracking, combined by MIS (balance
 * heuristic) with BSDF or phase-function sampling, which also finds area
 * lights and the sky. Russian roulette after depth 1, `maxdepth` scattering
 * events (surfaces and media alike; interfaces are not events). With a
 * shadow cache, a scattering vertex in a grid medium reads a distant light's
 * transmittance from it: no shadow ray, and no noise from one (the same
 * estimate for every hero channel, so r_u and r_l stay as they are). With a
 * step, grid media are marched instead of tracked (Cycles' estimator:
 * biased by the step, cheaper and without null collisions): a flight samples
 * its distance in the strata's piecewise-constant field in the hero channel,
 * and the other lanes' weights are their transmittances there over the
 * hero's; a shadow ray's transmittance is exp(-sigma_t D) of the strata's
 * density integral D.
 *
 * Random numbers: the pixel sampler for light, BSDF and phase sampling and
 * the roulette (as pbrt-v4), a per-path rng (core/rng.h, seeded from the
 * sampler) for the media's tracking decisions: the image depends on the
 * scene and seed only, not on the thread count. A scene without media runs
 * no media code. Emitting media add their emission at every tentative
 * collision (pbrt-v4's estimator), while depth < maxdepth. */
#ifndef HAZE_INTEGRATOR_VOLPATH_H
#define HAZE_INTEGRATOR_VOLPATH_H

#include <stdbool.h>
#include <stdio.h>

#include "core/error.h"
#include "core/ray.h"
#include "film/film.h"
#include "media/medium.h"
#include "geometry/geometry.h"
#include "lights/light_sampler.h"
#include "lights/lights.h"
#include "integrator/path.h"
#include "integrator/shadow_cache.h"
#include "sampler/sampler.h"
#include "scene/scene_desc.h"

/* The most continuations "mediumsplits" may ask for. */
#define VOLPATH_MAX_SPLITS 256

typedef struct {
    int max_depth;                     /* "maxdepth", default 5 */
    bool regularize;                   /* "regularize", default false */
    light_sampler_kind light_sampler;  /* "lightsampler": uniform, power, bvh */
    /* Option "forcediffuse": each hit's BSDF becomes a diffuse one of its
     * directional albedo, estimated from one sample (as pbrt-v4). */
    bool force_diffuse;
    /* "shadowcache": the node spacing (voxels) of the shadow cache that
     * scattering vertices in grid media read for distant lights instead of
     * tracing shadow rays (integrator/shadow_cache.h); 0: none. */
    double shadow_cache;
    /* "stepsize": voxels between the strata that flights and shadow rays
     * through marchable grid media march (volpath_media.h's volpath_marches)
     * instead of tracking them; 0: tracking (pbrt-v4's, unbiased). */
    double step;
    /* "mediumsplits": how many continuations a path runs from its first
     * scattering point in a medium, each with its own phase-sampled
     * direction and random numbers, averaged (unbiased); 1: none. */
    int medium_splits;
} volpath_settings;

/* Reads `Integrator "volpath"`'s parameters; "exhaustive" runs as "bvh"
 * (the default) with a warning naming its place (to `warn` when not NULL);
 * other names and a negative maxdepth are errors. Does not call
 * params_finish. */
hz_status volpath_settings_from_entity(scene_entity *e, FILE *warn, volpath_settings *out,
                                       hz_error *err);

typedef struct {
    integrator_inputs in;
    volpath_settings settings;
    light_sampler sampler;
    rgb sky; /* the sum of the constant infinite lights' radiance */
    bool image_lights; /* some infinite light has an image (light-sampled, MIS) */
    /* The constant infinite lights (spectral rendering sums their spectra):
     * the first, -1 for none; whether there are more. */
    int sky_light;
    bool sky_lights_many;
    /* The point and spot lights (indices into in.lights), which homogeneous
     * media also light-sample by equiangular sampling along each segment
     * (docs/media.md); NULL and 0 when there are none. */
    size_t *eq_lights;
    size_t eq_light_count;
    /* The shadow caches at settings.shadow_cache, built by the caller
     * (render_scene) over `in`; NULL: every shadow ray is traced. */
    const shadow_caches *caches;
} volpath_scene;

hz_status volpath_scene_init(volpath_scene *out, const integrator_inputs *in,
                             volpath_settings settings, hz_error *err);
void volpath_scene_free(volpath_scene *sc);

/* Radiance along the camera ray `r` (unit direction). `depth` receives the
 * distance to the first opaque surface on the camera ray before any scattering
 * (INFINITY when none). Thread-safe; allocates nothing. */
rgb volpath_li(const volpath_scene *sc, const ray_differential *rd, const spectral_ctx *sp,
               sampler_state *st,
               double *depth, film_surface *vs, integrator_counters *counters);

#endif
