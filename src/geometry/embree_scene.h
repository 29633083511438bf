/* Private to src/geometry: struct geometry (the Embree device and scene, and
 * what the queries keep beside it) and the steps that build it, shared by
 * embree_scene.c (the device, the top-level scene, geometry_create) and
 * instances.c (objects, instances, motion). */
#ifndef HAZE_GEOMETRY_EMBREE_SCENE_H
#define HAZE_GEOMETRY_EMBREE_SCENE_H

#include <string.h>

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

/* A scene with haze's flags and build quality, or NULL. */
RTCScene geom_new_scene(RTCDevice device);
/* rtcNewScene failed: the device's error, or a generic message. */
hz_status geom_new_scene_failed(RTCDevice device, hz_error *err);
/* HZ_OK unless Embree reported an error (out of memory named as such). */
hz_status geom_check_device(RTCDevice device, hz_error *err);
/* A shape's own error (it has a place) goes to `errs` when there is one: the
 * shape is left out and the build goes on. */
hz_status geom_shape_failed(geom_shape *s, hz_errors *errs, hz_error *err);

/* Whether a transform differs at the two TransformTimes (only then is an
 * animated transform built: equal keyframes build exactly as without motion). */
static inline bool geom_moves(const transform *start, const transform *end)
{
    return memcmp(&start->m, &end->m, sizeof start->m) != 0;
}

/* instances.c: the ObjectBegin prototypes, the ObjectInstances (after the
 * top-level shapes: their geomIDs follow), and a moving top-level shape i
 * (`a` its motion) in a scene of its own. */
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
