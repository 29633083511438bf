#include "render/integrator.h"

#include <math.h>

static rgb sky(const integrator_scene *sc)
{
    rgb L = rgb_grey(0.0);
    for (size_t i = 0; i < sc->light_count; ++i)
        if (sc->lights[i].kind == LIGHT_INFINITE)
            L = rgb_add(L, sc->lights[i].emit);
    return L;
}

static bool unoccluded(const integrator_scene *sc, const geom_hit *h, const light_sample *ls,
                       render_counters *counters)
{
    counters->shadow_rays++;
    vec3 o = geometry_offset_origin(h->p, h->ng, ls->wi);
    if (ls->infinite)
        return !geometry_occluded(sc->geom, o, ls->wi, INFINITY);
    vec3 target = ls->p_light;
    /* Area-light points sit on a surface Embree can hit: lift them off it
     * toward the receiver, like the origin. */
    if (v3_length_sq(ls->n_light) > 0.0)
        target = geometry_offset_origin(target, ls->n_light, v3_neg(ls->wi));
    return !geometry_occluded(sc->geom, o, v3_sub(target, o), 1.0 - INTEGRATOR_SHADOW_EPSILON);
}

static rgb direct_diffuse(const integrator_scene *sc, const geom_hit *h, vec3 wo, rgb reflectance,
                          sampler_state *st, render_counters *counters)
{
    /* pbrt-v4's diffuse BSDF reflects on both sides: work on the side of wo. */
    vec3 ns = v3_dot(h->ns, wo) < 0.0 ? v3_neg(h->ns) : h->ns;
    rgb f = rgb_scale(reflectance, HZ_INV_PI);
    rgb L = rgb_grey(0.0);
    for (size_t i = 0; i < sc->light_count; ++i) {
        const light *l = &sc->lights[i];
        /* Non-delta lights always take their 2D sample, hit or not, so the
         * sampler dimensions do not depend on what happened before. */
        vec2 u = light_is_delta(l) ? v2(0.5, 0.5) : sampler_2d(st);
        light_sample ls;
        if (!light_sample_li(l, h->p, ns, u, &ls))
            continue;
        double cos_theta = v3_dot(ns, ls.wi);
        if (cos_theta <= 0.0 || ls.pdf <= 0.0)
            continue;
        if (!unoccluded(sc, h, &ls, counters))
            continue;
        L = rgb_add(L, rgb_scale(rgb_mul(f, ls.L), cos_theta / ls.pdf));
    }
    return L;
}

/* The ray parameter just past an interface hit: where the line crosses the
 * origin offset of the far side. Staying on the same line (rather than
 * starting a new ray off the surface) keeps what lies behind exactly where
 * it would be without the interface. */
static double step_past(const geom_hit *h, vec3 o, vec3 d)
{
    double t_hit = v3_dot(v3_sub(h->p, o), d) / v3_dot(d, d);
    double dn = v3_dot(d, h->ng);
    vec3 past = geometry_offset_origin(h->p, h->ng, d);
    double dt = dn != 0.0 ? v3_dot(v3_sub(past, h->p), h->ng) / dn : 0.0;
    return fmax(t_hit + dt, nextafter(t_hit, INFINITY));
}

rgb integrator_li(const integrator_scene *sc, const ray *r, sampler_state *st, double *depth,
                  render_counters *counters)
{
    counters->camera_rays++;
    *depth = INFINITY;
    vec3 o = r->o, d = r->d;
    geom_hit h;
    double tmin = 0.0;
    for (int crossing = 0;; ++crossing) {
        if (!geometry_intersect(sc->geom, o, d, tmin, INFINITY, &h))
            return sky(sc);
        if (h.shape->material->kind != MATERIAL_INTERFACE)
            break;
        if (crossing == INTEGRATOR_MAX_CROSSINGS)
            return rgb_grey(0.0);
        tmin = step_past(&h, o, d);
    }
    *depth = v3_length(v3_sub(h.p, r->o));

    vec3 wo = v3_normalize(v3_neg(d));
    rgb L = rgb_grey(0.0);
    if (h.shape->area_light >= 0)
        L = light_area_le(&sc->lights[h.shape->area_light], h.ng, wo);
    switch (h.shape->material->kind) {
    case MATERIAL_DIFFUSE:
        if (rgb_is_black(h.shape->material->reflectance))
            break;
        L = rgb_add(L, direct_diffuse(sc, &h, wo, h.shape->material->reflectance, st, counters));
        break;
    case MATERIAL_INTERFACE:
        break;
    }
    return L;
}
