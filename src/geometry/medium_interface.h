/* Private to src/geometry: the shapes that change the medium (also for the
 * small convex meshes among them, convex_mesh.c) and the boxes around them,
 * found once the scene is built (medium_interface.c). */
#ifndef HAZE_GEOMETRY_MEDIUM_INTERFACE_H
#define HAZE_GEOMETRY_MEDIUM_INTERFACE_H

#include "geometry/geometry.h"

static inline bool geom_changes_medium(const geom_shape *s)
{
    return !s->left_out && s->material->kind == MATERIAL_INTERFACE &&
           s->medium_inside != s->medium_outside;
}

/* The render-space box of a static shape, padded well beyond the rounding
 * of Embree's float hits. */
void geom_shape_box(const geom_shape *s, vec3 *lo_out, vec3 *hi_out);

/* Fills g's interface boxes (see struct geometry). */
hz_status geom_find_interfaces(geometry *g, hz_error *err);

#endif
