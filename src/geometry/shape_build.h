/* Private to src/geometry: one shape as Embree geometry. shape_build.c does
 * what every shape shares (material, media, alpha, the filters) and triangle
 * meshes; user_shapes.c makes the user geometry of spheres and curves. */
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

/* A sphere's Embree user geometry, solved in object space in double (out's
 * sphere fields filled from g). */
RTCGeometry geom_build_sphere(RTCDevice device, const shape_geometry *g,
                              transform space_from_object, geom_shape *out);

/* pbrt-v4's curve: Embree user geometry of 2^splitdepth pieces per segment,
 * intersected by pbrt-v4's algorithm (curve.c). Widths scale with the
 * transform (its volume's cube root: the scale of a similarity). */
hz_status geom_build_curves(RTCDevice device, shape_entity *se, const shape_geometry *g,
                            transform space_from_object, bool interface, geom_shape *out,
                            RTCGeometry *geom_out, hz_error *err);

#endif
