/* Where a hit lies and what the surface is like there, per kind of shape, as
 * pbrt-v4's shapes report it: the point in double on the surface Embree
 * tested, the geometric and shading normals with pbrt-v4's orientation
 * rules, and (u, v) with dp/du and dp/dv. */
#include "geometry/surface_hit.h"

#include <assert.h>
#include <math.h>
#include <string.h>

void geom_sphere_uv(const geom_shape *s, vec3 po, geom_hit *hit)
{
    double r = s->radius, phi = atan2(po.y, po.x);
    if (phi < 0.0)
        phi += 2.0 * HZ_PI;
    double th_min = acos(hz_clamp(fmin(s->zmin, s->zmax) / r, -1.0, 1.0));
    double th_max = acos(hz_clamp(s->zmax / r, -1.0, 1.0));
    double theta = acos(hz_clamp(po.z / r, -1.0, 1.0));
    hit->dudx = hit->dudy = hit->dvdx = hit->dvdy = 0.0;
    hit->dpdx = hit->dpdy = v3(0.0, 0.0, 0.0);
    hit->u = phi / s->phimax;
    hit->v = (theta - th_min) / (th_max - th_min);
    double zr = sqrt(po.x * po.x + po.y * po.y);
    double cos_phi = zr > 0.0 ? po.x / zr : 1.0, sin_phi = zr > 0.0 ? po.y / zr : 0.0;
    hit->dpdu = transform_vector(&s->space_from_object,
                                 v3(-s->phimax * po.y, s->phimax * po.x, 0.0));
    hit->dpdv = transform_vector(&s->space_from_object,
                                 v3_scale(v3(po.z * cos_phi, po.z * sin_phi, -r * sin(theta)),
                                          th_max - th_min));
}

vec2 geometry_sphere_uv(const geom_shape *s, vec3 po)
{
    geom_hit h;
    geom_sphere_uv(s, po, &h);
    return v2(h.u, h.v);
}

void geom_triangle_corner_uv(const geom_shape *s, unsigned prim, double uv[3][2])
{
    const uint32_t *tri = &s->indices[3 * prim];
    static const double defaults[3][2] = {{0, 0}, {1, 0}, {1, 1}};
    memcpy(uv, defaults, sizeof defaults);
    if (s->uv) {
        for (int i = 0; i < 3; ++i) {
            uv[i][0] = s->uv[2 * tri[i]];
            uv[i][1] = s->uv[2 * tri[i] + 1];
        }
    } else if (s->quads && (prim & 1u)) {
        /* p00 p11 p01 */
        uv[1][0] = 1, uv[1][1] = 1, uv[2][0] = 0, uv[2][1] = 1;
    }
}

/* pbrt-v4's triangle parameters: the mesh's uv (or its defaults, a
 * bilinear patch's for a quad's halves) at barycentrics (b1, b2). */
static void triangle_uv(const geom_shape *s, unsigned prim, double b1, double b2, vec3 p0,
                        vec3 p1, vec3 p2, geom_hit *hit)
{
    double uv[3][2];
    geom_triangle_corner_uv(s, prim, uv);
    double b0 = 1.0 - b1 - b2;
    hit->dudx = hit->dudy = hit->dvdx = hit->dvdy = 0.0;
    hit->dpdx = hit->dpdy = v3(0.0, 0.0, 0.0);
    hit->u = b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0];
    hit->v = b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1];
    double d02[2] = {uv[0][0] - uv[2][0], uv[0][1] - uv[2][1]};
    double d12[2] = {uv[1][0] - uv[2][0], uv[1][1] - uv[2][1]};
    vec3 dp02 = v3_sub(p0, p2), dp12 = v3_sub(p1, p2);
    double det = d02[0] * d12[1] - d02[1] * d12[0];
    if (fabs(det) > 1e-12) {
        double inv = 1.0 / det;
        hit->dpdu = v3_scale(v3_sub(v3_scale(dp02, d12[1]), v3_scale(dp12, d02[1])), inv);
        hit->dpdv = v3_scale(v3_sub(v3_scale(dp12, d02[0]), v3_scale(dp02, d12[0])), inv);
        if (v3_length_sq(v3_cross(hit->dpdu, hit->dpdv)) > 0.0)
            return;
    }
    /* Degenerate uv: any frame of the plane (as pbrt-v4). */
    v3_basis(v3_normalize(v3_cross(dp02, dp12)), &hit->dpdu, &hit->dpdv);
}

/* A curve hit as pbrt-v4's Curve::Intersect reports it, at Embree's curve
 * parameter u of segment `prim` and its t: dp/du from the Bezier; dp/dv
 * across the width in the plane facing the ray (a ribbon: across its
 * normal, the width foreshortened by it); v from the side and distance of
 * the point to the centre line (0.5 on it); a "cylinder" turns dp/dv about
 * dp/du by -lerp(v, -90, 90) degrees, so that the normal cross(dp/du, dp/dv)
 * rounds over the width. */
double geom_curve_at(const geom_shape *s, unsigned prim, double u, vec3 o, vec3 d, double t,
                     geom_hit *hit)
{
    size_t seg = prim >> s->curve_split;
    const double *c = &s->curve_cp[12 * seg];
    vec3 P[4];
    for (int i = 0; i < 4; ++i)
        P[i] = v3(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
    u = hz_clamp(u, 0.0, 1.0);
    double a = 1.0 - u;
    vec3 centre = v3_add(v3_add(v3_scale(P[0], a * a * a), v3_scale(P[1], 3.0 * a * a * u)),
                         v3_add(v3_scale(P[2], 3.0 * a * u * u), v3_scale(P[3], u * u * u)));
    vec3 dpdu = v3_scale(v3_add(v3_add(v3_scale(v3_sub(P[1], P[0]), a * a),
                                       v3_scale(v3_sub(P[2], P[1]), 2.0 * a * u)),
                                v3_scale(v3_sub(P[3], P[2]), u * u)),
                         3.0);
    if (!(v3_length_sq(dpdu) > 0.0))
        dpdu = v3_sub(P[3], P[0]);
    hit->p = v3_add(o, v3_scale(d, t));
    double width = geometry_curve_width(s, seg, u);
    vec3 dn = v3_normalize(d);
    vec3 across = v3_cross(dn, dpdu);
    across = v3_length_sq(across) > 0.0 ? v3_normalize(across) : v3(0.0, 0.0, 0.0);
    vec3 n_ribbon = v3(0.0, 0.0, 0.0);
    if (s->curve == CURVE_RIBBON) {
        n_ribbon = geometry_curve_ribbon_normal(s, seg, u);
        width *= fabs(v3_dot(n_ribbon, dn));
    }
    /* pbrt-v4's v: the whole distance from the ray to the curve point in
     * the plane facing the ray, on the side `across` tells. */
    vec3 off = v3_sub(hit->p, centre);
    off = v3_sub(off, v3_scale(dn, v3_dot(off, dn)));
    double dist = v3_length(off);
    double v = width > 0.0 ? 0.5 + (v3_dot(off, across) < 0.0 ? -dist : dist) / width : 0.5;
    v = hz_clamp(v, 0.0, 1.0);
    vec3 dpdv;
    if (s->curve == CURVE_RIBBON) {
        vec3 x = v3_cross(n_ribbon, dpdu);
        dpdv = v3_scale(v3_length_sq(x) > 0.0 ? v3_normalize(x) : across, width);
    } else {
        dpdv = v3_scale(across, width);
        if (s->curve == CURVE_CYLINDER) {
            double phi = -(-90.0 + 180.0 * v) * HZ_PI / 180.0;
            vec3 axis = v3_normalize(dpdu);
            dpdv = v3_add(v3_scale(dpdv, cos(phi)), v3_scale(v3_cross(axis, dpdv), sin(phi)));
        }
    }
    vec3 n = v3_cross(dpdu, dpdv);
    n = v3_length_sq(n) > 0.0 ? v3_normalize(n) : v3_neg(dn);
    hit->ng = hit->ns = s->flip_normal ? v3_neg(n) : n;
    hit->p_error = width;
    if (s->hit_uv) {
        hit->dudx = hit->dudy = hit->dvdx = hit->dvdy = 0.0;
        hit->dpdx = hit->dpdy = v3(0.0, 0.0, 0.0);
        hit->u = u;
        hit->v = v;
        hit->dpdu = dpdu;
        hit->dpdv = dpdv;
    }
    return v;
}

void geom_surface_at(const geom_shape *s, unsigned prim, double u, double v, vec3 o, vec3 d,
                     double t, geom_hit *hit)
{
    hit->p_error = 0.0;
    if (s->kind == GEOMETRY_CURVES) {
        geom_curve_at(s, prim, u, o, d, t, hit);
        return;
    }
    if (s->kind == GEOMETRY_SPHERE) {
        transform object_from_space = transform_inverse(s->space_from_object);
        vec3 po = transform_point(&object_from_space, v3_add(o, v3_scale(d, t)));
        /* Reproject onto the sphere, as pbrt-v4 does, to remove the error of t. */
        po = v3_scale(po, s->radius / v3_length(po));
        hit->p = transform_point(&s->space_from_object, po);
        vec3 n = v3_normalize(transform_normal(&s->space_from_object, po));
        hit->ng = hit->ns = s->flip_normal ? v3_neg(n) : n;
        if (s->hit_uv)
            geom_sphere_uv(s, po, hit);
        return;
    }
    const uint32_t *tri = &s->indices[3 * prim];
    vec3 p0 = geom_vertex(s, tri[0]), p1 = geom_vertex(s, tri[1]), p2 = geom_vertex(s, tri[2]);
    double b0 = 1.0 - u - v;
    vec3 n = v3_cross(v3_sub(p0, p2), v3_sub(p1, p2));
    double dn = v3_dot(d, n);
    if (dn != 0.0) {
        /* Intersect the plane of Embree's float vertices in double: the
         * point lies on the surface Embree tested and on the double ray.
         * Embree's float barycentrics would be off by ~1e-6 of the
         * triangle's size, which shows on large triangles. */
        hit->p = v3_add(o, v3_scale(d, v3_dot(v3_sub(p2, o), n) / dn));
    } else {
        hit->p = v3_add(v3_add(v3_scale(p0, b0), v3_scale(p1, u)), v3_scale(p2, v));
    }
    if (s->hit_uv)
        triangle_uv(s, prim, u, v, p0, p1, p2, hit);
    vec3 ng = v3_normalize(n);
    if (s->flip_normal)
        ng = v3_neg(ng);
    hit->ng = hit->ns = ng;
    if (s->n) {
        const double *n0 = &s->n[3 * tri[0]], *n1 = &s->n[3 * tri[1]], *n2 = &s->n[3 * tri[2]];
        vec3 ns = v3_add(v3_add(v3_scale(v3(n0[0], n0[1], n0[2]), b0),
                                v3_scale(v3(n1[0], n1[1], n1[2]), u)),
                         v3_scale(v3(n2[0], n2[1], n2[2]), v));
        if (v3_length_sq(ns) > 0.0) {
            hit->ns = v3_normalize(ns);
            /* pbrt-v4: given normals are authoritative for orientation. */
            if (v3_dot(hit->ng, hit->ns) < 0.0)
                hit->ng = v3_neg(hit->ng);
        }
    }
}

void geometry_triangle_point(const geom_shape *s, unsigned prim, double u, double v,
                             geom_hit *out)
{
    assert(s->kind == GEOMETRY_TRIANGLES);
    out->shape = s;
    out->prim = prim;
    out->t = 0.0;
    geom_surface_at(s, prim, u, v, v3(0, 0, 0), v3(0, 0, 0), 0.0, out);
}
