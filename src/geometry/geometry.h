/* Surfaces in render space, intersected by Embree: triangle meshes as Embree
 * triangles (vertices baked to float in render space), spheres as user
 * geometry solved in object space in double precision, ObjectBegin/End
 * prototypes as Embree instances. Hits come back with pbrt-v4's normal
 * orientation rules applied.
 *
 * Motion (docs/motion.md): a top-level shape or an instance whose transform
 * differs at the two TransformTimes moves as pbrt-v4's AnimatedTransform,
 * intersected through Embree's quaternion motion blur: the shape sits in
 * object space in a scene of its own, instanced with time steps. Shapes and
 * instances whose keyframes are equal are built exactly as without motion, and
 * a scene without motion has no time steps at all. */
#ifndef HAZE_GEOMETRY_GEOMETRY_H
#define HAZE_GEOMETRY_GEOMETRY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/animated_transform.h"
#include "core/error.h"
#include "core/transform.h"
#include "materials/material.h"
#include "scene/scene_desc.h"
#include "scene/shape.h"

/* How a moving shape or instance moves: render_from_object (or
 * render_from_instance) as the Embree time steps it is intersected with, over
 * the scene's TransformTimes. */
typedef struct {
    double start_time, end_time; /* TransformTimes, end > start */
    int segments;                /* Embree time steps - 1, in [1, GEOMETRY_MAX_SEGMENTS] */
    quat_decomposition *steps;   /* segments + 1 */
} geom_motion;

/* At most 128 segments (Embree takes up to 129 time steps); the steps of a
 * motion are doubled from 1 until Embree's path follows pbrt-v4's within
 * GEOMETRY_MOTION_TOLERANCE (relative to the distance from the camera). */
#define GEOMETRY_MAX_SEGMENTS 128
#define GEOMETRY_MOTION_TOLERANCE 1e-5

/* The transform at scene time `time` (clamped to TransformTimes): exactly the
 * motion Embree intersects (its segment choice and interpolation, in double). */
transform geom_motion_at(const geom_motion *m, double time);

/* A face of a convex mesh (geom_shape.faces): the plane of some of its
 * triangles, n . x = c with n the unit normal pointing away from the mesh,
 * and those triangles, geom_shape.face_tris[first .. first + count). */
typedef struct {
    double n[3], c;
    uint32_t first, count;
} geom_face;

/* A triangle of a convex mesh, for hits found from its planes: q's
 * barycentrics (Embree's u, v) are b1 . (q, 1) and b2 . (q, 1); p2 and
 * n = (p0 - p2) x (p1 - p2) are geom_surface_at's, in double; ng its geometric
 * normal. */
typedef struct {
    double b1[4], b2[4];
    vec3 p2, n, ng;
} geom_convex_tri;

/* One shape as the renderer sees it. Top-level shapes live in render space,
 * shapes of an object (ObjectBegin) in that object's prototype space. */
typedef struct {
    geometry_kind kind;
    const material *material; /* never NULL (the default material when none is named) */
    int area_light;           /* index into the scene's lights, -1 = not an emitter */
    bool left_out;            /* refused with an error (geometry_create's errs): not built */
    /* pbrt-v4: ReverseOrientation XOR a handedness-swapping transform flips
     * the geometric normal (triangles and spheres alike). */
    bool flip_normal;
    /* MediumInterface (indices into scene_desc.media, -1 = vacuum). When they
     * are equal the shape is no medium transition: rays keep their medium. */
    int medium_inside, medium_outside;
    /* triangles: Embree's own buffers, so sampling and hit points use exactly
     * the surface Embree intersects */
    size_t vertex_count, triangle_count;
    const float *p;           /* 3 per vertex */
    const uint32_t *indices;  /* 3 per triangle */
    double *n;                /* 3 per vertex, shading normals in this space, or NULL */
    double *uv;               /* 2 per vertex, or NULL: pbrt-v4's defaults */
    bool quads;               /* bilinearmesh: triangles 2i, 2i + 1 are quad i's halves */
    /* The material (or a mix's component) has textures: hits carry (u, v)
     * and dp/du, dp/dv (no cost for the others). */
    bool textured;
    /* Hits carry (u, v) and dp/du, dp/dv: textured shapes, and every shape
     * after geometry_require_uv. */
    bool hit_uv;
    /* sphere; a part of it (pbrt-v4's zmin, zmax, phimax) when `partial` */
    double radius;
    double zmin, zmax, phimax;
    bool partial;
    double unit_area;            /* shape_geometry's: what area lights' "power" divides */
    /* curves (Embree's flat or normal-oriented Bezier curves): each segment's
     * 4 control points in this space (in double, for the hit's frame), its
     * widths at the ends (object widths times the transform's scale) and,
     * for ribbons, its unit normals at the ends */
    curve_type curve;
    size_t segment_count;
    double *curve_cp; /* 12 per segment */
    double *curve_w;  /* 2 per segment */
    double *curve_n;  /* 6 per segment, or NULL */
    int curve_split;  /* pbrt-v4's "splitdepth": 2^split Embree primitives per segment */
    /* pbrt-v4's alpha cut-out: hits where the alpha (the texture at the hit's
     * uv, or the constant) is 0 are ignored, where it is in (0, 1) kept with
     * that probability by a hash of the ray (the same for camera and shadow
     * rays); a shape with alpha 1 and no texture has no filter at all
     * (has_alpha false: the zero value is an opaque shape). */
    bool has_alpha;
    double alpha;
    const texture *alpha_tex;
    transform space_from_object; /* render (or prototype) space from object space */
    /* A moving top-level shape: everything above is in object space (space =
     * object space, space_from_object the identity) and render_from_object at
     * a time is geom_motion_at(motion, time). NULL for static shapes. */
    const geom_motion *motion;
    /* A small static convex mesh that changes the medium, in a scene where
     * nothing moves or is instanced (geometry_past): per triangle its plane,
     * the unit normal pointing away from the mesh (every vertex lies on or
     * behind each triangle's plane, up to convex_tol) and its dot product
     * with the triangle's vertices; or NULL. And the padded box around every
     * other shape (empty, lo > hi, when there is none). */
    double *planes; /* 4 per triangle */
    double convex_tol;
    geom_face *faces; /* the distinct planes, each with its triangles */
    size_t face_count;
    uint32_t *face_tris;
    geom_convex_tri *convex_tris; /* per triangle */
    vec3 others_lo, others_hi;
} geom_shape;

typedef struct {
    double t;                 /* along the (unnormalised) query direction */
    vec3 p;                   /* render space */
    vec3 ng;                  /* unit geometric normal, pbrt-v4 orientation */
    vec3 ns;                  /* unit shading normal (equals ng without mesh normals) */
    const geom_shape *shape;
    unsigned prim;            /* triangle index */
    /* Only when shape->hit_uv: the surface parameters as pbrt-v4's
     * (sphere: phi / phimax and (theta - theta(zmin)) / range; triangles:
     * the mesh's "uv" or (0,0), (1,0), (1,1)) and their render-space
     * partial derivatives. */
    double u, v;
    vec3 dpdu, dpdv;
    /* Screen-space footprint of (u, v): 0 unless geometry_hit_footprint or
     * geometry_hit_set_footprint set it (textured shapes). */
    double dudx, dudy, dvdx, dvdy;
    vec3 dpdx, dpdy; /* the point's own footprint (0 unless one of those set it) */
    /* How far the point may be off the surface a leaving ray must clear
     * (curves: the width there, pbrt-v4's error bound; 0: float rounding
     * only). geometry_leave_origin moves that far off along the normal. */
    double p_error;
} geom_hit;

/* pbrt-v4's footprint of a textured hit: the differential rays meet the
 * tangent plane at p + dp/dx and p + dp/dy, and (du/dx, dv/dx, ...) solve
 * dp/dx = du/dx dp/du + dv/dx dp/dv in the least-squares sense. */
void geometry_hit_footprint(geom_hit *h, vec3 rx_o, vec3 rx_d, vec3 ry_o, vec3 ry_d);
/* Sets the hit's footprint to p + dpdx, p + dpdy, and on a textured shape
 * the (u, v) derivatives that solve it (as geometry_hit_footprint). */
void geometry_hit_set_footprint(geom_hit *h, vec3 dpdx, vec3 dpdy);
/* Where the differential rays meet the hit's tangent plane, as offsets from
 * h->p (pbrt-v4's dpdx, dpdy). False (zeros) when one runs parallel to it. */
bool geometry_hit_dpdxy(const geom_hit *h, vec3 rx_o, vec3 rx_d, vec3 ry_o, vec3 ry_d,
                        vec3 *dpdx, vec3 *dpdy);

/* The material at hit h seen from wo: material_at's choice with its
 * textures evaluated at the hit (into *scratch when it has any). */
const material *geometry_material_at(const geom_hit *h, vec3 wo, material *scratch);

typedef struct geometry geometry;

/* Builds every shape of `sd` (top level and objects, then instances); medium
 * names resolve to indices of sd->media (an unknown name is an error).
 * `materials` are indexed by shape_entity.material; `default_material` is used
 * for -1. Moving shapes and instances move over sd's TransformTimes; keyframes
 * of different handedness are an error. Errors name the shape's
 * file:line:column. With `errs` (may be NULL), a shape's own error (its
 * parameters, material, media) is added there and the shape left out
 * (geom_shape.left_out), so one run reports every shape's; what is not a
 * shape's (memory, Embree) still ends the build. `textures` (may be NULL:
 * none) resolves "texture alpha". Embree runs with the best
 * instruction set the CPU has, or, with `portable_isa`, SSE4.2 on every
 * machine (byte-identical images across x86 machines: other ISAs may find a
 * different triangle at a shared edge). */
hz_status geometry_create(scene_desc *sd, transform render_from_world, const material *materials,
                          size_t material_count, const material *default_material,
                          const texture_set *textures, bool portable_isa, hz_errors *errs,
                          geometry **out, hz_error *err);
/* The shading normal of hit h under material m (geometry_material_at's):
 * h->ns, or bumped by m's displacement texture as pbrt-v4's BumpMap (the
 * texture at (u, v) and one footprint step (or 0.0005) along u and v, the
 * shading frame's dp/du, dp/dv tilted by the differences along the normal;
 * the displace dn/du term is left out: haze has no dn/du) and faced to the
 * geometric normal's side. */
vec3 geometry_shading_normal(const geom_hit *h, const material *m);
/* Curves (curve.c). Primitive `prim` of curve shape s is piece
 * prim & (2^split - 1) of segment prim >> split: its 4 control points (in
 * the shape's space) and its range [u0, u1] of the segment's u. */
void geometry_curve_piece(const geom_shape *s, unsigned prim, vec3 cp[4], double *u0, double *u1);
/* The box of piece `prim`, widened by half its largest width. */
void geometry_curve_bounds(const geom_shape *s, unsigned prim, vec3 *lo, vec3 *hi);
/* pbrt-v4's nearest hit of piece `prim` by o + t d in (tnear, tfar): its t
 * (-1: none) and the segment's u there. */
double geometry_curve_hit(const geom_shape *s, unsigned prim, vec3 o, vec3 d, double tnear,
                          double tfar, double *u_hit);
/* The width of segment `seg` at u, and a ribbon's normal there (pbrt-v4's
 * slerp of the end normals). */
double geometry_curve_width(const geom_shape *s, size_t seg, double u);
vec3 geometry_curve_ribbon_normal(const geom_shape *s, size_t seg, double u);
/* pbrt-v4's AlphaMasked of an area light's point: alpha (its texture at uv
 * and p) >= 1 shows it, <= 0 hides it, between a hash of p decides. */
bool geometry_alpha_masked(const geom_shape *s, vec2 uv, vec3 p);
/* pbrt-v4's (u, v) of sphere `s` at object-space point po (on it). */
vec2 geometry_sphere_uv(const geom_shape *s, vec3 po);
/* Every shape's hits carry (u, v) from now on (a gbuffer film's channels). */
void geometry_require_uv(geometry *g);
void geometry_destroy(geometry *g);

/* The committed Embree scene (RTCScene; declared without Embree's header),
 * for bench/embree_loop.c's bare-Embree yardstick. */
struct RTCSceneTy *geometry_embree_scene(const geometry *g);

/* True when some shape or instance moves (the scene has Embree time steps). */
bool geometry_has_motion(const geometry *g);

/* True when some shape (top-level or of an object) names a medium in its
 * MediumInterface: the only way, besides the camera's medium, for a ray to
 * enter one. */
bool geometry_references_media(const geometry *g);

/* False when the segment o + t d, t in [0, tmax], surely crosses no shape
 * that changes the medium (an interface with different media on its sides):
 * a shadow ray that starts in vacuum then stays in vacuum, so
 * geometry_occluded decides it. Conservative (boxes around those shapes;
 * true whenever one moves or lies in an object). */
bool geometry_may_cross_interface(const geometry *g, vec3 o, vec3 d, double tmax);

/* The render-space box, padded, around every shape when nothing moves (lo >
 * hi when there is no shape): a ray that misses it hits nothing. False when
 * something moves. */
bool geometry_static_box(const geometry *g, vec3 *lo, vec3 *hi);

/* Top-level shapes, in scene_desc.shapes order (index = shape index). */
size_t geometry_shape_count(const geometry *g);
geom_shape *geometry_shape(geometry *g, size_t i);

/* Where the double-precision ray o + t w crosses the surface of hit `h` (found
 * by Embree from o rounded to float, and h->t rounded to float): h->t moved
 * along w onto the tangent plane at h->p, which lies on the surface. Media
 * segments start and end there, so a medium denser than float rounding is
 * bounded where its surface is. */
double geometry_crossing_t(const geom_hit *h, vec3 o, vec3 w);

/* Closest hit of o + t d for t in (tmin, tmax) at scene time `time` (the
 * ray's time, in TransformTimes units). Interface surfaces are hit
 * too (the integrator steps through them by raising tmin, which keeps the
 * ray's line exact). Thread-safe.
 * A ray Embree cannot trace (a non-finite value, or a coordinate beyond
 * Embree's range, ~1.8e18) hits nothing, and is blocked for geometry_occluded:
 * the scene factories keep such rays from arising (core/ray.h, HZ_MAX_COORD);
 * this keeps a missed case from aborting inside Embree. */
bool geometry_intersect(const geometry *g, vec3 o, vec3 d, double tmin, double tmax, double time,
                        geom_hit *hit);
/* Any non-interface surface on o + t d, t in (0, tmax), at scene time `time`. Thread-safe. */
bool geometry_occluded(const geometry *g, vec3 o, vec3 d, double tmax, double time);

/* The point at barycentrics (u, v) of triangle `prim` (u weights its second
 * vertex, v its third) with pbrt-v4's normals, in the shape's own space
 * (object space for a moving shape). */
void geometry_triangle_point(const geom_shape *s, unsigned prim, double u, double v,
                             geom_hit *out);

/* Shadow rays to a point stop this fraction short of it (pbrt-v4's
 * ShadowEpsilon), so the light's own surface is not counted as a blocker. */
#define GEOMETRY_SHADOW_EPSILON 1e-4

/* The medium a ray leaving hit `h` along `w` travels in, when it travelled in
 * `current` before: the side `w` points to for a medium transition (pbrt-v4:
 * outside where the oriented normal points), else unchanged. */
static inline int geometry_medium_after(const geom_hit *h, vec3 w, int current)
{
    const geom_shape *s = h->shape;
    if (s->medium_inside == s->medium_outside)
        return current;
    return v3_dot(w, h->ng) > 0.0 ? s->medium_outside : s->medium_inside;
}

/* What a ray knows of the convex meshes (geom_shape.planes) it has crossed:
 * the one it has left for good (it crossed it outward: the whole mesh lies
 * behind the plane it left through), or the one it has entered. The zero
 * value knows nothing. */
typedef struct {
    const geom_shape *left, *within;
} geom_past;

/* What a ray going on along d past hit h knows (geometry_step_past). */
geom_past geometry_past(const geom_hit *h, vec3 d);

/* A convex mesh whose inside is medium `medium` (-1 or none: NULL): where a
 * ray that starts in that medium most likely is (geom_past.within, which
 * geometry_intersect_past checks). */
const geom_shape *geometry_convex_around(const geometry *g, int medium);

/* geometry_intersect, with what the ray knows. A ray that has left a convex
 * mesh for good and misses the box around every other shape hits nothing;
 * one inside a convex mesh (its origin at tmin behind every plane) whose
 * path to the mesh's exit misses that box hits the exit, found from the
 * planes. Neither asks Embree. The answer is geometry_intersect's (the exit
 * in double, on the plane Embree tests). */
bool geometry_intersect_past(const geometry *g, geom_past past, vec3 o, vec3 d, double tmin,
                             double tmax, double time, geom_hit *hit);

/* The ray parameter just past hit `h` of o + t d: where the line crosses the
 * origin offset of the far side. Staying on the same line (rather than
 * starting a new ray off the surface) keeps what lies behind exactly where it
 * would be without the surface. */
double geometry_step_past(const geom_hit *h, vec3 o, vec3 d);

/* Moves a surface point off the surface along the side of `n` that `w`
 * points to, by a few hundred float ULPs per coordinate (Wächter & Binder,
 * Ray Tracing Gems ch. 6): scale-invariant, so no scene-size epsilon. */
vec3 geometry_offset_origin(vec3 p, vec3 n, vec3 w);
/* The origin of a ray leaving hit h along w: geometry_offset_origin, first
 * moved p_error * (|n.x| + |n.y| + |n.z|) along the normal to w's side (as
 * pbrt-v4's OffsetRayOrigin). */
vec3 geometry_leave_origin(const geom_hit *h, vec3 w);

/* The most memory Embree has held for this geometry (its memory monitor):
 * BVHs and vertex copies, in bytes. */
size_t geometry_embree_peak_bytes(const geometry *g);

#endif
