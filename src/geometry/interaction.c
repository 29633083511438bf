/* What shading asks of a hit (pbrt-v4's SurfaceInteraction): its footprint
 * on the screen, the material there, and the shading normal under bump and
 * normal maps. (Where a ray leaving it starts: medium_interface.c.) */
#include "geometry/geometry.h"

#include <math.h>

/* a b - c d */
static double diff_products(double a, double b, double c, double d)
{
    return a * b - c * d;
}

static double clamp_derivative(double x)
{
    return isfinite(x) ? hz_clamp(x, -1e8, 1e8) : 0.0;
}

bool geometry_hit_dpdxy(const geom_hit *h, vec3 rx_o, vec3 rx_d, vec3 ry_o, vec3 ry_d,
                        vec3 *dpdx, vec3 *dpdy)
{
    vec3 n = h->ng;
    double nx = v3_dot(n, rx_d), ny = v3_dot(n, ry_d);
    *dpdx = *dpdy = v3(0.0, 0.0, 0.0);
    if (nx == 0.0 || ny == 0.0)
        return false;
    double d = -v3_dot(n, h->p);
    vec3 px = v3_add(rx_o, v3_scale(rx_d, (-v3_dot(n, rx_o) - d) / nx));
    vec3 py = v3_add(ry_o, v3_scale(ry_d, (-v3_dot(n, ry_o) - d) / ny));
    *dpdx = v3_sub(px, h->p);
    *dpdy = v3_sub(py, h->p);
    return true;
}

void geometry_hit_set_footprint(geom_hit *h, vec3 dpdx, vec3 dpdy)
{
    h->dpdx = dpdx;
    h->dpdy = dpdy;
    if (!h->shape->textured)
        return;
    double a00 = v3_dot(h->dpdu, h->dpdu), a01 = v3_dot(h->dpdu, h->dpdv);
    double a11 = v3_dot(h->dpdv, h->dpdv);
    double inv = 1.0 / diff_products(a00, a11, a01, a01);
    inv = isfinite(inv) ? inv : 0.0;
    double b0x = v3_dot(h->dpdu, dpdx), b1x = v3_dot(h->dpdv, dpdx);
    double b0y = v3_dot(h->dpdu, dpdy), b1y = v3_dot(h->dpdv, dpdy);
    h->dudx = clamp_derivative(diff_products(a11, b0x, a01, b1x) * inv);
    h->dvdx = clamp_derivative(diff_products(a00, b1x, a01, b0x) * inv);
    h->dudy = clamp_derivative(diff_products(a11, b0y, a01, b1y) * inv);
    h->dvdy = clamp_derivative(diff_products(a00, b1y, a01, b0y) * inv);
}

void geometry_hit_footprint(geom_hit *h, vec3 rx_o, vec3 rx_d, vec3 ry_o, vec3 ry_d)
{
    vec3 dpdx, dpdy;
    if (h->shape->textured && geometry_hit_dpdxy(h, rx_o, rx_d, ry_o, ry_d, &dpdx, &dpdy))
        geometry_hit_set_footprint(h, dpdx, dpdy);
}

const material *geometry_material_at(const geom_hit *h, vec3 wo, material *scratch)
{
    if (!h->shape->textured)
        return material_at(h->shape->material, h->p, wo, NULL);
    texture_ctx c = {.u = h->u, .v = h->v, .p = h->p, .dudx = h->dudx, .dudy = h->dudy,
                     .dvdx = h->dvdx, .dvdy = h->dvdy, .dpdx = h->dpdx, .dpdy = h->dpdy,
                     .n = h->ng};
    return material_textured(material_at(h->shape->material, h->p, wo, &c), &c, scratch);
}

vec3 geometry_shading_normal(const geom_hit *h, const material *m)
{
    if (!m->displacement && !m->normal_map)
        return h->ns;
    /* pbrt-v4's shading frame: a mesh with normals takes ss = (ns x dpdu) x
     * ns and ts = ns x dpdu; otherwise dp/du and dp/dv themselves. */
    vec3 ss = h->dpdu, ts = h->dpdv;
    if (h->shape->kind == GEOMETRY_TRIANGLES && h->shape->n) {
        vec3 t = v3_cross(h->ns, h->dpdu);
        if (v3_length_sq(t) > 0.0) {
            ss = v3_cross(t, h->ns);
            ts = t;
        } else {
            v3_basis(h->ns, &ss, &ts);
        }
    }
    if (m->normal_map) {
        /* pbrt-v4's NormalMap: the image's (2 rgb - 1), normalised, in the
         * frame (dp/du, n x dp/du, n) of the shading geometry; looked up
         * without a footprint, at (u, 1 - v), repeated. */
        texture_ctx c0 = {.u = h->u, .v = h->v, .p = h->p, .n = h->ng};
        rgb t = texture_eval(m->normal_map, &c0);
        vec3 l = v3(2.0 * t.r - 1.0, 2.0 * t.g - 1.0, 2.0 * t.b - 1.0);
        vec3 x = v3_sub(ss, v3_scale(h->ns, v3_dot(ss, h->ns)));
        if (!(v3_length_sq(l) > 0.0) || !(v3_length_sq(x) > 0.0))
            return h->ns;
        x = v3_normalize(x);
        l = v3_normalize(l);
        vec3 n = v3_add(v3_add(v3_scale(x, l.x), v3_scale(v3_cross(h->ns, x), l.y)),
                        v3_scale(h->ns, l.z));
        if (!v3_is_finite(n) || !(v3_length_sq(n) > 0.0))
            return h->ns;
        n = v3_normalize(n);
        return v3_dot(n, h->ng) < 0.0 ? v3_neg(n) : n;
    }
    texture_ctx c = {.u = h->u, .v = h->v, .p = h->p, .dudx = h->dudx, .dudy = h->dudy,
                     .dvdx = h->dvdx, .dvdy = h->dvdy, .dpdx = h->dpdx, .dpdy = h->dpdy,
                     .n = h->ng};
    double du = 0.5 * (fabs(h->dudx) + fabs(h->dudy));
    double dv = 0.5 * (fabs(h->dvdx) + fabs(h->dvdy));
    du = du == 0.0 ? 0.0005 : du;
    dv = dv == 0.0 ? 0.0005 : dv;
    double d0 = texture_eval_float(m->displacement, &c);
    texture_ctx cu = c, cv = c;
    cu.u += du;
    cu.p = v3_add(h->p, v3_scale(ss, du));
    cv.v += dv;
    cv.p = v3_add(h->p, v3_scale(ts, dv));
    double d_u = texture_eval_float(m->displacement, &cu);
    double d_v = texture_eval_float(m->displacement, &cv);
    vec3 dpdu = v3_add(ss, v3_scale(h->ns, (d_u - d0) / du));
    vec3 dpdv = v3_add(ts, v3_scale(h->ns, (d_v - d0) / dv));
    vec3 n = v3_cross(dpdu, dpdv);
    if (!(v3_length_sq(n) > 0.0) || !v3_is_finite(n))
        return h->ns;
    n = v3_normalize(n);
    return v3_dot(n, h->ng) < 0.0 ? v3_neg(n) : n;
}
