/* Shape factories: turn a shape_entity's parameters into object-space geometry.
 * "trianglemesh" (indices P N uv), "plymesh" (filename, relative to the top-level
 * scene file's directory), "sphere" (radius), "disk" (height radius innerradius),
 * "bilinearmesh" (indices P N uv, each quad split into two triangles),
 * "curve" (P basis degree type N width width0 width1 splitdepth). */
#ifndef HAZE_SCENE_SHAPE_H
#define HAZE_SCENE_SHAPE_H

#include "core/error.h"
#include "scene/scene_desc.h"
#include "scene/shape_geometry.h"

hz_status shape_geometry_create(shape_entity *se, shape_geometry *out, hz_error *err);

#endif
