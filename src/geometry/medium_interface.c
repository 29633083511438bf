/* Medium interfaces: boxes around the shapes that change the medium (a
 * shadow ray sure to cross none needs no media), and rays crossing a
 * surface: where the double-precision ray meets a hit's surface, the ray
 * parameter just past it, and the origin of a ray leaving a hit, which
 * geometry_step_past inlines (it runs at every interface crossing). */
#include "core/box.h"
#include "geometry/geometry_types.h"
#include "geometry/medium_interface.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void geom_shape_box(const geom_shape *s, vec3 *lo_out, vec3 *hi_out)
{
    vec3 lo = v3(INFINITY, INFINITY, INFINITY), hi = v3(-INFINITY, -INFINITY, -INFINITY);
    switch (s->kind) {
    case GEOMETRY_SPHERE: {
        double r = s->radius;
        transform_box(&s->space_from_object, v3(-r, -r, -r), v3(r, r, r), &lo, &hi);
        break;
    }
    case GEOMETRY_TRIANGLES:
        for (size_t v = 0; v < s->vertex_count; ++v) {
            const float *f = &s->p[3 * v];
            vec3 p = v3(f[0], f[1], f[2]);
            lo = v3_min(lo, p);
            hi = v3_max(hi, p);
        }
        break;
    case GEOMETRY_CURVES:
        for (size_t i = 0; i < s->segment_count << s->curve_split; ++i) {
            vec3 a, b;
            geometry_curve_bounds(s, (unsigned)i, &a, &b);
            lo = v3_min(lo, a);
            hi = v3_max(hi, b);
        }
        break;
    }
    double pad = 1e-5 * v3_max_component(v3_max(v3_abs(lo), v3_abs(hi))) + 1e-30;
    *lo_out = v3_sub(lo, v3(pad, pad, pad));
    *hi_out = v3_add(hi, v3(pad, pad, pad));
}

/* Beyond this many medium-changing shapes the boxes cost more than they save. */
#define GEOMETRY_MAX_INTERFACE_BOXES 16

hz_status geom_find_interfaces(geometry *g, hz_error *err)
{
    for (size_t o = 0; o < g->object_count; ++o)
        for (size_t i = 0; i < g->objects[o].shape_count; ++i)
            g->interfaces_anywhere |= geom_changes_medium(&g->objects[o].shapes[i]);
    size_t n = 0;
    for (size_t i = 0; i < g->shape_count; ++i)
        if (geom_changes_medium(&g->shapes[i])) {
            n++;
            g->interfaces_anywhere |= g->shapes[i].motion != NULL;
        }
    if (n > GEOMETRY_MAX_INTERFACE_BOXES)
        g->interfaces_anywhere = true;
    if (g->interfaces_anywhere || n == 0)
        return HZ_OK;
    g->interface_boxes = malloc(n * sizeof *g->interface_boxes);
    if (!g->interface_boxes)
        return hz_fail(err, "out of memory");
    for (size_t i = 0; i < g->shape_count; ++i) {
        const geom_shape *s = &g->shapes[i];
        if (!geom_changes_medium(s))
            continue;
        geom_shape_box(s, &g->interface_boxes[g->interface_box_count][0],
                       &g->interface_boxes[g->interface_box_count][1]);
        g->interface_box_count++;
    }
    return HZ_OK;
}

bool geometry_may_cross_interface(const geometry *g, vec3 o, vec3 d, double tmax)
{
    if (g->interfaces_anywhere)
        return true;
    for (size_t i = 0; i < g->interface_box_count; ++i) {
        double t0 = 0.0, t1 = tmax;
        if (box_clip_ray(o, d, g->interface_boxes[i][0], g->interface_boxes[i][1], &t0, &t1))
            return true;
    }
    return false;
}

static float offset_coord(float p, float n)
{
    const float origin = 1.0f / 32.0f, float_scale = 1.0f / 65536.0f, int_scale = 256.0f;
    if (fabsf(p) < origin)
        return p + float_scale * n;
    int32_t of = (int32_t)(int_scale * n);
    int32_t bits;
    memcpy(&bits, &p, sizeof bits);
    bits += p < 0.0f ? -of : of;
    float r;
    memcpy(&r, &bits, sizeof r);
    return r;
}

vec3 geometry_leave_origin(const geom_hit *h, vec3 w)
{
    vec3 n = v3_dot(h->ng, w) < 0.0 ? v3_neg(h->ng) : h->ng;
    vec3 p = h->p;
    if (h->p_error > 0.0)
        p = v3_add(p, v3_scale(n, h->p_error * (fabs(n.x) + fabs(n.y) + fabs(n.z))));
    return geometry_offset_origin(p, n, w);
}

vec3 geometry_offset_origin(vec3 p, vec3 n, vec3 w)
{
    if (v3_dot(n, w) < 0.0)
        n = v3_neg(n);
    return v3(offset_coord((float)p.x, (float)n.x), offset_coord((float)p.y, (float)n.y),
              offset_coord((float)p.z, (float)n.z));
}

double geometry_step_past(const geom_hit *h, vec3 o, vec3 d)
{
    double t_hit = v3_dot(v3_sub(h->p, o), d) / v3_dot(d, d);
    double dn = v3_dot(d, h->ng);
    vec3 past = geometry_leave_origin(h, d);
    double dt = dn != 0.0 ? v3_dot(v3_sub(past, h->p), h->ng) / dn : 0.0;
    /* Past Embree's own (float) t of the hit too, whatever rounding put
     * h->p at. */
    return hz_fmax(hz_fmax(t_hit + dt, hz_next_up(t_hit)), hz_next_up(h->t));
}

double geometry_crossing_t(const geom_hit *h, vec3 o, vec3 w)
{
    double dn = v3_dot(w, h->ng);
    vec3 off = v3_sub(h->p, v3_add(o, v3_scale(w, h->t)));
    double c = dn != 0.0 ? v3_dot(off, h->ng) / dn : 0.0;
    /* A correction beyond float rounding (a ray grazing the surface) keeps h->t. */
    double scale = hz_fmax(hz_fmax(fabs(h->p.x), fabs(h->p.y)), hz_fmax(fabs(h->p.z), fabs(h->t)));
    return fabs(c) <= 0x1p-12 * scale ? h->t + c : h->t;
}
