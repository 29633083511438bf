/* Private to src/geometry: spheres and curves as Embree user geometry
 * (user_shapes.c), built for shape_build.c once a shape's material, media
 * and alpha are set. */
#ifndef HAZE_GEOMETRY_USER_SHAPES_H
#define HAZE_GEOMETRY_USER_SHAPES_H

#include <embree3/rtcore.h>

#include "geometry/geometry.h"

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
