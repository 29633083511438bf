/* Choosing one light per light sample in path tracing (pbrt-v4's
 * LightSampler): "uniform" (every light alike) or "power" (probability
 * proportional to each light's emitted power, light_phi averaged over RGB, as
 * PowerLightSampler; all powers zero: uniform). For pbrt-v4's default "bvh",
 * haze keeps the BVH sampler's split without its tree: distant lights
 * (unbounded) each get the probability 1 / (number of distant lights + 1 if
 * there is any bounded light), and the bounded lights (point, spot, area)
 * share the rest in proportion to their power. Without that split a distant
 * light's power (π r² L over the scene's whole bounding sphere) starves small
 * bright lamps of samples (docs/differences-from-pbrt.md).
 *
 * Infinite lights are never chosen: volpath (like pbrt-v4, whose uniform
 * infinite light returns no sample when an incomplete pdf is allowed) finds
 * the sky by BSDF and phase-function sampling alone. */
#ifndef HAZE_RENDER_LIGHT_SAMPLER_H
#define HAZE_RENDER_LIGHT_SAMPLER_H

#include <stddef.h>

#include "core/error.h"
#include "render/lights.h"

typedef enum {
    LIGHT_SAMPLER_UNIFORM,
    LIGHT_SAMPLER_POWER,
    LIGHT_SAMPLER_BVH_SPLIT, /* "bvh": distant lights apart, power among the rest */
} light_sampler_kind;

typedef struct {
    light_sampler_kind kind;
    size_t count;   /* lights that can be chosen */
    size_t *index;  /* their indices into the scene's lights */
    double *cdf;    /* count cumulative probabilities, the last exactly 1 */
    double *pmf;    /* per scene light (0 for those never chosen) */
} light_sampler;

/* `scene_radius`: of the scene's bounding sphere (distant lights' power). */
hz_status light_sampler_create(light_sampler_kind kind, const light *lights, size_t light_count,
                               double scene_radius, light_sampler *out, hz_error *err);
void light_sampler_free(light_sampler *ls);

/* The scene index of the light chosen by u in [0, 1), with its probability;
 * false when no light can be chosen. */
bool light_sampler_sample(const light_sampler *ls, double u, size_t *light, double *pmf);

static inline double light_sampler_pmf(const light_sampler *ls, size_t light)
{
    return ls->pmf[light];
}

#endif
