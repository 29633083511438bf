/* The object-space geometry a shape becomes (shape.h's factories, ply.h's
 * reader, curve.h's curves), in a header of its own so that each of them
 * includes this rather than each other. */
#ifndef HAZE_SCENE_SHAPE_GEOMETRY_H
#define HAZE_SCENE_SHAPE_GEOMETRY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef enum { GEOMETRY_TRIANGLES, GEOMETRY_SPHERE, GEOMETRY_CURVES } geometry_kind;

/* pbrt-v4's curve types: a ribbon facing the ray ("flat"), the same ribbon
 * shaded as a tube ("cylinder"), a ribbon turned by given normals ("ribbon"). */
typedef enum { CURVE_FLAT, CURVE_CYLINDER, CURVE_RIBBON } curve_type;

typedef struct {
    geometry_kind kind;
    /* triangles, in object space */
    size_t vertex_count, triangle_count;
    double *p;          /* 3 * vertex_count */
    double *n;          /* 3 * vertex_count, or NULL */
    double *uv;         /* 2 * vertex_count, or NULL */
    bool quads;         /* bilinearmesh: triangles 2i, 2i + 1 are quad i's halves */
    uint32_t *indices;  /* 3 * triangle_count */
    /* sphere, centred at the object-space origin; a part of it when zmin >
     * -radius, zmax < radius or phimax < 2 pi (pbrt-v4's partial sphere) */
    double radius;
    double zmin, zmax, phimax;
    /* curve: cubic Bezier segments (pbrt-v4's "curve" with its quadratic
     * segments raised to cubic and b-splines converted), in object space */
    curve_type curve;
    size_t segment_count;
    double *cp;      /* 12 per segment: its 4 control points */
    double *width;   /* 2 per segment: the width at its ends */
    double *normals; /* ribbon: 6 per segment, the unit normals at its ends; else NULL */
    int split;       /* "splitdepth": each segment intersected as 2^split pieces */
    /* pbrt-v4's Area() of the shape as one emitter (sphere, disk, cylinder:
     * the analytic surface in object space, as pbrt-v4 computes it, whatever
     * the transform); 0 for meshes, each of whose triangles (bilinearmesh:
     * quads) is an emitter of its own. What an area light's "power" divides. */
    double unit_area;
    /* pbrt-v4's "alpha": a constant (1: opaque, the default) or the name of a
     * float texture ("texture alpha", resolved by geometry_create). */
    double alpha;
    const char *alpha_texture;
} shape_geometry;

void shape_geometry_free(shape_geometry *g);

#endif
