/* Private to src/geometry: struct geometry (the Embree device and scene, and
 * what the queries keep beside it) with its prototypes and instances, for
 * every file that builds or reads it. Includes no other geometry file but
 * the public geometry.h, so each of them can include it. */
#ifndef HAZE_GEOMETRY_GEOMETRY_TYPES_H
#define HAZE_GEOMETRY_GEOMETRY_TYPES_H

#include <embree3/rtcore.h>

#include "geometry/geometry.h"

typedef struct {
    RTCScene scene;
    geom_shape *shapes;
    size_t shape_count;
} prototype;

/* An Embree instance: of an object's prototype (ObjectInstance), or of the
 * private scene of a moving top-level shape. */
typedef struct {
    transform render_from_instance; /* static instances */
    geom_motion motion;             /* moving ones: motion.steps != NULL */
    const geom_shape *shapes;       /* the instanced scene's shapes, by Embree geomID */
    RTCScene own_scene;             /* a moving shape's scene (released with the geometry) */
} instance;

struct geometry {
    RTCDevice device;
    RTCScene scene;
    geom_shape *shapes;       /* top-level; Embree geomID = index */
    size_t shape_count;
    prototype *objects;
    size_t object_count;
    instance *instances;      /* Embree geomID = shape_count + index */
    size_t instance_count;
    /* Per top-level shape, the instance that moves it (NULL: static); the
     * table itself is NULL when no shape moves. */
    instance **shape_instances;
    bool motion;              /* some shape or instance moves */
    /* Render-space boxes around the static top-level shapes that change the
     * medium (interface material, inside != outside); `interfaces_anywhere`
     * when such a shape moves, lies in an object or is one of too many to
     * test one by one (then every ray may cross one). */
    vec3 (*interface_boxes)[2];
    size_t interface_box_count;
    bool interfaces_anywhere;
    /* A render-space box around every static shape (padded as the interface
     * boxes): rays that miss it skip Embree. Not kept when something moves. */
    bool has_world_box;
    vec3 world_box[2];
    /* geometry_convex_around, per medium (NULL: none); NULL when no shape
     * has planes. */
    const geom_shape **convex_around;
    size_t convex_around_count;
    /* The largest convex mesh (geom_shape.planes), or NULL: a ray that knows
     * nothing (geom_past's zero value) and misses the box of the other shapes
     * finds its entry from the planes (geometry_intersect_past). */
    const geom_shape *convex_entry;
    double start_time, end_time; /* TransformTimes */
    const texture_set *textures; /* for "texture alpha" while building */
    /* Bytes Embree holds (its memory monitor): now and at most. */
    _Atomic long long embree_bytes, embree_peak;
};

#endif
