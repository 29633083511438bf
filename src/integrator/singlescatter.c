#define _POSIX_C_SOURCE 200809L
#include "integrator/singlescatter.h"
#include "integrator/visible_surface.h"

#include <math.h>

#include <string.h>

#include "core/clock.h"
#include "integrator/singlescatter_light.h"
#include "integrator/singlescatter_media.h"
#include "integrator/walk.h"
#include "materials/bsdf.h"

/* The infinite lights seen along w (light sampling of image lights is not
 * MIS-weighted here: the path that escapes is the camera ray's or a
 * transmitted one, which light sampling does not cover). */
static rgb sky(const singlescatter_scene *sc, vec3 o, vec3 w, const spectral_ctx *sp)
{
    rgb L = rgb_grey(0.0);
    for (size_t i = 0; i < sc->in.light_count; ++i)
        if (sc->in.lights[i].kind == LIGHT_INFINITE) {
            const light *l = &sc->in.lights[i];
            L = rgb_add(L, light_spectral(l, light_infinite_le(l, o, w), sp));
        }
    return L;
}

/* The shadow ray of light sample `ls` from surface hit `h`: 1 or 0 without
 * media, the transmittance through media and interfaces with them. */
static rgb shadow(const singlescatter_scene *sc, const geom_hit *h, int medium,
                  const light_sample *ls, media_walk *walk, integrator_counters *counters)
{
    path_shadow_ray sr = path_surface_shadow_ray(h, ls);
    int start = sc->in.medium_count == 0 ? -1 : geometry_medium_after(h, sr.w, medium);
    if (path_shadow_ray_unattenuated(&sc->in, start, &sr, walk->time, &walk->majorant_steps)) {
        counters->shadow_rays++;
        return rgb_grey(geometry_occluded(sc->in.geom, sr.o, sr.w, sr.tmax, walk->time) ? 0.0 : 1.0);
    }
    double e;
    if (!path_shadow_ray_for_media(h, ls, &sr, &e))
        return rgb_grey(0.0);
    uint64_t t0 = counters->timed ? hz_clock_ns() : 0;
    rgb T = singlescatter_shadow_transmittance(sc, v3_sub(sr.o, v3_scale(sr.w, e)), sr.w, e,
                                               sr.tmax + e, start, walk);
    if (counters->timed)
        counters->media_ns += hz_clock_ns() - t0;
    return T;
}

/* Direct light through the BSDF of the material at the first hit: a light
 * sample per light, without the paths volpath continues (a perfect mirror or
 * clear glass passes no light sample: black). Diffuse surfaces reflect on
 * the side of wo, as pbrt-v4's two-sided diffuse BSDF. The sky is sampled
 * around the normal on wo's side; through a surface that transmits, on
 * either side with probability 1/2. */
static rgb direct_bsdf(const singlescatter_scene *sc, const geom_hit *h, int medium, vec3 wo,
                       const material *mat, sampler_state *st, media_walk *walk,
                       integrator_counters *counters)
{
    /* Diffuse surfaces, the common case, skip the BSDF's dispatch: with ns on
     * wo's side, f is r / pi wherever cos > 0. */
    bool diffuse = mat->kind == MATERIAL_DIFFUSE;
    bsdf b;
    vec3 n_shading = geometry_shading_normal(h, mat);
    if (!bsdf_from_material(mat, n_shading, h->dpdu, h->v, &b) || !(diffuse || bsdf_is_non_specular(&b)))
        return rgb_grey(0.0);
    vec3 ns = v3_dot(n_shading, wo) < 0.0 ? v3_neg(n_shading) : n_shading;
    bool transmits = material_transmits(mat);
    rgb L = rgb_grey(0.0);
    for (size_t i = 0; i < sc->in.light_count; ++i) {
        const light *l = &sc->in.lights[i];
        vec2 u = light_is_delta(l) ? v2(0.5, 0.5) : sampler_2d(st);
        vec3 side = ns;
        bool both = transmits && l->kind == LIGHT_INFINITE && !light_is_image(l);
        if (both) { /* half the samples on each side */
            side = u.x < 0.5 ? ns : v3_neg(ns);
            u.x = u.x < 0.5 ? 2.0 * u.x : 2.0 * u.x - 1.0;
        }
        light_sample ls;
        if (!light_sample_li(l, h->p, side, walk->time, u, &ls) || ls.pdf <= 0.0)
            continue;
        ls.L = light_spectral(l, ls.L, walk->sp);
        if (both)
            ls.pdf *= 0.5;
        double cos_theta = v3_dot(ns, ls.wi);
        rgb f = !diffuse          ? bsdf_f(&b, wo, ls.wi)
                : cos_theta > 0.0 ? rgb_scale(b.reflectance, HZ_INV_PI)
                                  : rgb_grey(0.0);
        if (rgb_is_black(f))
            continue;
        rgb T = shadow(sc, h, medium, &ls, walk, counters);
        if (rgb_is_black(T))
            continue;
        L = rgb_add(L, rgb_scale(rgb_mul(rgb_mul(f, ls.L), T), fabs(cos_theta) / ls.pdf));
    }
    return L;
}

/* The light leaving the camera ray's opaque hit h toward the camera: its
 * emission and the direct light its BSDF reflects. */
static rgb surface_li(const singlescatter_scene *sc, const ray_differential *rd, geom_hit *h,
                      int medium, sampler_state *st, media_walk *walk, film_surface *vs,
                      integrator_counters *counters)
{
    vec3 wo = v3_normalize(v3_neg(rd->r.d));
    rgb Ls = rgb_grey(0.0);
    if (h->shape->area_light >= 0) {
        const light *l = &sc->in.lights[h->shape->area_light];
        Ls = light_spectral(l, light_area_le(l, h->ng, wo, v2(h->u, h->v), h->p), walk->sp);
    }
    if (rd->has_differentials)
        geometry_hit_footprint(h, rd->rx_o, rd->rx_d, rd->ry_o, rd->ry_d);
    if (vs)
        visible_surface_at(h, rd, vs);
    material scratch;
    const material *mat = material_spectral(geometry_material_at(h, wo, &scratch), walk->sp,
                                            &scratch);
    switch (mat->kind) {
    case MATERIAL_DIFFUSE:
    case MATERIAL_CONDUCTOR:
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_DIFFUSE_TRANSMISSION:
    case MATERIAL_HAIR:
    case MATERIAL_MEASURED:
        Ls = rgb_add(Ls, direct_bsdf(sc, h, medium, wo, mat, st, walk, counters));
        break;
    case MATERIAL_MIX: /* material_at resolved it */
    case MATERIAL_INTERFACE:
        break;
    }
    return Ls;
}

rgb singlescatter_li(const singlescatter_scene *sc, const ray_differential *rd,
                     const spectral_ctx *sp, sampler_state *st, double *depth, film_surface *vs,
                     integrator_counters *counters)
{
    const ray *r = &rd->r;
    counters->camera_rays++;
    *depth = INFINITY;
    vec3 o = r->o, d = r->d;
    media_walk walk = {.time = r->time, .sp = sp};
    /* The walk's rng is seeded once the ray meets something: a camera ray
     * from vacuum that misses everything (most of a small subject's frame)
     * skips the hashing. The dimension is taken now, as before. */
    int seed_dim = sc->in.medium_count > 0 ? sampler_reserve_dim(st) : -1;
    rgb beta = rgb_grey(1.0), L = rgb_grey(0.0);
    ray_walk rw;
    walk_start(&rw, sc->in.geom, o, d, 0.0, 0.0, INFINITY, r->time, r->medium,
               sc->in.medium_count > 0 ? WALK_EXACT_ENDS : 0u);
    for (walk_segment seg; walk_next(&rw, &seg);) {
        if (seed_dim >= 0 && (seg.hit || seg.medium >= 0)) {
            walk.r = rng_seeded(sampler_stream_seed_at(st, seed_dim));
            seed_dim = -1;
        }
        int medium = seg.medium;
        double t_start = seg.t0, t_hit = seg.t1;
        if (medium >= 0) {
            uint64_t t0 = counters->timed ? hz_clock_ns() : 0;
            singlescatter_segment(sc, medium, o, d, t_start, t_hit, &beta, &L, st, &walk);
            if (counters->timed)
                counters->media_ns += hz_clock_ns() - t0;
            if (rgb_is_black(beta))
                break;
        }
        if (!seg.hit) {
            L = rgb_add(L, rgb_mul(beta, sky(sc, o, d, sp)));
            break;
        }
        if (seg.opaque) {
            *depth = v3_length(v3_sub(seg.h.p, r->o));
            rgb Ls = surface_li(sc, rd, &seg.h, medium, st, &walk, vs, counters);
            L = rgb_add(L, rgb_mul(beta, Ls));
            break;
        }
    }
    walk.lost += walk_lost(&rw);
    counters->shadow_rays += walk.shadow_rays;
    counters->density_lookups += walk.lookups;
    counters->majorant_steps += walk.majorant_steps;
    counters->lost_paths += walk.lost;
    return L;
}
