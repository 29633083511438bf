/* Private to src/geometry: one shape as Embree geometry (shape_build.c):
 * what every shape shares (material, media, alpha, the filters) and triangle
 * meshes; spheres and curves come from user_shapes.h. A shape that fails
 * with a place is left out. */
#ifndef HAZE_GEOMETRY_SHAPE_BUILD_H
#define HAZE_GEOMETRY_SHAPE_BUILD_H

#include <embree3/rtcore.h>

#include "geometry/geometry.h"

/* Builds shape `se` into *out and attaches it to `scene` as `geom_id` (an
 * empty mesh attaches nothing); `space_from_object` puts it in the scene's
 * space. */
hz_status geom_build_shape(RTCDevice device, RTCScene scene, unsigned geom_id,
                           const scene_desc *sd, shape_entity *se, transform space_from_object,
                           const material *materials, size_t material_count,
                           const material *default_material, const texture_set *textures,
                           geom_shape *out, hz_error *err);

/* A shape's own error (it has a place) goes to `errs` when there is one: the
 * shape is left out and the build goes on. */
hz_status geom_shape_failed(geom_shape *s, hz_errors *errs, hz_error *err);

#endif
