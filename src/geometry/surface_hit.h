/* Private to src/geometry: a hit's point, normals and surface parameters on
 * each kind of shape (surface_hit.c), for the queries that find hits
 * (intersect.c, convex_mesh.c) and the intersectors and filters that look at
 * candidate hits (user_shapes.c, alpha.c). */
#ifndef HAZE_GEOMETRY_SURFACE_HIT_H
#define HAZE_GEOMETRY_SURFACE_HIT_H

#include "geometry/geometry.h"

/* Vertex i of a triangle mesh: Embree's float vertex, exactly. */
static inline vec3 geom_vertex(const geom_shape *s, uint32_t i)
{
    return v3(s->p[3 * i], s->p[3 * i + 1], s->p[3 * i + 2]);
}

/* Fills p, ng, ns in the shape's own space (render or prototype), for the
 * ray o + t d of that space; d = 0 asks for the point at barycentrics (u, v). */
void geom_surface_at(const geom_shape *s, unsigned prim, double u, double v, vec3 o, vec3 d,
                     double t, geom_hit *hit);

/* pbrt-v4's sphere parameters at the object-space point po. */
void geom_sphere_uv(const geom_shape *s, vec3 po, geom_hit *hit);

/* The (u, v) of triangle prim's three corners: the mesh's "uv", or pbrt-v4's
 * defaults (a bilinear patch's for a quad's halves). */
void geom_triangle_corner_uv(const geom_shape *s, unsigned prim, double uv[3][2]);

/* A curve hit at Embree's curve parameter u of primitive prim and its t
 * along o + t d, as pbrt-v4's Curve::Intersect reports it; returns its v. */
double geom_curve_at(const geom_shape *s, unsigned prim, double u, vec3 o, vec3 d, double t,
                     geom_hit *hit);

#endif
