/* Spheres and curves as Embree user geometry: their bounds, and intersectors
 * that solve in double (a sphere in object space, a curve by pbrt-v4's
 * algorithm, curve.c) and apply the alpha test to each candidate hit. */
#include "geometry/alpha.h"
#include "geometry/surface_hit.h"
#include "geometry/user_shapes.h"

#include <math.h>
#include <stdlib.h>

static void sphere_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const geom_shape *s = args->geometryUserPtr;
    /* Transform the 8 corners of the object-space box: conservative for any
     * affine transform. Widen by a few float ULPs since Embree stores floats. */
    vec3 blo, bhi;
    transform_box(&s->space_from_object, v3(-s->radius, -s->radius, -s->radius),
                  v3(s->radius, s->radius, s->radius), &blo, &bhi);
    const double lo[3] = {blo.x, blo.y, blo.z}, hi[3] = {bhi.x, bhi.y, bhi.z};
    struct RTCBounds *b = args->bounds_o;
    float pad[3];
    for (int k = 0; k < 3; ++k)
        pad[k] = (float)(1e-6 * fmax(fabs(lo[k]), fabs(hi[k])));
    b->lower_x = (float)lo[0] - pad[0];
    b->lower_y = (float)lo[1] - pad[1];
    b->lower_z = (float)lo[2] - pad[2];
    b->upper_x = (float)hi[0] + pad[0];
    b->upper_y = (float)hi[1] + pad[1];
    b->upper_z = (float)hi[2] + pad[2];
}

/* Whether the object-space point p (on a partial sphere) lies on its part:
 * the z range and phi in [0, phimax], as pbrt-v4's partial sphere tests
 * them. */
static bool sphere_part_has(const geom_shape *s, vec3 p)
{
    p = v3_scale(p, s->radius / v3_length(p));
    if ((s->zmin > -s->radius && p.z < s->zmin) || (s->zmax < s->radius && p.z > s->zmax))
        return false;
    if (p.x == 0.0 && p.y == 0.0)
        p.x = 1e-5 * s->radius;
    double phi = atan2(p.y, p.x);
    if (phi < 0.0)
        phi += 2.0 * HZ_PI;
    return phi <= s->phimax;
}

/* Whether sphere s's hit at object-space point po (at t along the ray o, d of
 * the shape's space) survives its alpha. */
static bool sphere_alpha_keeps(const geom_shape *s, vec3 po, vec3 o, vec3 d, double t)
{
    if (!s->has_alpha)
        return true;
    geom_hit h;
    geom_sphere_uv(s, po, &h);
    return geom_alpha_keeps(
        geom_shape_alpha_at(s, h.u, h.v, transform_point(&s->space_from_object, po)), o, d, t);
}

/* Nearest root of |o + t d| = r in (tnear, tfar) on the sphere's part that
 * its alpha keeps, or -1. pbrt-v4's
 * formulation: the discriminant from the closest-approach vector avoids the
 * cancellation of b^2 - 4ac for distant origins. */
static double sphere_hit_t(const geom_shape *s, vec3 o_space, vec3 d_space, double tnear,
                           double tfar)
{
    transform object_from_space = transform_inverse(s->space_from_object);
    vec3 o = transform_point(&object_from_space, o_space);
    vec3 d = transform_vector(&object_from_space, d_space);
    double a = v3_dot(d, d);
    double b = 2.0 * v3_dot(d, o);
    double c = v3_dot(o, o) - s->radius * s->radius;
    vec3 v = v3_sub(o, v3_scale(d, b / (2.0 * a)));
    double len = v3_length(v);
    double disc = 4.0 * a * (s->radius + len) * (s->radius - len);
    if (disc < 0.0)
        return -1.0;
    double root = sqrt(disc);
    double q = b < 0.0 ? -0.5 * (b - root) : -0.5 * (b + root);
    double t0 = q / a, t1 = c / q;
    if (t0 > t1) {
        double t = t0;
        t0 = t1;
        t1 = t;
    }
    const double roots[2] = {t0, t1};
    for (int k = 0; k < 2; ++k) {
        double t = roots[k];
        vec3 po = v3_add(o, v3_scale(d, t));
        if (t > tnear && t < tfar && (!s->partial || sphere_part_has(s, po)) &&
            sphere_alpha_keeps(s, po, o_space, d_space, t))
            return t;
    }
    return -1.0;
}

/* Embree's rays and hits of width N (RTCRayN, RTCHitN) are structures of
 * arrays, field f of lane i at [f * N + i] (for N = 1 the layout of RTCRay and
 * RTCHit): haze traces single rays, but the callbacks serve any width. */
enum { RAY_ORG = 0, RAY_TNEAR = 3, RAY_DIR = 4, RAY_TFAR = 8 };
enum { HIT_NG = 0, HIT_U = 3, HIT_V = 4, HIT_PRIM = 5, HIT_GEOM = 6, HIT_INST = 7 };

static float *ray_lane(void *ray, unsigned N, unsigned field, unsigned i)
{
    return (float *)ray + field * N + i;
}

static unsigned *hit_lane(void *hit, unsigned N, unsigned field, unsigned i)
{
    return (unsigned *)hit + field * N + i;
}

static void ray_lane_read(void *ray, unsigned N, unsigned i, vec3 *o, vec3 *d)
{
    *o = v3(*ray_lane(ray, N, RAY_ORG, i), *ray_lane(ray, N, RAY_ORG + 1, i),
            *ray_lane(ray, N, RAY_ORG + 2, i));
    *d = v3(*ray_lane(ray, N, RAY_DIR, i), *ray_lane(ray, N, RAY_DIR + 1, i),
            *ray_lane(ray, N, RAY_DIR + 2, i));
}

/* Records a hit of user geometry on lane i of rayhit (normal 0: haze
 * recomputes it in double later). */
static void hit_lane_write(const struct RTCIntersectFunctionNArguments *args, unsigned i,
                           double t, double u)
{
    unsigned N = args->N;
    float *ray = (float *)args->rayhit;
    void *hit = ray + 12 * N; /* RTCRayHitN: the RTCRayN, then the RTCHitN */
    *ray_lane(ray, N, RAY_TFAR, i) = (float)t;
    for (unsigned k = 0; k < 3; ++k)
        *(float *)hit_lane(hit, N, HIT_NG + k, i) = 0.0f;
    *(float *)hit_lane(hit, N, HIT_U, i) = (float)u;
    *(float *)hit_lane(hit, N, HIT_V, i) = 0.0f;
    *hit_lane(hit, N, HIT_PRIM, i) = args->primID;
    *hit_lane(hit, N, HIT_GEOM, i) = args->geomID;
    *hit_lane(hit, N, HIT_INST, i) = args->context->instID[0];
}

/* The hit of one ray with primitive prim of user geometry s in (tnear,
 * tfar): its t (and the curve's u), or -1. */
typedef double (*lane_hit_fn)(const geom_shape *s, unsigned prim, vec3 o, vec3 d, double tnear,
                              double tfar, double *u);

static void intersect_lanes(const struct RTCIntersectFunctionNArguments *args, lane_hit_fn hit)
{
    for (unsigned i = 0; i < args->N; ++i) {
        if (!args->valid[i])
            continue;
        vec3 o, d;
        ray_lane_read(args->rayhit, args->N, i, &o, &d);
        double u = 0.0;
        double t = hit(args->geometryUserPtr, args->primID, o, d,
                       *ray_lane(args->rayhit, args->N, RAY_TNEAR, i),
                       *ray_lane(args->rayhit, args->N, RAY_TFAR, i), &u);
        if (t >= 0.0)
            hit_lane_write(args, i, t, u);
    }
}

/* Shadow rays: a hit blocks a lane unless the shape is an interface. */
static void occlude_lanes(const struct RTCOccludedFunctionNArguments *args, lane_hit_fn hit)
{
    const geom_shape *s = args->geometryUserPtr;
    if (s->material->kind == MATERIAL_INTERFACE)
        return;
    for (unsigned i = 0; i < args->N; ++i) {
        if (!args->valid[i])
            continue;
        vec3 o, d;
        ray_lane_read(args->ray, args->N, i, &o, &d);
        float *tfar = ray_lane(args->ray, args->N, RAY_TFAR, i);
        double u;
        if (hit(s, args->primID, o, d, *ray_lane(args->ray, args->N, RAY_TNEAR, i), *tfar, &u) >=
            0.0)
            *tfar = -INFINITY;
    }
}

static double sphere_lane_hit(const geom_shape *s, unsigned prim, vec3 o, vec3 d, double tnear,
                              double tfar, double *u)
{
    (void)prim;
    *u = 0.0;
    return sphere_hit_t(s, o, d, tnear, tfar);
}

static void sphere_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    intersect_lanes(args, sphere_lane_hit);
}

static void sphere_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    occlude_lanes(args, sphere_lane_hit);
}

static void curve_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const geom_shape *s = args->geometryUserPtr;
    vec3 lo, hi;
    geometry_curve_bounds(s, args->primID, &lo, &hi);
    const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    float *b = &args->bounds_o->lower_x;
    for (int k = 0; k < 3; ++k) {
        double pad = 1e-6 * fmax(fabs(l[k]), fabs(h[k]));
        b[k] = (float)(l[k] - pad);
        b[4 + k] = (float)(h[k] + pad);
    }
}

/* Whether curve s's hit at (u, t) on primitive prim survives its alpha
 * (pbrt-v4's test of the hit; a masked hit is no hit of the segment, which a
 * ray crosses once). */
static inline bool curve_alpha_keeps(const geom_shape *s, unsigned prim, double u, vec3 o,
                                     vec3 d, double t)
{
    if (!s->has_alpha)
        return true;
    double a = s->alpha;
    if (s->alpha_tex) {
        geom_hit h;
        double v = geom_curve_at(s, prim, u, o, d, t, &h);
        a = geom_shape_alpha_at(s, hz_clamp(u, 0.0, 1.0), v, h.p);
    }
    return geom_alpha_keeps(a, o, d, t);
}

/* A curve's hit that survives its alpha; a shadow ray's hit needs no more,
 * a camera or bounce ray's must also stay below tfar once rounded to float
 * (the t Embree keeps). */
static double curve_lane_hit(const geom_shape *s, unsigned prim, vec3 o, vec3 d, double tnear,
                             double tfar, double *u)
{
    double t = geometry_curve_hit(s, prim, o, d, tnear, tfar, u);
    return t >= 0.0 && curve_alpha_keeps(s, prim, *u, o, d, t) ? t : -1.0;
}

static double curve_lane_hit_closer(const geom_shape *s, unsigned prim, vec3 o, vec3 d,
                                    double tnear, double tfar, double *u)
{
    double t = curve_lane_hit(s, prim, o, d, tnear, tfar, u);
    return t >= 0.0 && (float)t < (float)tfar ? t : -1.0;
}

static void curve_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    intersect_lanes(args, curve_lane_hit_closer);
}

static void curve_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    occlude_lanes(args, curve_lane_hit);
}

RTCGeometry geom_build_sphere(RTCDevice device, const shape_geometry *g,
                              transform space_from_object, geom_shape *out)
{
    out->radius = g->radius;
    out->zmin = g->zmin;
    out->zmax = g->zmax;
    out->phimax = g->phimax;
    out->partial = g->zmin > -g->radius || g->zmax < g->radius || g->phimax < 2.0 * HZ_PI;
    out->space_from_object = space_from_object;
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, 1);
    rtcSetGeometryUserData(geom, out);
    rtcSetGeometryBoundsFunction(geom, sphere_bounds, NULL);
    rtcSetGeometryIntersectFunction(geom, sphere_intersect);
    rtcSetGeometryOccludedFunction(geom, sphere_occluded);
    return geom;
}

hz_status geom_build_curves(RTCDevice device, shape_entity *se, const shape_geometry *g,
                            transform space_from_object, bool interface, geom_shape *out,
                            RTCGeometry *geom_out, hz_error *err)
{
    if (interface && out->medium_inside != out->medium_outside)
        return hz_fail_at(err, se->entity.loc,
                          "a curve cannot separate media (it encloses no volume): give it no "
                          "MediumInterface, or the same medium on both sides");
    size_t n = g->segment_count;
    if (n > (UINT32_MAX >> g->split))
        return hz_fail_at(err, se->entity.loc, "curve has too many segments");
    double scale = cbrt(fabs(transform_det3(&space_from_object)));
    out->curve = g->curve;
    out->curve_split = g->split;
    out->segment_count = n;
    out->curve_cp = malloc(12 * n * sizeof *out->curve_cp);
    out->curve_w = malloc(2 * n * sizeof *out->curve_w);
    out->curve_n = g->normals ? malloc(6 * n * sizeof *out->curve_n) : NULL;
    if (!out->curve_cp || !out->curve_w || (g->normals && !out->curve_n))
        return hz_fail(err, "out of memory");
    for (size_t s = 0; s < n; ++s) {
        out->curve_w[2 * s] = scale * g->width[2 * s];
        out->curve_w[2 * s + 1] = scale * g->width[2 * s + 1];
        for (int e = 0; g->normals && e < 2; ++e) {
            const double *gn = &g->normals[6 * s + 3 * (size_t)e];
            vec3 nn = v3_normalize(transform_normal(&space_from_object, v3(gn[0], gn[1], gn[2])));
            out->curve_n[6 * s + 3 * (size_t)e] = nn.x;
            out->curve_n[6 * s + 3 * (size_t)e + 1] = nn.y;
            out->curve_n[6 * s + 3 * (size_t)e + 2] = nn.z;
        }
        for (int i = 0; i < 4; ++i) {
            const double *c = &g->cp[12 * s + 3 * (size_t)i];
            vec3 q = transform_point(&space_from_object, v3(c[0], c[1], c[2]));
            out->curve_cp[12 * s + 3 * (size_t)i] = q.x;
            out->curve_cp[12 * s + 3 * (size_t)i + 1] = q.y;
            out->curve_cp[12 * s + 3 * (size_t)i + 2] = q.z;
        }
    }
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    if (!geom)
        return hz_fail(err, "cannot create an Embree geometry");
    rtcSetGeometryUserPrimitiveCount(geom, (unsigned)(n << g->split));
    rtcSetGeometryUserData(geom, out);
    rtcSetGeometryBoundsFunction(geom, curve_bounds, NULL);
    rtcSetGeometryIntersectFunction(geom, curve_intersect);
    rtcSetGeometryOccludedFunction(geom, curve_occluded);
    *geom_out = geom;
    return HZ_OK;
}
