/* Private to src/geometry: the small convex meshes that change the medium
 * (convex_mesh.c), found once the scene is built (embree_scene.c). */
#ifndef HAZE_GEOMETRY_CONVEX_MESH_H
#define HAZE_GEOMETRY_CONVEX_MESH_H

#include "geometry/geometry.h"

/* geom_shape.planes and the boxes of the other shapes, for the small convex
 * meshes that change the medium, when nothing moves or is instanced; and
 * geometry_convex_around's table. */
hz_status geom_find_convex_interfaces(geometry *g, size_t medium_count, hz_error *err);

#endif
