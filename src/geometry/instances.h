/* Private to src/geometry: ObjectBegin prototypes, ObjectInstances and
 * motion (instances.c), built into the top-level scene by embree_scene.c. */
#ifndef HAZE_GEOMETRY_INSTANCES_H
#define HAZE_GEOMETRY_INSTANCES_H

#include <string.h>

#include "geometry/geometry.h"

/* Whether a transform differs at the two TransformTimes (only then is an
 * animated transform built: equal keyframes build exactly as without motion). */
static inline bool geom_moves(const transform *start, const transform *end)
{
    return memcmp(&start->m, &end->m, sizeof start->m) != 0;
}

/* The ObjectBegin prototypes, the ObjectInstances (after the top-level
 * shapes: their geomIDs follow), and a moving top-level shape i (`a` its
 * motion) in a scene of its own. */
hz_status geom_build_objects(geometry *g, scene_desc *sd, const material *materials,
                             size_t material_count, const material *default_material,
                             hz_errors *errs, hz_error *err);
hz_status geom_build_instances(geometry *g, scene_desc *sd, transform render_from_world,
                               hz_error *err);
hz_status geom_build_moving_shape(geometry *g, scene_desc *sd, size_t i,
                                  const animated_transform *a, const material *materials,
                                  size_t material_count, const material *default_material,
                                  hz_error *err);

#endif
