#include "geometry/geometry.h"
#include "core/hash.h"

#include "core/box.h"
#include "core/ray.h"

#include <stdatomic.h>

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <embree3/rtcore.h>

typedef struct {
    RTCScene scene;
    geom_shape *shapes;
    size_t shape_count;
} prototype;

/* An Embree instance: of an object's prototype (ObjectInstance), or of the
 * private scene of a moving top-level shape. */
typedef struct {
    transform render_from_instance; /* static instances */
    geom_motion motion;             /* moving ones: motion.steps != NULL */
    const geom_shape *shapes;       /* the instanced scene's shapes, by Embree geomID */
    RTCScene own_scene;             /* a moving shape's scene (released with the geometry) */
} instance;

struct geometry {
    RTCDevice device;
    RTCScene scene;
    geom_shape *shapes;       /* top-level; Embree geomID = index */
    size_t shape_count;
    prototype *objects;
    size_t object_count;
    instance *instances;      /* Embree geomID = shape_count + index */
    size_t instance_count;
    /* Per top-level shape, the instance that moves it (NULL: static); the
     * table itself is NULL when no shape moves. */
    instance **shape_instances;
    bool motion;              /* some shape or instance moves */
    /* Render-space boxes around the static top-level shapes that change the
     * medium (interface material, inside != outside); `interfaces_anywhere`
     * when such a shape moves, lies in an object or is one of too many to
     * test one by one (then every ray may cross one). */
    vec3 (*interface_boxes)[2];
    size_t interface_box_count;
    bool interfaces_anywhere;
    /* A render-space box around every static shape (padded as the interface
     * boxes): rays that miss it skip Embree. Not kept when something moves. */
    bool has_world_box;
    vec3 world_box[2];
    /* geometry_convex_around, per medium (NULL: none); NULL when no shape
     * has planes. */
    const geom_shape **convex_around;
    size_t convex_around_count;
    /* The largest convex mesh (geom_shape.planes), or NULL: a ray that knows
     * nothing (geom_past's zero value) and misses the box of the other shapes
     * finds its entry from the planes (geometry_intersect_past). */
    const geom_shape *convex_entry;
    double start_time, end_time; /* TransformTimes */
    const texture_set *textures; /* for "texture alpha" while building */
    /* Bytes Embree holds (its memory monitor): now and at most. */
    _Atomic long long embree_bytes, embree_peak;
};

static bool embree_memory(void *user, ssize_t bytes, bool post)
{
    (void)post;
    geometry *g = user;
    long long now = atomic_fetch_add(&g->embree_bytes, (long long)bytes) + bytes;
    long long peak = atomic_load(&g->embree_peak);
    while (now > peak && !atomic_compare_exchange_weak(&g->embree_peak, &peak, now))
        ;
    return true;
}

size_t geometry_embree_peak_bytes(const geometry *g)
{
    long long p = atomic_load(&((geometry *)g)->embree_peak);
    return p > 0 ? (size_t)p : 0;
}

/* ---- spheres: Embree user geometry solved in object space, in double ---- */

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

/* ---- alpha cut-outs (pbrt-v4's GeometricPrimitive alpha test) ---- */

static void triangle_corner_uv(const geom_shape *s, unsigned prim, double uv[3][2]);
static void sphere_uv(const geom_shape *s, vec3 po, geom_hit *hit);

/* Whether the hit at distance t of the ray (o, d) where the alpha is `a`
 * counts: always at 1 and above, never at 0 and below, otherwise when a hash
 * of the ray and t is at most a. pbrt-v4 hashes the ray, and after ignoring a
 * hit traces a new ray from it, so each surface along the way decides anew
 * (the back of a sphere of alpha 1/2 shows through its front half the time):
 * hashing t as well gives each hit its own decision along the one ray Embree
 * keeps tracing. */
static bool alpha_keeps(double a, vec3 o, vec3 d, double t)
{
    if (a >= 1.0)
        return true;
    if (!(a > 0.0))
        return false;
    const float v[7] = {(float)o.x, (float)o.y, (float)o.z, (float)d.x,
                        (float)d.y, (float)d.z, (float)t};
    uint64_t h = fnv1a(HZ_FNV_OFFSET, v, sizeof v);
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return (double)(h >> 11) * 0x1.0p-53 <= a;
}

/* The shape's alpha at surface parameters (u, v) and point p. */
static double shape_alpha_at(const geom_shape *s, double u, double v, vec3 p)
{
    if (!s->alpha_tex)
        return s->alpha;
    texture_ctx c = {.u = u, .v = v, .p = p};
    return texture_eval_float(s->alpha_tex, &c);
}

bool geometry_alpha_masked(const geom_shape *s, vec2 uv, vec3 p)
{
    if (!s->has_alpha)
        return false;
    double a = shape_alpha_at(s, uv.x, uv.y, p);
    if (a >= 1.0)
        return false;
    if (!(a > 0.0))
        return true;
    const float v[3] = {(float)p.x, (float)p.y, (float)p.z};
    uint64_t h = fnv1a(HZ_FNV_OFFSET, v, sizeof v);
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return (double)(h >> 11) * 0x1.0p-53 > a;
}

/* Embree's filter for triangles with an alpha: drops the hits the alpha test
 * ignores, so Embree goes on to the next surface (camera and shadow rays). */
static void alpha_filter(const struct RTCFilterFunctionNArguments *args)
{
    const geom_shape *s = args->geometryUserPtr;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0)
            continue;
        /* Embree's SOA layouts (RTCRayN, RTCHitN; C has no accessors): a
         * field's N values in a row, the fields in struct order. */
        const float *ray = (const float *)args->ray, *hit = (const float *)args->hit;
        unsigned n = args->N, prim;
        memcpy(&prim, &hit[5 * n + i], sizeof prim);
        double b1 = hit[3 * n + i], b2 = hit[4 * n + i];
        vec3 o = v3(ray[0 * n + i], ray[1 * n + i], ray[2 * n + i]);
        vec3 d = v3(ray[4 * n + i], ray[5 * n + i], ray[6 * n + i]);
        double t = ray[8 * n + i];
        double uv[3][2];
        triangle_corner_uv(s, prim, uv);
        double b0 = 1.0 - b1 - b2;
        double u = b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0];
        double v = b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1];
        if (!alpha_keeps(shape_alpha_at(s, u, v, v3_add(o, v3_scale(d, t))), o, d, t))
            args->valid[i] = 0;
    }
}

/* Whether sphere s's hit at object-space point po (at t along the ray o, d of
 * the shape's space) survives its alpha. */
static bool sphere_alpha_keeps(const geom_shape *s, vec3 po, vec3 o, vec3 d, double t)
{
    if (!s->has_alpha)
        return true;
    geom_hit h;
    sphere_uv(s, po, &h);
    return alpha_keeps(shape_alpha_at(s, h.u, h.v, transform_point(&s->space_from_object, po)),
                       o, d, t);
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

static double curve_at(const geom_shape *s, unsigned prim, double u, vec3 o, vec3 d, double t,
                       geom_hit *hit);

/* Whether curve s's hit at (u, t) on primitive prim survives its alpha
 * (pbrt-v4's test of the hit; a masked hit is no hit of the segment, which a
 * ray crosses once). */
static bool curve_alpha_keeps(const geom_shape *s, unsigned prim, double u, vec3 o, vec3 d,
                              double t)
{
    if (!s->has_alpha)
        return true;
    double a = s->alpha;
    if (s->alpha_tex) {
        geom_hit h;
        double v = curve_at(s, prim, u, o, d, t, &h);
        a = shape_alpha_at(s, hz_clamp(u, 0.0, 1.0), v, h.p);
    }
    return alpha_keeps(a, o, d, t);
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

/* Shadow rays pass through interfaces (they bound media, not surfaces). */
static void reject_occlusion(const struct RTCFilterFunctionNArguments *args)
{
    for (unsigned i = 0; i < args->N; ++i)
        args->valid[i] = 0;
}

/* ---- building ---- */

/* The index of medium `name` in sd->media; "" is vacuum (-1). */
static hz_status resolve_medium(const scene_desc *sd, const char *name, file_loc loc, int *out,
                                hz_error *err)
{
    *out = scene_find_medium(sd, name);
    if (*out != SCENE_MEDIUM_UNDEFINED)
        return HZ_OK;
    return hz_fail_at(err, loc, "MediumInterface names medium \"%s\", which is not defined "
                                "(MakeNamedMedium)",
                      name);
}

/* pbrt-v4's curve: Embree user geometry of 2^splitdepth pieces per segment,
 * intersected by pbrt-v4's algorithm (curve.c). Widths scale with the
 * transform (its volume's cube root: the scale of a similarity). */
static hz_status build_curves(RTCDevice device, shape_entity *se, const shape_geometry *g,
                              transform space_from_object, bool interface,
                              geom_shape *out, RTCGeometry *geom_out, hz_error *err)
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

static hz_status build_shape(RTCDevice device, RTCScene scene, unsigned geom_id,
                             const scene_desc *sd, shape_entity *se, transform space_from_object,
                             const material *materials,
                             size_t material_count, const material *default_material,
                             const texture_set *textures, geom_shape *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    out->area_light = -1;
    out->material = default_material;
    if (se->material >= 0) {
        if ((size_t)se->material >= material_count)
            return hz_fail_at(err, se->entity.loc, "shape names material %d of %zu",
                              se->material, material_count);
        out->material = &materials[se->material];
    }
    if (resolve_medium(sd, se->inside_medium, se->entity.loc, &out->medium_inside, err) != HZ_OK ||
        resolve_medium(sd, se->outside_medium, se->entity.loc, &out->medium_outside, err) != HZ_OK)
        return HZ_ERROR;

    shape_geometry g;
    if (shape_geometry_create(se, &g, err) != HZ_OK)
        return HZ_ERROR;
    out->kind = g.kind;
    out->flip_normal = se->reverse_orientation ^ transform_swaps_handedness(&space_from_object);
    bool interface = out->material->kind == MATERIAL_INTERFACE;
    out->textured = material_has_textures(out->material);
    out->hit_uv = out->textured || material_needs_hair_frame(out->material);
    out->unit_area = g.unit_area;
    out->alpha = g.alpha;
    if (g.alpha_texture) {
        out->alpha_tex = textures ? texture_set_find(textures, g.alpha_texture, false) : NULL;
        if (!out->alpha_tex) {
            hz_status st = hz_fail_at(err, params_loc(&se->entity.params, "alpha"),
                                      "\"texture alpha\": no float texture named \"%s\" "
                                      "defined before it",
                                      g.alpha_texture);
            shape_geometry_free(&g);
            return st;
        }
    }
    out->has_alpha = out->alpha_tex || out->alpha < 1.0;
    /* An alpha texture on an emitter is looked up at light samples too. */
    out->hit_uv |= out->alpha_tex != NULL;
    bool cutout = out->has_alpha;

    RTCGeometry geom = NULL;
    if (g.kind == GEOMETRY_SPHERE) {
        out->radius = g.radius;
        out->zmin = g.zmin;
        out->zmax = g.zmax;
        out->phimax = g.phimax;
        out->partial = g.zmin > -g.radius || g.zmax < g.radius || g.phimax < 2.0 * HZ_PI;
        out->space_from_object = space_from_object;
        geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(geom, 1);
        rtcSetGeometryUserData(geom, out);
        rtcSetGeometryBoundsFunction(geom, sphere_bounds, NULL);
        rtcSetGeometryIntersectFunction(geom, sphere_intersect);
        rtcSetGeometryOccludedFunction(geom, sphere_occluded);
    } else if (g.kind == GEOMETRY_CURVES) {
        if (build_curves(device, se, &g, space_from_object, interface, out, &geom, err) !=
            HZ_OK) {
            shape_geometry_free(&g);
            return HZ_ERROR;
        }
    } else if (g.triangle_count > 0) {
        geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *p = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           3 * sizeof(float), g.vertex_count);
        unsigned *idx = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                3 * sizeof(unsigned), g.triangle_count);
        if (!p || !idx) {
            rtcReleaseGeometry(geom);
            shape_geometry_free(&g);
            return hz_fail_at(err, se->entity.loc, "out of memory for a mesh of %zu triangles",
                              g.triangle_count);
        }
        /* Transform in double, round once: render space keeps float precision
         * near the camera however far the scene is from the world origin. */
        for (size_t i = 0; i < g.vertex_count; ++i) {
            vec3 q = transform_point(&space_from_object,
                                     v3(g.p[3 * i], g.p[3 * i + 1], g.p[3 * i + 2]));
            p[3 * i] = (float)q.x;
            p[3 * i + 1] = (float)q.y;
            p[3 * i + 2] = (float)q.z;
        }
        for (size_t i = 0; i < 3 * g.triangle_count; ++i) {
            if (g.indices[i] >= g.vertex_count) {
                rtcReleaseGeometry(geom);
                shape_geometry_free(&g);
                return hz_fail_at(err, se->entity.loc,
                                  "vertex index %u out of range (%zu vertices)", g.indices[i],
                                  g.vertex_count);
            }
            idx[i] = g.indices[i];
        }
        if (g.n) {
            out->n = malloc(3 * g.vertex_count * sizeof(double));
            if (!out->n) {
                rtcReleaseGeometry(geom);
                shape_geometry_free(&g);
                return hz_fail(err, "out of memory");
            }
            /* pbrt-v4's TriangleMesh flips given normals with ReverseOrientation
             * only (not with the handedness of the transform). */
            for (size_t i = 0; i < g.vertex_count; ++i) {
                vec3 n = transform_normal(&space_from_object,
                                          v3(g.n[3 * i], g.n[3 * i + 1], g.n[3 * i + 2]));
                if (se->reverse_orientation)
                    n = v3_neg(n);
                out->n[3 * i] = n.x;
                out->n[3 * i + 1] = n.y;
                out->n[3 * i + 2] = n.z;
            }
        }
        out->uv = g.uv; /* taken from g */
        g.uv = NULL;
        out->quads = g.quads;
        out->vertex_count = g.vertex_count;
        out->triangle_count = g.triangle_count;
        out->p = p;
        out->indices = idx;
    }
    shape_geometry_free(&g);
    if (!geom)
        return HZ_OK; /* an empty mesh: nothing to intersect */
    if (cutout && out->kind == GEOMETRY_TRIANGLES) {
        rtcSetGeometryUserData(geom, out);
        rtcSetGeometryIntersectFilterFunction(geom, alpha_filter);
        if (!interface)
            rtcSetGeometryOccludedFilterFunction(geom, alpha_filter);
    }
    if (interface)
        rtcSetGeometryOccludedFilterFunction(geom, reject_occlusion);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene, geom, geom_id);
    rtcReleaseGeometry(geom); /* the scene keeps it (and its buffers) alive */
    return HZ_OK;
}

static hz_status check_device(RTCDevice device, hz_error *err)
{
    enum RTCError e = rtcGetDeviceError(device);
    switch (e) {
    case RTC_ERROR_NONE:
        return HZ_OK;
    case RTC_ERROR_OUT_OF_MEMORY:
        return hz_fail(err, "out of memory building the Embree scene (acceleration structure)");
    default:
        return hz_fail(err, "Embree error %d while building the scene", (int)e);
    }
}

/* rtcNewScene failed: the device's error, or a generic message. */
static hz_status new_scene_failed(RTCDevice device, hz_error *err)
{
    if (check_device(device, err) != HZ_OK)
        return HZ_ERROR;
    return hz_fail(err, "cannot create an Embree scene");
}

static RTCScene new_scene(RTCDevice device)
{
    RTCScene s = rtcNewScene(device);
    if (!s)
        return NULL;
    /* Robust mode makes the triangle test watertight against edges and
     * vertices; the cost is small and leaks between triangles are worse. */
    rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
    return s;
}

/* A shape's own error (it has a place) goes to `errs` when there is one: the
 * shape is left out and the build goes on. */
static hz_status shape_failed(geom_shape *s, hz_errors *errs, hz_error *err)
{
    if (!errs || !err->loc.file)
        return HZ_ERROR;
    hz_errors_add(errs, err);
    s->left_out = true;
    s->area_light = -1;
    return HZ_OK;
}

static hz_status build_objects(geometry *g, scene_desc *sd, const material *materials,
                               size_t material_count, const material *default_material,
                               hz_errors *errs, hz_error *err)
{
    g->objects = calloc(sd->object_count ? sd->object_count : 1, sizeof *g->objects);
    if (!g->objects)
        return hz_fail(err, "out of memory");
    g->object_count = sd->object_count;
    for (size_t o = 0; o < sd->object_count; ++o) {
        object_entity *oe = &sd->objects[o];
        prototype *pr = &g->objects[o];
        pr->scene = new_scene(g->device);
        if (!pr->scene)
            return new_scene_failed(g->device, err);
        pr->shapes = calloc(oe->shape_count ? oe->shape_count : 1, sizeof *pr->shapes);
        if (!pr->shapes)
            return hz_fail(err, "out of memory");
        pr->shape_count = oe->shape_count;
        for (size_t i = 0; i < oe->shape_count; ++i) {
            shape_entity *se = &sd->object_shapes[oe->first_shape + i];
            if (se->has_area_light) {
                hz_fail_at(err, se->entity.loc,
                           "area lights inside object instances are not supported "
                           "(pbrt-v4 refuses them too)");
                if (shape_failed(&pr->shapes[i], errs, err) != HZ_OK)
                    return HZ_ERROR;
                continue;
            }
            /* Prototype space = the object's world space; instances carry
             * render_from_world to the instance transform. */
            transform space_from_object =
                transform_compose(transform_identity(), se->world_from_object);
            if (build_shape(g->device, pr->scene, (unsigned)i, sd, se, space_from_object,
                            materials, material_count, default_material, g->textures,
                            &pr->shapes[i], err) != HZ_OK &&
                shape_failed(&pr->shapes[i], errs, err) != HZ_OK)
                return HZ_ERROR;
        }
        rtcCommitScene(pr->scene);
        if (check_device(g->device, err) != HZ_OK)
            return HZ_ERROR;
    }
    return HZ_OK;
}

/* ---- motion ---- */

static bool moves(const transform *start, const transform *end)
{
    return memcmp(&start->m, &end->m, sizeof start->m) != 0;
}

transform geom_motion_at(const geom_motion *m, double time)
{
    double u = hz_clamp((time - m->start_time) / (m->end_time - m->start_time), 0.0, 1.0);
    /* Embree sees the ray time as a float. */
    mat4 x = quat_motion_at(m->steps, m->segments, (double)(float)u);
    transform t;
    if (!transform_from_matrix(x, &t)) { /* not for steps of one handedness */
        mat4 x0 = quat_decomposition_matrix(&m->steps[0]);
        if (!transform_from_matrix(x0, &t))
            t = transform_identity();
    }
    return t;
}

/* Attaches to the top-level scene, as `geom_id`, an instance of `child` that
 * moves with `a` (animated): time steps doubled until Embree's path follows
 * a's within GEOMETRY_MOTION_TOLERANCE over the child's bounds. */
static hz_status attach_moving(geometry *g, instance *in, RTCScene child,
                               const animated_transform *a, unsigned geom_id, file_loc loc,
                               hz_error *err)
{
    /* pbrt-v4 lerps S from one keyframe to the other: with a reflection at
     * one end only it passes through a singular transform. */
    if (transform_swaps_handedness(&a->start) != transform_swaps_handedness(&a->end))
        return hz_fail_at(err, loc,
                          "the start and end transforms differ in handedness (one mirrors, the "
                          "other does not): the motion would pass through a flat transform");
    struct RTCBounds b;
    rtcGetSceneBounds(child, &b);
    if (!(b.lower_x <= b.upper_x && b.lower_y <= b.upper_y && b.lower_z <= b.upper_z))
        return HZ_OK; /* nothing to intersect */
    vec3 lo = v3(b.lower_x, b.lower_y, b.lower_z), hi = v3(b.upper_x, b.upper_y, b.upper_z);
    int n = 1;
    quat_decomposition *steps = NULL;
    for (;;) {
        quat_decomposition *grown = realloc(steps, (size_t)(n + 1) * sizeof *steps);
        if (!grown) {
            free(steps);
            return hz_fail(err, "out of memory");
        }
        steps = grown;
        if (!animated_transform_time_steps(a, n, steps)) {
            free(steps);
            return hz_fail_at(err, loc, "the animated transform is singular between its keyframes");
        }
        if (n >= GEOMETRY_MAX_SEGMENTS ||
            animated_transform_steps_error(a, steps, n, lo, hi) <= GEOMETRY_MOTION_TOLERANCE)
            break;
        n *= 2;
    }
    in->motion = (geom_motion){a->start_time, a->end_time, n, steps};

    RTCGeometry geom = rtcNewGeometry(g->device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(geom, child);
    rtcSetGeometryTimeStepCount(geom, (unsigned)n + 1);
    for (int k = 0; k <= n; ++k) {
        const quat_decomposition *d = &steps[k];
        struct RTCQuaternionDecomposition qd;
        rtcInitQuaternionDecomposition(&qd);
        rtcQuaternionDecompositionSetScale(&qd, (float)d->scale[0], (float)d->scale[1],
                                           (float)d->scale[2]);
        rtcQuaternionDecompositionSetSkew(&qd, (float)d->skew[0], (float)d->skew[1],
                                          (float)d->skew[2]);
        rtcQuaternionDecompositionSetQuaternion(&qd, (float)d->rotation.w, (float)d->rotation.x,
                                                (float)d->rotation.y, (float)d->rotation.z);
        rtcQuaternionDecompositionSetTranslation(&qd, (float)d->translation.x,
                                                 (float)d->translation.y,
                                                 (float)d->translation.z);
        rtcSetGeometryTransformQuaternion(geom, (unsigned)k, &qd);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(g->scene, geom, geom_id);
    rtcReleaseGeometry(geom);
    g->motion = true;
    return HZ_OK;
}

/* A moving top-level shape: built in object space in a scene of its own,
 * instanced with its motion as Embree geomID i. Like pbrt-v4's animated
 * shapes (created with an identity transform), its normals do not flip with
 * the handedness of the transform. */
static hz_status build_moving_shape(geometry *g, scene_desc *sd, size_t i,
                                    const animated_transform *a, const material *materials,
                                    size_t material_count, const material *default_material,
                                    hz_error *err)
{
    instance *in = calloc(1, sizeof *in);
    if (!in)
        return hz_fail(err, "out of memory");
    g->shape_instances[i] = in;
    in->own_scene = new_scene(g->device);
    if (!in->own_scene)
        return new_scene_failed(g->device, err);
    in->shapes = &g->shapes[i];
    shape_entity *se = &sd->shapes[i];
    if (build_shape(g->device, in->own_scene, 0, sd, se, transform_identity(), materials,
                    material_count, default_material, g->textures, &g->shapes[i],
                    err) != HZ_OK)
        return HZ_ERROR;
    rtcCommitScene(in->own_scene);
    if (check_device(g->device, err) != HZ_OK ||
        attach_moving(g, in, in->own_scene, a, (unsigned)i, se->entity.loc, err) != HZ_OK)
        return HZ_ERROR;
    if (in->motion.steps)
        g->shapes[i].motion = &in->motion;
    return HZ_OK;
}

static hz_status build_shapes(geometry *g, scene_desc *sd, transform render_from_world,
                              const material *materials, size_t material_count,
                              const material *default_material, hz_errors *errs, hz_error *err)
{
    for (size_t i = 0; i < sd->shape_count; ++i) {
        shape_entity *se = &sd->shapes[i];
        transform render_from_object = transform_compose(render_from_world, se->world_from_object);
        if (moves(&se->world_from_object, &se->world_from_object_end)) {
            animated_transform a = animated_transform_make(
                render_from_object, sd->transform_start_time,
                transform_compose(render_from_world, se->world_from_object_end),
                sd->transform_end_time);
            if (a.animated) {
                if (!g->shape_instances) {
                    g->shape_instances = calloc(sd->shape_count, sizeof *g->shape_instances);
                    if (!g->shape_instances)
                        return hz_fail(err, "out of memory");
                }
                if (build_moving_shape(g, sd, i, &a, materials, material_count, default_material,
                                       err) != HZ_OK &&
                    shape_failed(&g->shapes[i], errs, err) != HZ_OK)
                    return HZ_ERROR;
                continue;
            }
        }
        if (build_shape(g->device, g->scene, (unsigned)i, sd, se, render_from_object, materials,
                        material_count, default_material, g->textures, &g->shapes[i],
                        err) != HZ_OK &&
            shape_failed(&g->shapes[i], errs, err) != HZ_OK)
            return HZ_ERROR;
    }
    return HZ_OK;
}

static hz_status build_instances(geometry *g, scene_desc *sd, transform render_from_world,
                                 hz_error *err)
{
    g->instances = calloc(sd->instance_count ? sd->instance_count : 1, sizeof *g->instances);
    if (!g->instances)
        return hz_fail(err, "out of memory");
    g->instance_count = sd->instance_count;
    for (size_t i = 0; i < sd->instance_count; ++i) {
        instance_entity *ie = &sd->instances[i];
        if (ie->object >= g->object_count)
            return hz_fail_at(err, ie->loc, "instance of unknown object %zu", ie->object);
        instance *in = &g->instances[i];
        in->shapes = g->objects[ie->object].shapes;
        in->render_from_instance = transform_compose(render_from_world, ie->world_from_instance);
        unsigned geom_id = (unsigned)(g->shape_count + i);
        if (moves(&ie->world_from_instance, &ie->world_from_instance_end)) {
            animated_transform a = animated_transform_make(
                in->render_from_instance, sd->transform_start_time,
                transform_compose(render_from_world, ie->world_from_instance_end),
                sd->transform_end_time);
            if (a.animated) {
                if (attach_moving(g, in, g->objects[ie->object].scene, &a, geom_id, ie->loc,
                                  err) != HZ_OK)
                    return HZ_ERROR;
                continue;
            }
        }
        float xfm[12];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                xfm[4 * r + c] = (float)in->render_from_instance.m.m[r][c];
        RTCGeometry geom = rtcNewGeometry(g->device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(geom, g->objects[ie->object].scene);
        rtcSetGeometryTimeStepCount(geom, 1);
        rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(g->scene, geom, geom_id);
        rtcReleaseGeometry(geom);
    }
    return HZ_OK;
}

/* Scenes of at most this many primitives build their BVH on the calling
 * thread (Embree's "threads=1"): Embree's task scheduler starting its worker
 * threads for the first build took a median 4.7 ms with a 12-triangle
 * scene, the device and the build 1.2 ms in all without them (40 runs each),
 * and the workers then spin beside the render threads. A build this small
 * takes well under a millisecond on one thread. */
enum { GEOMETRY_SMALL_SCENE = 10000 };

/* The primitives the scene's shapes give Embree, at most, or SIZE_MAX when
 * some shape's count is unknown before it is built (a PLY file, a
 * subdivision surface, ...). Reads the parameters without marking them used. */
static size_t primitive_bound(const scene_desc *sd)
{
    size_t n = sd->instance_count;
    for (size_t i = 0; i < sd->shape_count + sd->object_shape_count; ++i) {
        const scene_entity *e = i < sd->shape_count ? &sd->shapes[i].entity
                                                    : &sd->object_shapes[i - sd->shape_count].entity;
        /* A mesh has fewer triangles than index values; a curve fewer
         * segments than control point coordinates, each cut into at most
         * 2^8 pieces (its "splitdepth"). */
        const char *count_of = NULL;
        int shift = 0;
        if (strcmp(e->type, "trianglemesh") == 0 || strcmp(e->type, "bilinearmesh") == 0) {
            count_of = "indices";
        } else if (strcmp(e->type, "curve") == 0) {
            count_of = "P";
            shift = 8;
        } else if (strcmp(e->type, "sphere") != 0) {
            return SIZE_MAX;
        }
        size_t k = 1;
        for (size_t j = 0; count_of && j < e->params.count; ++j)
            if (strcmp(e->params.items[j].name, count_of) == 0)
                k = e->params.items[j].count;
        n += k << shift;
    }
    return n;
}

static RTCDevice new_device(bool portable_isa, bool small)
{
    /* Embree's choice is the widest ISA the CPU has (AVX-512 here: 12% faster
     * than SSE4.2 on bench/scenes/surfaces.pbrt). Hit points are recomputed
     * in double (surface_at), so an ISA changes an image only where rays
     * graze a shared edge; pinning SSE4.2 removes even that across machines.
     * Fall back to Embree's choice on a CPU without SSE4.2. */
    RTCDevice d = NULL;
    if (portable_isa)
        d = rtcNewDevice(small ? "isa=sse4.2,threads=1" : "isa=sse4.2");
    if (!d && small)
        d = rtcNewDevice("threads=1");
    return d ? d : rtcNewDevice(NULL);
}

static bool changes_medium(const geom_shape *s)
{
    return !s->left_out && s->material->kind == MATERIAL_INTERFACE &&
           s->medium_inside != s->medium_outside;
}

/* The render-space box of a static shape, padded well beyond the rounding
 * of Embree's float hits. */
static void shape_box(const geom_shape *s, vec3 *lo_out, vec3 *hi_out)
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

/* Fills g's interface boxes (see struct geometry). */
static hz_status find_interfaces(geometry *g, hz_error *err)
{
    for (size_t o = 0; o < g->object_count; ++o)
        for (size_t i = 0; i < g->objects[o].shape_count; ++i)
            g->interfaces_anywhere |= changes_medium(&g->objects[o].shapes[i]);
    size_t n = 0;
    for (size_t i = 0; i < g->shape_count; ++i)
        if (changes_medium(&g->shapes[i])) {
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
        if (!changes_medium(s))
            continue;
        shape_box(s, &g->interface_boxes[g->interface_box_count][0],
                  &g->interface_boxes[g->interface_box_count][1]);
        g->interface_box_count++;
    }
    return HZ_OK;
}

/* The world box, when nothing moves (Embree's bounds of the scene, padded
 * as the interface boxes). An empty scene has an empty box. */
static void find_world_box(geometry *g)
{
    if (g->motion)
        return;
    struct RTCBounds b;
    rtcGetSceneBounds(g->scene, &b);
    vec3 lo = v3(b.lower_x, b.lower_y, b.lower_z), hi = v3(b.upper_x, b.upper_y, b.upper_z);
    g->has_world_box = true;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) {
        g->world_box[0] = v3(1.0, 1.0, 1.0);
        g->world_box[1] = v3(-1.0, -1.0, -1.0);
        return;
    }
    double pad = 1e-5 * v3_max_component(v3_max(v3_abs(lo), v3_abs(hi))) + 1e-30;
    vec3 d = v3(pad, pad, pad);
    g->world_box[0] = v3_sub(lo, d);
    g->world_box[1] = v3_add(hi, d);
}

/* Meshes up to this many triangles are checked for convexity (all pairs of
 * triangle and vertex: at most 64 x 192). */
#define GEOMETRY_MAX_CONVEX_TRIANGLES 64

/* The planes of a convex mesh (geom_shape.planes), or NULL when some vertex
 * lies in front of some triangle's plane by more than `tol`. A degenerate
 * triangle (Embree never reports it) gets a zero plane. */
static double *convex_planes(const geom_shape *s, double tol)
{
    double *out = malloc(4 * s->triangle_count * sizeof *out);
    if (!out)
        return NULL;
    for (size_t t = 0; t < s->triangle_count; ++t) {
        vec3 v[3];
        for (int k = 0; k < 3; ++k) {
            const float *f = &s->p[3 * s->indices[3 * t + (size_t)k]];
            v[k] = v3(f[0], f[1], f[2]);
        }
        vec3 n = v3_cross(v3_sub(v[1], v[0]), v3_sub(v[2], v[0]));
        double len = v3_length(n);
        if (!(len > 0.0)) {
            out[4 * t] = out[4 * t + 1] = out[4 * t + 2] = out[4 * t + 3] = 0.0;
            continue;
        }
        n = v3_scale(n, 1.0 / len);
        double front = 0.0, behind = 0.0;
        for (size_t k = 0; k < s->vertex_count; ++k) {
            const float *f = &s->p[3 * k];
            double h = v3_dot(v3_sub(v3(f[0], f[1], f[2]), v[0]), n);
            front = hz_fmax(front, h);
            behind = hz_fmax(behind, -h);
        }
        if (front > tol && behind > tol) {
            free(out);
            return NULL;
        }
        if (front > tol)
            n = v3_neg(n);
        out[4 * t] = n.x;
        out[4 * t + 1] = n.y;
        out[4 * t + 2] = n.z;
        out[4 * t + 3] = v3_dot(n, v[0]);
    }
    return out;
}

static vec3 vertex(const geom_shape *s, uint32_t i);

/* geom_shape.convex_tris. */
static geom_convex_tri *convex_tris(const geom_shape *s)
{
    geom_convex_tri *out = malloc(s->triangle_count * sizeof *out);
    if (!out)
        return NULL;
    for (size_t t = 0; t < s->triangle_count; ++t) {
        const uint32_t *tri = &s->indices[3 * t];
        vec3 p0 = vertex(s, tri[0]), p1 = vertex(s, tri[1]), p2 = vertex(s, tri[2]);
        vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0), n = v3_cross(e1, e2);
        double nn = v3_dot(n, n);
        /* b1 = ((q - p0) x e2) . n / |n|^2, b2 = (e1 x (q - p0)) . n / |n|^2;
         * a degenerate triangle holds no point. */
        vec3 a1 = nn > 0.0 ? v3_scale(v3_cross(e2, n), 1.0 / nn) : v3(0, 0, 0);
        vec3 a2 = nn > 0.0 ? v3_scale(v3_cross(n, e1), 1.0 / nn) : v3(0, 0, 0);
        geom_convex_tri *c = &out[t];
        c->b1[0] = a1.x;
        c->b1[1] = a1.y;
        c->b1[2] = a1.z;
        c->b1[3] = nn > 0.0 ? -v3_dot(a1, p0) : -1.0;
        c->b2[0] = a2.x;
        c->b2[1] = a2.y;
        c->b2[2] = a2.z;
        c->b2[3] = nn > 0.0 ? -v3_dot(a2, p0) : -1.0;
        c->p2 = p2;
        c->n = v3_cross(v3_sub(p0, p2), v3_sub(p1, p2));
        c->ng = v3_normalize(c->n);
        if (s->flip_normal)
            c->ng = v3_neg(c->ng);
    }
    return out;
}

/* geom_shape.faces from its planes: triangles whose planes agree (normals
 * within 1e-9, offsets within convex_tol) share a face. */
static hz_status convex_faces(geom_shape *s)
{
    size_t n = s->triangle_count;
    uint32_t *face_of = malloc(n * sizeof *face_of);
    s->faces = malloc(n * sizeof *s->faces);
    s->face_tris = malloc(n * sizeof *s->face_tris);
    if (!face_of || !s->faces || !s->face_tris) {
        free(face_of);
        return HZ_ERROR;
    }
    size_t faces = 0;
    for (size_t t = 0; t < n; ++t) {
        const double *pl = &s->planes[4 * t];
        face_of[t] = UINT32_MAX;
        if (pl[0] == 0.0 && pl[1] == 0.0 && pl[2] == 0.0)
            continue; /* degenerate: never hit */
        size_t f = 0;
        while (f < faces &&
               !(fabs(s->faces[f].n[0] - pl[0]) <= 1e-9 && fabs(s->faces[f].n[1] - pl[1]) <= 1e-9 &&
                 fabs(s->faces[f].n[2] - pl[2]) <= 1e-9 &&
                 fabs(s->faces[f].c - pl[3]) <= s->convex_tol))
            ++f;
        if (f == faces) {
            s->faces[faces] = (geom_face){{pl[0], pl[1], pl[2]}, pl[3], 0, 0};
            ++faces;
        }
        face_of[t] = (uint32_t)f;
        s->faces[f].count++;
    }
    uint32_t next = 0;
    for (size_t f = 0; f < faces; ++f) {
        s->faces[f].first = next;
        next += s->faces[f].count;
        s->faces[f].count = 0;
    }
    for (size_t t = 0; t < n; ++t)
        if (face_of[t] != UINT32_MAX) {
            geom_face *f = &s->faces[face_of[t]];
            s->face_tris[f->first + f->count++] = (uint32_t)t;
        }
    s->face_count = faces;
    free(face_of);
    return HZ_OK;
}

/* geom_shape.planes and the boxes of the other shapes, for the small convex
 * meshes that change the medium, when nothing moves or is instanced; and
 * geometry_convex_around's table. */
static hz_status find_convex_interfaces(geometry *g, size_t medium_count, hz_error *err)
{
    if (g->motion || g->instance_count > 0 || g->object_count > 0 || g->shape_count == 0)
        return HZ_OK;
    bool any = false;
    for (size_t i = 0; i < g->shape_count; ++i) {
        const geom_shape *s = &g->shapes[i];
        any |= changes_medium(s) && s->kind == GEOMETRY_TRIANGLES &&
               s->triangle_count <= GEOMETRY_MAX_CONVEX_TRIANGLES;
    }
    if (!any)
        return HZ_OK;
    size_t n = g->shape_count;
    vec3(*box)[2] = malloc(n * sizeof *box);
    vec3(*before)[2] = malloc((n + 1) * sizeof *before);
    vec3(*after)[2] = malloc((n + 1) * sizeof *after);
    if (!box || !before || !after) {
        free(box);
        free(before);
        free(after);
        return hz_fail(err, "out of memory");
    }
    /* before[i]: the union of the boxes of shapes 0..i-1; after[i]: of i..n-1. */
    before[0][0] = after[n][0] = v3(INFINITY, INFINITY, INFINITY);
    before[0][1] = after[n][1] = v3(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < n; ++i) {
        box[i][0] = v3(INFINITY, INFINITY, INFINITY);
        box[i][1] = v3(-INFINITY, -INFINITY, -INFINITY);
        if (!g->shapes[i].left_out)
            shape_box(&g->shapes[i], &box[i][0], &box[i][1]);
        before[i + 1][0] = v3_min(before[i][0], box[i][0]);
        before[i + 1][1] = v3_max(before[i][1], box[i][1]);
    }
    for (size_t i = n; i-- > 0;) {
        after[i][0] = v3_min(after[i + 1][0], box[i][0]);
        after[i][1] = v3_max(after[i + 1][1], box[i][1]);
    }
    for (size_t i = 0; i < n; ++i) {
        geom_shape *s = &g->shapes[i];
        if (!changes_medium(s) || s->kind != GEOMETRY_TRIANGLES ||
            s->triangle_count > GEOMETRY_MAX_CONVEX_TRIANGLES)
            continue;
        /* Float rounding: 1e-6 of the mesh's extent. */
        s->convex_tol = 1e-6 * v3_max_component(v3_sub(box[i][1], box[i][0]));
        s->planes = convex_planes(s, s->convex_tol);
        if (s->planes && (convex_faces(s) != HZ_OK || !(s->convex_tris = convex_tris(s)))) {
            free(box);
            free(before);
            free(after);
            return hz_fail(err, "out of memory");
        }
        s->others_lo = v3_min(before[i][0], after[i + 1][0]);
        s->others_hi = v3_max(before[i][1], after[i + 1][1]);
    }
    free(box);
    free(before);
    free(after);
    g->convex_around = calloc(medium_count ? medium_count : 1, sizeof *g->convex_around);
    if (!g->convex_around)
        return hz_fail(err, "out of memory");
    g->convex_around_count = medium_count;
    double largest = -1.0;
    for (size_t i = n; i-- > 0;) {
        const geom_shape *s = &g->shapes[i];
        if (s->planes && s->medium_inside >= 0 && (size_t)s->medium_inside < medium_count)
            g->convex_around[s->medium_inside] = s;
        if (s->planes && s->face_count > 0 && s->convex_tol > largest) {
            largest = s->convex_tol; /* proportional to the mesh's extent */
            g->convex_entry = s;
        }
    }
    return HZ_OK;
}

bool geometry_static_box(const geometry *g, vec3 *lo, vec3 *hi)
{
    *lo = g->world_box[0];
    *hi = g->world_box[1];
    return g->has_world_box;
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

hz_status geometry_create(scene_desc *sd, transform render_from_world, const material *materials,
                          size_t material_count, const material *default_material,
                          const texture_set *textures, bool portable_isa, hz_errors *errs,
                          geometry **out, hz_error *err)
{
    *out = NULL;
    geometry *g = calloc(1, sizeof *g);
    if (!g)
        return hz_fail(err, "out of memory");
    g->start_time = sd->transform_start_time;
    g->end_time = sd->transform_end_time;
    g->textures = textures;
    g->device = new_device(portable_isa, primitive_bound(sd) <= GEOMETRY_SMALL_SCENE);
    if (!g->device) {
        free(g);
        return hz_fail(err, "cannot create the Embree device (error %d)",
                       (int)rtcGetDeviceError(NULL));
    }
    rtcSetDeviceMemoryMonitorFunction(g->device, embree_memory, g);
    g->scene = new_scene(g->device);
    if (!g->scene) {
        hz_status st = new_scene_failed(g->device, err);
        geometry_destroy(g);
        return st;
    }
    g->shapes = calloc(sd->shape_count ? sd->shape_count : 1, sizeof *g->shapes);
    if (!g->shapes) {
        geometry_destroy(g);
        return hz_fail(err, "out of memory");
    }
    g->shape_count = sd->shape_count;
    if (build_shapes(g, sd, render_from_world, materials, material_count, default_material, errs,
                     err) != HZ_OK ||
        build_objects(g, sd, materials, material_count, default_material, errs, err) != HZ_OK ||
        build_instances(g, sd, render_from_world, err) != HZ_OK) {
        geometry_destroy(g);
        return HZ_ERROR;
    }
    rtcCommitScene(g->scene);
    find_world_box(g);
    if (check_device(g->device, err) != HZ_OK || find_interfaces(g, err) != HZ_OK ||
        find_convex_interfaces(g, sd->medium_count, err) != HZ_OK) {
        geometry_destroy(g);
        return HZ_ERROR;
    }
    *out = g;
    return HZ_OK;
}

static void free_shape_arrays(geom_shape *s)
{
    free(s->planes);
    free(s->faces);
    free(s->face_tris);
    free(s->convex_tris);
    free(s->n);
    free(s->uv);
    free(s->curve_cp);
    free(s->curve_w);
    free(s->curve_n);
}

void geometry_destroy(geometry *g)
{
    if (!g)
        return;
    for (size_t i = 0; i < g->shape_count; ++i)
        free_shape_arrays(&g->shapes[i]);
    free(g->shapes);
    if (g->shape_instances) {
        for (size_t i = 0; i < g->shape_count; ++i) {
            instance *in = g->shape_instances[i];
            if (!in)
                continue;
            free(in->motion.steps);
            if (in->own_scene)
                rtcReleaseScene(in->own_scene);
            free(in);
        }
        free(g->shape_instances);
    }
    for (size_t o = 0; o < g->object_count; ++o) {
        for (size_t i = 0; i < g->objects[o].shape_count; ++i)
            free_shape_arrays(&g->objects[o].shapes[i]);
        free(g->objects[o].shapes);
        if (g->objects[o].scene)
            rtcReleaseScene(g->objects[o].scene);
    }
    free(g->objects);
    for (size_t i = 0; i < g->instance_count; ++i)
        free(g->instances[i].motion.steps);
    free(g->instances);
    free(g->interface_boxes);
    free(g->convex_around);
    if (g->scene)
        rtcReleaseScene(g->scene);
    if (g->device)
        rtcReleaseDevice(g->device);
    free(g);
}

struct RTCSceneTy *geometry_embree_scene(const geometry *g) { return g->scene; }

bool geometry_has_motion(const geometry *g) { return g->motion; }

static bool shapes_reference_media(const geom_shape *shapes, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!shapes[i].left_out && (shapes[i].medium_inside >= 0 || shapes[i].medium_outside >= 0))
            return true;
    return false;
}

bool geometry_references_media(const geometry *g)
{
    if (shapes_reference_media(g->shapes, g->shape_count))
        return true;
    for (size_t i = 0; i < g->object_count; ++i)
        if (shapes_reference_media(g->objects[i].shapes, g->objects[i].shape_count))
            return true;
    return false;
}

size_t geometry_shape_count(const geometry *g) { return g->shape_count; }
geom_shape *geometry_shape(geometry *g, size_t i) { return &g->shapes[i]; }

/* ---- queries ---- */

static vec3 vertex(const geom_shape *s, uint32_t i)
{
    return v3(s->p[3 * i], s->p[3 * i + 1], s->p[3 * i + 2]);
}

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

void geometry_hit_footprint(geom_hit *h, vec3 rx_o, vec3 rx_d, vec3 ry_o, vec3 ry_d)
{
    vec3 dpdx, dpdy;
    if (!h->shape->textured || !geometry_hit_dpdxy(h, rx_o, rx_d, ry_o, ry_d, &dpdx, &dpdy))
        return;
    h->dpdx = dpdx;
    h->dpdy = dpdy;
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

void geometry_require_uv(geometry *g)
{
    for (size_t i = 0; i < g->shape_count; ++i)
        g->shapes[i].hit_uv = true;
    for (size_t o = 0; o < g->object_count; ++o)
        for (size_t i = 0; i < g->objects[o].shape_count; ++i)
            g->objects[o].shapes[i].hit_uv = true;
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

/* pbrt-v4's sphere parameters at the object-space point po. */
static void sphere_uv(const geom_shape *s, vec3 po, geom_hit *hit)
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
    sphere_uv(s, po, &h);
    return v2(h.u, h.v);
}

/* pbrt-v4's triangle parameters: the mesh's uv (or its defaults, a
 * bilinear patch's for a quad's halves) at barycentrics (b1, b2). */
/* The (u, v) of triangle prim's three corners: the mesh's "uv", or pbrt-v4's
 * defaults (a bilinear patch's for a quad's halves). */
static void triangle_corner_uv(const geom_shape *s, unsigned prim, double uv[3][2])
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

static void triangle_uv(const geom_shape *s, unsigned prim, double b1, double b2, vec3 p0,
                        vec3 p1, vec3 p2, geom_hit *hit)
{
    double uv[3][2];
    triangle_corner_uv(s, prim, uv);
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
static double curve_at(const geom_shape *s, unsigned prim, double u, vec3 o, vec3 d, double t,
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

/* Fills p, ng, ns in the shape's own space (render or prototype), for the
 * ray o + t d of that space; d = 0 asks for the point at barycentrics (u, v). */
static void surface_at(const geom_shape *s, unsigned prim, double u, double v, vec3 o, vec3 d,
                       double t, geom_hit *hit)
{
    hit->p_error = 0.0;
    if (s->kind == GEOMETRY_CURVES) {
        curve_at(s, prim, u, o, d, t, hit);
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
            sphere_uv(s, po, hit);
        return;
    }
    const uint32_t *tri = &s->indices[3 * prim];
    vec3 p0 = vertex(s, tri[0]), p1 = vertex(s, tri[1]), p2 = vertex(s, tri[2]);
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
    surface_at(s, prim, u, v, v3(0, 0, 0), v3(0, 0, 0), 0.0, out);
}

/* The ray time Embree sees: the scene time over TransformTimes, in [0, 1];
 * 0 in a scene without motion, as before motion existed. */
static float embree_time(const geometry *g, double time)
{
    if (!g->motion)
        return 0.0f;
    return (float)hz_clamp((time - g->start_time) / (g->end_time - g->start_time), 0.0, 1.0);
}

static void init_ray(struct RTCRay *r, vec3 o, vec3 d, double tmax, float time)
{
    r->org_x = (float)o.x;
    r->org_y = (float)o.y;
    r->org_z = (float)o.z;
    r->tnear = 0.0f;
    r->dir_x = (float)d.x;
    r->dir_y = (float)d.y;
    r->dir_z = (float)d.z;
    r->time = time;
    r->tfar = tmax >= (double)INFINITY ? INFINITY : (float)tmax;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

/* What Embree's ray validity check accepts (kernels/common/ray.h: |org| and
 * |dir| components at most FLT_LARGE = 1.844e18, tnear and tfar not NaN),
 * with a margin, and tnear >= 0 (its documented range). */
static bool embree_can_trace(vec3 o, vec3 d, double tmin, double tmax)
{
    const double large = 1e18;
    return point_within(o, large) && point_within(d, large) && tmin >= 0.0 && !isnan(tmax) &&
           (float)tmin <= large;
}

/* Whether the segment [tmin, tmax] of the ray certainly hits nothing: it
 * misses the padded box around every static shape. */
static inline bool misses_box(vec3 box_lo, vec3 box_hi, vec3 o, vec3 d, double tmin, double tmax)
{
    /* The slab test with reciprocals (box_clip_ray divides: 6 divisions on
     * every Embree query were 5% of a peer render). A NaN (0 * inf where the
     * origin lies on a slab's plane and the ray runs in it) restricts
     * nothing: the answer is then "may hit", which is always safe. */
    const double o3[3] = {o.x, o.y, o.z}, d3[3] = {d.x, d.y, d.z};
    const double lo[3] = {box_lo.x, box_lo.y, box_lo.z};
    const double hi[3] = {box_hi.x, box_hi.y, box_hi.z};
    double t0 = tmin, t1 = tmax;
    for (int a = 0; a < 3; ++a) {
        double inv = 1.0 / d3[a];
        double tn = (lo[a] - o3[a]) * inv, tf = (hi[a] - o3[a]) * inv;
        if (tn > tf) {
            double t = tn;
            tn = tf;
            tf = t;
        }
        t0 = tn > t0 ? tn : t0;
        t1 = tf < t1 ? tf : t1;
    }
    return t0 > t1;
}

static bool misses_world_box(const geometry *g, vec3 o, vec3 d, double tmin, double tmax)
{
    return g->has_world_box && misses_box(g->world_box[0], g->world_box[1], o, d, tmin, tmax);
}

static bool trace(const geometry *g, vec3 o, vec3 d, double tmin, double tmax, double time,
                  geom_hit *hit);

bool geometry_intersect(const geometry *g, vec3 o, vec3 d, double tmin, double tmax, double time,
                        geom_hit *hit)
{
    /* Either test's "no" means no hit, so their order changes no answer;
     * the world box first spares most rays of a small subject the other. */
    return !misses_world_box(g, o, d, tmin, tmax) && trace(g, o, d, tmin, tmax, time, hit);
}

/* geometry_intersect after the box test. */
static bool trace(const geometry *g, vec3 o, vec3 d, double tmin, double tmax, double time,
                  geom_hit *hit)
{
    if (!embree_can_trace(o, d, tmin, tmax))
        return false;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    init_ray(&rh.ray, o, d, tmax, embree_time(g, time));
    /* Rounded up, so Embree searches no nearer than tmin: rounded to the
     * nearest, a step past a hit far from the origin (step_past's few ulps
     * of double) could land on the hit's own float t and find it again. */
    float tnear = (float)tmin;
    if ((double)tnear < tmin)
        tnear = nextafterf(tnear, INFINITY);
    rh.ray.tnear = tnear;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(g->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return false;

    hit->t = rh.ray.tfar;
    hit->prim = rh.hit.primID;
    if (rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID) {
        const geom_shape *s = &g->shapes[rh.hit.geomID];
        hit->shape = s;
        surface_at(s, rh.hit.primID, rh.hit.u, rh.hit.v, o, d, rh.ray.tfar, hit);
        return true;
    }
    unsigned id = rh.hit.instID[0];
    const instance *in = id < g->shape_count ? g->shape_instances[id]
                                             : &g->instances[id - g->shape_count];
    const geom_shape *s = &in->shapes[rh.hit.geomID];
    hit->shape = s;
    /* A moving instance at the ray's time, as Embree moved it. */
    transform render_from_instance =
        in->motion.steps ? geom_motion_at(&in->motion, time) : in->render_from_instance;
    transform instance_from_render = transform_inverse(render_from_instance);
    surface_at(s, rh.hit.primID, rh.hit.u, rh.hit.v, transform_point(&instance_from_render, o),
               transform_vector(&instance_from_render, d), rh.ray.tfar, hit);
    hit->p = transform_point(&render_from_instance, hit->p);
    hit->p_error *= cbrt(fabs(transform_det3(&render_from_instance)));
    hit->ng = v3_normalize(transform_normal(&render_from_instance, hit->ng));
    hit->ns = v3_normalize(transform_normal(&render_from_instance, hit->ns));
    if (s->hit_uv) {
        hit->dpdu = transform_vector(&render_from_instance, hit->dpdu);
        hit->dpdv = transform_vector(&render_from_instance, hit->dpdv);
    }
    return true;
}

geom_past geometry_past(const geom_hit *h, vec3 d)
{
    geom_past past = {NULL, NULL};
    const double *n = h->shape->planes;
    if (!n)
        return past;
    n += 4 * (size_t)h->prim;
    double dn = d.x * n[0] + d.y * n[1] + d.z * n[2];
    if (dn > 0.0)
        past.left = h->shape;
    else if (dn < 0.0)
        past.within = h->shape;
    return past;
}

const geom_shape *geometry_convex_around(const geometry *g, int medium)
{
    return medium >= 0 && (size_t)medium < g->convex_around_count ? g->convex_around[medium]
                                                                   : NULL;
}

/* How far q lies inside triangle `prim` of convex mesh s (the least of its
 * barycentrics: >= 0 inside), and its barycentrics (Embree's u, v). */
static double triangle_inside(const geom_shape *s, unsigned prim, vec3 q, double *u, double *v)
{
    const geom_convex_tri *c = &s->convex_tris[prim];
    double b1 = c->b1[0] * q.x + c->b1[1] * q.y + c->b1[2] * q.z + c->b1[3];
    double b2 = c->b2[0] * q.x + c->b2[1] * q.y + c->b2[2] * q.z + c->b2[3];
    *u = b1;
    *v = b2;
    return hz_fmin(hz_fmin(b1, b2), 1.0 - b1 - b2);
}

/* surface_at for triangle `prim` of convex mesh s (no uv, no shading
 * normals), with its cached plane: the same values. */
static void convex_surface_at(const geom_shape *s, unsigned prim, double u, double v, vec3 o,
                              vec3 d, double t, geom_hit *hit)
{
    const geom_convex_tri *c = &s->convex_tris[prim];
    double dn = v3_dot(d, c->n);
    if (dn == 0.0) {
        surface_at(s, prim, u, v, o, d, t, hit);
        return;
    }
    hit->p_error = 0.0;
    hit->p = v3_add(o, v3_scale(d, v3_dot(v3_sub(c->p2, o), c->n) / dn));
    hit->ng = hit->ns = c->ng;
}

/* The hit of o + t d on face f of convex mesh s: the face's triangle that
 * holds the point. 1 with *hit filled, -1 (Embree must answer) when none
 * does. */
static int face_hit(const geom_shape *s, const geom_face *f, vec3 o, vec3 d, double t,
                    geom_hit *hit)
{
    vec3 q = v3_add(o, v3_scale(d, t));
    double best = -INFINITY, u = 0.0, v = 0.0;
    unsigned prim = 0;
    for (uint32_t i = 0; i < f->count && best < 0.0; ++i) {
        unsigned k = s->face_tris[f->first + i];
        double bu = 0.0, bv = 0.0, in = triangle_inside(s, k, q, &bu, &bv);
        if (in > best) {
            best = in;
            prim = k;
            u = bu;
            v = bv;
        }
    }
    if (!(best >= -1e-7))
        return -1;
    hit->t = t;
    hit->prim = prim;
    hit->shape = s;
    convex_surface_at(s, prim, u, v, o, d, t, hit);
    return 1;
}

/* The next hit of a ray inside convex mesh s (geom_past.within): 1 with
 * *hit filled (the mesh's exit), 0 for none within [tmin, tmax], -1 when
 * Embree must answer (the origin is not inside, another shape's box lies on
 * the way, the exit is not found on a triangle, or the hit needs more than
 * the plane). */
static int convex_exit(const geom_shape *s, vec3 o, vec3 d, double tmin, double tmax,
                       geom_hit *hit)
{
    if (s->hit_uv || s->n || !embree_can_trace(o, d, tmin, tmax))
        return -1;
    vec3 p = v3_add(o, v3_scale(d, tmin));
    double t_exit = INFINITY;
    const geom_face *exit = NULL;
    for (size_t k = 0; k < s->face_count; ++k) {
        const geom_face *f = &s->faces[k];
        double h = f->n[0] * p.x + f->n[1] * p.y + f->n[2] * p.z - f->c;
        if (!(h <= s->convex_tol))
            return -1; /* not inside (or NaN) */
        double dn = f->n[0] * d.x + f->n[1] * d.y + f->n[2] * d.z;
        if (dn > 0.0 && -h < t_exit * dn) {
            t_exit = -h / dn;
            exit = f;
        }
    }
    if (!exit || !(t_exit >= 0.0))
        return -1;
    double t = tmin + t_exit;
    bool others = s->others_lo.x <= s->others_hi.x;
    if (t > tmax)
        return others && !misses_box(s->others_lo, s->others_hi, o, d, tmin, tmax) ? -1 : 0;
    if (others && !misses_box(s->others_lo, s->others_hi, o, d, tmin, t))
        return -1;
    return face_hit(s, exit, o, d, t, hit);
}

/* The next hit of a ray whose origin at tmin lies outside convex mesh s,
 * when the ray misses the box of every other shape: 1 with *hit filled (the
 * mesh's entry, where the last of the planes it enters through is crossed),
 * 0 for none within [tmin, tmax], -1 when Embree must answer (the origin is
 * inside or within rounding of a plane, the ray grazes an edge, another
 * shape's box lies on the way, the entry is not found on a triangle, or the
 * hit needs more than the plane). */
static int convex_entry(const geom_shape *s, vec3 o, vec3 d, double tmin, double tmax,
                        geom_hit *hit)
{
    if (s->hit_uv || s->n || !embree_can_trace(o, d, tmin, tmax))
        return -1;
    if (s->others_lo.x <= s->others_hi.x &&
        !misses_box(s->others_lo, s->others_hi, o, d, tmin, tmax))
        return -1;
    vec3 p = v3_add(o, v3_scale(d, tmin));
    double t_near = 0.0, t_far = INFINITY;
    const geom_face *entry = NULL;
    for (size_t k = 0; k < s->face_count; ++k) {
        const geom_face *f = &s->faces[k];
        double h = f->n[0] * p.x + f->n[1] * p.y + f->n[2] * p.z - f->c;
        if (!(fabs(h) > s->convex_tol))
            return -1; /* on the surface (or NaN) */
        double dn = f->n[0] * d.x + f->n[1] * d.y + f->n[2] * d.z;
        if (h > 0.0) {
            if (!(dn < 0.0))
                return 0; /* in front of this plane and not moving towards it */
            if (h > t_near * -dn) {
                t_near = h / -dn;
                entry = f;
            }
        } else if (dn > 0.0 && -h < t_far * dn) {
            t_far = -h / dn;
        }
    }
    if (!entry)
        return -1; /* inside */
    /* Where the entry and exit planes cross within rounding the ray grazes
     * an edge: Embree decides. */
    double slack = 1e-6 * (t_near + fabs(tmin));
    if (t_near > t_far + slack)
        return 0;
    if (!(t_near < t_far - slack))
        return -1;
    double t = tmin + t_near;
    if (t > tmax)
        return 0;
    return face_hit(s, entry, o, d, t, hit);
}

bool geometry_intersect_past(const geometry *g, geom_past past, vec3 o, vec3 d, double tmin,
                             double tmax, double time, geom_hit *hit)
{
    /* The box of the other shapes lies inside the world box: it replaces
     * that test. With no other shape, nothing is left to hit. */
    const geom_shape *left = past.left;
    if (left)
        return left->others_lo.x <= left->others_hi.x &&
               !misses_box(left->others_lo, left->others_hi, o, d, tmin, tmax) &&
               trace(g, o, d, tmin, tmax, time, hit);
    if (past.within) {
        int found = convex_exit(past.within, o, d, tmin, tmax, hit);
        if (found >= 0)
            return found;
    }
    if (misses_world_box(g, o, d, tmin, tmax))
        return false;
    if (g->convex_entry) {
        int found = convex_entry(g->convex_entry, o, d, tmin, tmax, hit);
        if (found >= 0)
            return found;
    }
    return trace(g, o, d, tmin, tmax, time, hit);
}

bool geometry_occluded(const geometry *g, vec3 o, vec3 d, double tmax, double time)
{
    if (!embree_can_trace(o, d, 0.0, tmax))
        return true;
    if (misses_world_box(g, o, d, 0.0, tmax))
        return false;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r;
    init_ray(&r, o, d, tmax, embree_time(g, time));
    rtcOccluded1(g->scene, &ctx, &r);
    return r.tfar == -INFINITY;
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

/* ---- stepping past surfaces ---- */

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
