#include "integrator/singlescatter_light.h"

#include <math.h>

#include "core/phase.h"
#include "core/ray.h"
#include "integrator/singlescatter_tracking.h"
#include "integrator/walk.h"

/* Transmittance of the media along o + t w over [t_fill, tmax]; surfaces are
 * searched from tmin on. Hits before t_fill lie behind the point the light
 * arrives at: opaque ones there block nothing and are stepped over;
 * interfaces there still switch the medium (with no medium between them), so
 * that the walk leaves through a boundary that float rounding put just behind
 * the point. With t_fill = 0 this is the plain walk from o. */
static rgb shadow_walk(const singlescatter_scene *vs, vec3 o, vec3 w, double tmin, double t_fill,
                       double tmax, int medium, media_walk *walk)
{
    walk->shadow_rays++;
    rgb T = rgb_grey(1.0);
    ray_walk rw;
    walk_start(&rw, vs->in.geom, o, w, tmin, t_fill, tmax, walk->time, medium,
               WALK_EXACT_ENDS | WALK_CONVEX_START);
    for (walk_segment seg; walk_next(&rw, &seg);) {
        if (seg.opaque) {
            if (seg.h.t >= t_fill)
                return rgb_grey(0.0);
            walk_step_over(&rw);
            continue;
        }
        medium = seg.medium;
        double t_start = seg.t0, t_end = seg.t1;
        if (medium >= 0) {
            struct medium copy; /* `medium` is the index here */
            T = rgb_mul(T, singlescatter_segment_transmittance(
                               vs, walk_medium(&vs->in, medium, walk, &copy), o, w, t_start, t_end,
                               walk));
            if (rgb_is_black(T))
                return T;
        }
        if (!seg.hit)
            return T;
    }
    walk->lost++; /* the walk ends early only at the crossing limit */
    return rgb_grey(0.0);
}

rgb singlescatter_shadow_transmittance(const singlescatter_scene *vs, vec3 o, vec3 w, double tmin,
                                       double tmax, int medium, media_walk *walk)
{
    return shadow_walk(vs, o, w, tmin, 0.0, tmax, medium, walk);
}

/* The shadow ray from scattering point x in medium `mi` toward unit w, to
 * distance tmax. Embree sees x rounded to float: a point within rounding of
 * its medium's boundary can land on the far side, where the ray misses the
 * exit and sees the medium as unbounded (dense media, whose scattering happens
 * within a few free paths of the boundary, went dark: 9% at density scale 1e6,
 * black at 1e9). So surfaces are searched from x - e w, e a margin of
 * PATH_SHADOW_BACKOFF times x's largest coordinate (some 2^7..2^8 float ULPs,
 * far above the rounding even where w meets the boundary at a grazing 1/64),
 * and the medium fills the ray from x on. */
static rgb scatter_shadow(const singlescatter_scene *vs, vec3 x, vec3 w, double tmax, int mi,
                          media_walk *walk)
{
    double e = PATH_SHADOW_BACKOFF * hz_fmax(hz_fmax(fabs(x.x), fabs(x.y)), fabs(x.z));
    return shadow_walk(vs, v3_sub(x, v3_scale(w, e)), w, 0.0, e, tmax + e, mi, walk);
}

/* ---- light arriving at a scattering point ---- */

rgb singlescatter_light_inscattered(const singlescatter_scene *vs, int mi, const light *l, vec3 x,
                                    vec3 wo, sampler_state *u, media_walk *walk)
{
    const medium *m = &vs->in.media[mi];
    const shadow_cache *cache = shadow_caches_get(vs->caches, mi, (size_t)(l - vs->in.lights));
    if (cache) { /* a distant light: one direction, its shadow tabulated */
        vec3 wi = l->distant.w;
        double f = hg_phase(v3_dot(wo, wi), m->g);
        if (rgb_is_black(l->emit) || !(f > 0.0))
            return rgb_grey(0.0);
        rgb E = walk->sp ? light_emit_spectral(l, walk->sp) : l->emit;
        return rgb_scale(rgb_mul(E, shadow_cache_transmittance(cache, x, walk->sp)), f);
    }
    rgb L = rgb_grey(0.0);
    /* More samples of a delta light through deterministic transmittance
     * would repeat the same computation. */
    int n = light_is_delta(l) && !vs->stochastic_shadows ? 1 : vs->settings.light_samples;
    for (int k = 0; k < n; ++k) {
        vec2 uu = light_is_delta(l) ? v2(0.5, 0.5) : sampler_2d(u);
        vec3 wi;
        rgb Li;
        double f, tmax;
        if (l->kind == LIGHT_INFINITE && !light_is_image(l)) {
            /* A constant sky: sampling the phase function leaves only the
             * visibility to estimate (phase / pdf = 1). */
            double pdf;
            wi = hg_sample(wo, m->g, uu, &pdf);
            Li = walk->sp ? light_emit_spectral(l, walk->sp) : l->emit;
            f = 1.0;
            tmax = INFINITY;
        } else {
            light_sample ls;
            if (!light_sample_li(l, x, v3(0.0, 0.0, 0.0), walk->time, uu, &ls) || !(ls.pdf > 0.0))
                continue;
            wi = ls.wi;
            Li = light_spectral(l, ls.L, walk->sp);
            f = hg_phase(v3_dot(wo, wi), m->g) / ls.pdf;
            /* Only an emitting surface needs the shadow ray to stop short. */
            tmax = ls.infinite                     ? INFINITY
                   : v3_length_sq(ls.n_light) > 0.0 ? ls.dist * (1.0 - GEOMETRY_SHADOW_EPSILON)
                                                   : ls.dist;
        }
        if (rgb_is_black(Li) || !(f > 0.0))
            continue;
        rgb T = scatter_shadow(vs, x, wi, tmax, mi, walk);
        L = rgb_add(L, rgb_scale(rgb_mul(Li, T), f / n));
    }
    return L;
}

rgb singlescatter_inscattered(const singlescatter_scene *vs, int mi, vec3 x, vec3 wo,
                              sampler_state *u, media_walk *walk)
{
    rgb L = rgb_grey(0.0);
    for (size_t i = 0; i < vs->in.light_count; ++i)
        L = rgb_add(L, singlescatter_light_inscattered(vs, mi, &vs->in.lights[i], x, wo, u, walk));
    return L;
}
