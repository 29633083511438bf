/* Choosing one light per light sample in path tracing (pbrt-v4's
 * LightSampler): "uniform" (every light alike), "power" (probability
 * proportional to each light's emitted power, light_phi averaged over RGB, as
 * PowerLightSampler; all powers zero: uniform) or "bvh" (pbrt-v4's default:
 * light_bvh.h, which depends on the shading point).
 *
 * Infinite lights are never chosen: volpath (like pbrt-v4, whose uniform
 * infinite light returns no sample when an incomplete pdf is allowed) finds
 * the sky by BSDF and phase-function sampling alone. */
#ifndef HAZE_LIGHTS_LIGHT_SAMPLER_H
#define HAZE_LIGHTS_LIGHT_SAMPLER_H

#include <stddef.h>

#include "core/error.h"
#include "lights/light_bvh.h"
#include "lights/lights.h"

typedef enum { LIGHT_SAMPLER_UNIFORM, LIGHT_SAMPLER_POWER, LIGHT_SAMPLER_BVH } light_sampler_kind;

typedef struct {
    light_sampler_kind kind;
    size_t count;   /* lights that can be chosen */
    size_t *index;  /* their indices into the scene's lights */
    double *cdf;    /* count cumulative probabilities, the last exactly 1 */
    double *pmf;    /* per scene light (0 for those never chosen) */
    light_bvh bvh;  /* LIGHT_SAMPLER_BVH only */
} light_sampler;

/* `scene_radius`: of the scene's bounding sphere (distant lights' power). */
hz_status light_sampler_create(light_sampler_kind kind, const light *lights, size_t light_count,
                               double scene_radius, light_sampler *out, hz_error *err);
void light_sampler_free(light_sampler *ls);

/* The scene index of the light chosen by u in [0, 1) for shading point p
 * with unit normal n (zero in a medium), with its probability; false when no
 * light can be chosen. */
bool light_sampler_sample(const light_sampler *ls, vec3 p, vec3 n, double u, size_t *light,
                          double *pmf);

/* The probability that light_sampler_sample(ls, p, n, ..) chooses `light`. */
static inline double light_sampler_pmf(const light_sampler *ls, vec3 p, vec3 n, size_t light)
{
    if (ls->kind == LIGHT_SAMPLER_BVH)
        return light_bvh_pmf(&ls->bvh, p, n, light);
    return ls->pmf[light];
}

#endif
