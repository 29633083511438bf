#include "integrator/path.h"

#include <math.h>

path_shadow_ray path_surface_shadow_ray(const geom_hit *h, const light_sample *ls)
{
    path_shadow_ray r = {geometry_leave_origin(h, ls->wi), ls->wi, INFINITY};
    if (!ls->infinite) {
        bool emitter = v3_length_sq(ls->n_light) > 0.0;
        vec3 target = ls->p_light;
        /* Area-light points sit on a surface Embree can hit: lift them off it
         * toward the receiver, like the origin. */
        if (emitter)
            target = geometry_offset_origin(target, ls->n_light, v3_neg(ls->wi));
        r.w = v3_sub(target, r.o);
        /* Only an emitting surface needs the shadow ray to stop short of it. */
        r.tmax = emitter ? 1.0 - GEOMETRY_SHADOW_EPSILON : 1.0;
    }
    return r;
}

bool path_shadow_ray_for_media(const geom_hit *h, const light_sample *ls, path_shadow_ray *r,
                               double *back)
{
    if (!ls->infinite) {
        double dist = v3_length(r->w);
        if (!(dist > 0.0))
            return false;
        r->w = v3_scale(r->w, 1.0 / dist);
        r->tmax *= dist;
    }
    vec3 off = v3_sub(r->o, h->p);
    double wn = fabs(v3_dot(r->w, h->ng));
    double e = v3_length(off) * 16.0;
    if (wn * e > fabs(v3_dot(off, h->ng)))
        e = fabs(v3_dot(off, h->ng)) / wn;
    *back = e;
    return true;
}
