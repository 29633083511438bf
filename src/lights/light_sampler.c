#include "lights/light_sampler.h"

#include <math.h>
#include <stdlib.h>

hz_status light_sampler_create(light_sampler_kind kind, const light *lights, size_t light_count,
                               double scene_radius, light_sampler *out, hz_error *err)
{
    *out = (light_sampler){.kind = kind};
    size_t n = light_count ? light_count : 1;
    out->index = malloc(n * sizeof *out->index);
    out->cdf = malloc(n * sizeof *out->cdf);
    out->pmf = calloc(n, sizeof *out->pmf);
    if (!out->index || !out->cdf || !out->pmf) {
        light_sampler_free(out);
        return hz_fail(err, "out of memory");
    }
    if (kind == LIGHT_SAMPLER_BVH)
        return light_bvh_build(lights, light_count, &out->bvh, err);
    double total = 0.0;
    for (size_t i = 0; i < light_count; ++i) {
        if (lights[i].kind == LIGHT_INFINITE && !light_is_image(&lights[i]))
            continue; /* a constant sky is reached by escaping paths only */
        double w = 1.0;
        if (kind == LIGHT_SAMPLER_POWER) {
            rgb phi = light_phi(&lights[i], scene_radius);
            w = (phi.r + phi.g + phi.b) / 3.0;
            if (!(w > 0.0) || !isfinite(w))
                w = 0.0;
        }
        out->index[out->count] = i;
        out->cdf[out->count++] = w;
        total += w;
    }
    /* No power anywhere: every light alike (as pbrt-v4). */
    bool uniform = !(total > 0.0);
    if (uniform)
        total = (double)out->count;
    double sum = 0.0;
    for (size_t k = 0; k < out->count; ++k) {
        double p = (uniform ? 1.0 : out->cdf[k]) / total;
        out->pmf[out->index[k]] = p;
        sum += p;
        out->cdf[k] = sum;
    }
    if (out->count > 0)
        out->cdf[out->count - 1] = 1.0;
    return HZ_OK;
}

void light_sampler_free(light_sampler *ls)
{
    free(ls->index);
    free(ls->cdf);
    free(ls->pmf);
    light_bvh_free(&ls->bvh);
    ls->index = NULL;
    ls->cdf = ls->pmf = NULL;
    ls->count = 0;
}

bool light_sampler_sample(const light_sampler *ls, vec3 p, vec3 n, double u, size_t *light,
                          double *pmf)
{
    if (ls->kind == LIGHT_SAMPLER_BVH)
        return light_bvh_sample(&ls->bvh, p, n, u, light, pmf);
    if (ls->count == 0)
        return false;
    size_t lo = 0, hi = ls->count - 1;
    while (lo < hi) { /* first k with cdf[k] > u */
        size_t mid = (lo + hi) / 2;
        if (ls->cdf[mid] > u)
            hi = mid;
        else
            lo = mid + 1;
    }
    /* Lights of zero power have zero-width intervals: never chosen. */
    *light = ls->index[lo];
    *pmf = ls->pmf[*light];
    return *pmf > 0.0;
}
