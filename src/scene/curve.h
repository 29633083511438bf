/* pbrt-v4's "curve" shape (curve.c), one of shape.h's factories. */
#ifndef HAZE_SCENE_CURVE_H
#define HAZE_SCENE_CURVE_H

#include "core/error.h"
#include "scene/scene_desc.h"
#include "scene/shape_geometry.h"

/* Fills a GEOMETRY_CURVES shape_geometry; errors name the parameter. */
hz_status shape_curve_create(shape_entity *se, shape_geometry *g, hz_error *err);

#endif
