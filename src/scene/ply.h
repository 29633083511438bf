/* PLY mesh reader: ascii and binary little-endian (big-endian too), vertex
 * x y z, optional nx ny nz and u v (or s t, texture_u texture_v), faces as a
 * list property (vertex_indices or vertex_index) of triangles and quads
 * (quads split into two triangles). */
#ifndef HAZE_SCENE_PLY_H
#define HAZE_SCENE_PLY_H

#include "core/error.h"
#include "scene/shape_geometry.h"

/* Fills a GEOMETRY_TRIANGLES shape_geometry. Errors name the file and what is wrong. */
hz_status ply_read(const char *path, shape_geometry *out, hz_error *err);

#endif
