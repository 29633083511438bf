/* ObjectBegin prototypes and ObjectInstances, and motion: Embree instances of
 * a prototype's scene (pbrt-v4's TransformedPrimitive) or, with Embree's
 * quaternion time steps, of a moving instance or of a moving shape's own
 * scene (pbrt-v4's AnimatedPrimitive). */
#include "geometry/embree_device.h"
#include "geometry/geometry_types.h"
#include "geometry/instances.h"
#include "geometry/shape_build.h"

#include <stdlib.h>

hz_status geom_build_objects(geometry *g, scene_desc *sd, const material *materials,
                             size_t material_count, const material *default_material,
                             hz_errors *errs, hz_error *err)
{
    g->objects = calloc(sd->object_count ? sd->object_count : 1, sizeof *g->objects);
    if (!g->objects)
        return hz_fail(err, "out of memory");
    g->object_count = sd->object_count;
    for (size_t o = 0; o < sd->object_count; ++o) {
        object_entity *oe = &sd->objects[o];
        prototype *pr = &g->objects[o];
        pr->scene = geom_new_scene(g->device);
        if (!pr->scene)
            return geom_new_scene_failed(g->device, err);
        pr->shapes = calloc(oe->shape_count ? oe->shape_count : 1, sizeof *pr->shapes);
        if (!pr->shapes)
            return hz_fail(err, "out of memory");
        pr->shape_count = oe->shape_count;
        for (size_t i = 0; i < oe->shape_count; ++i) {
            shape_entity *se = &sd->object_shapes[oe->first_shape + i];
            if (se->has_area_light) {
                hz_fail_at(err, se->entity.loc,
                           "area lights inside object instances are not supported "
                           "(pbrt-v4 refuses them too)");
                if (geom_shape_failed(&pr->shapes[i], errs, err) != HZ_OK)
                    return HZ_ERROR;
                continue;
            }
            /* Prototype space = the object's world space; instances carry
             * render_from_world to the instance transform. */
            transform space_from_object =
                transform_compose(transform_identity(), se->world_from_object);
            if (geom_build_shape(g->device, pr->scene, (unsigned)i, sd, se, space_from_object,
                                 materials, material_count, default_material, g->textures,
                                 &pr->shapes[i], err) != HZ_OK &&
                geom_shape_failed(&pr->shapes[i], errs, err) != HZ_OK)
                return HZ_ERROR;
        }
        rtcCommitScene(pr->scene);
        if (geom_check_device(g->device, err) != HZ_OK)
            return HZ_ERROR;
    }
    return HZ_OK;
}

transform geom_motion_at(const geom_motion *m, double time)
{
    double u = hz_clamp((time - m->start_time) / (m->end_time - m->start_time), 0.0, 1.0);
    /* Embree sees the ray time as a float. */
    mat4 x = quat_motion_at(m->steps, m->segments, (double)(float)u);
    transform t;
    if (!transform_from_matrix(x, &t)) { /* not for steps of one handedness */
        mat4 x0 = quat_decomposition_matrix(&m->steps[0]);
        if (!transform_from_matrix(x0, &t))
            t = transform_identity();
    }
    return t;
}

/* Attaches to the top-level scene, as `geom_id`, an instance of `child` that
 * moves with `a` (animated): time steps doubled until Embree's path follows
 * a's within GEOMETRY_MOTION_TOLERANCE over the child's bounds. */
static hz_status attach_moving(geometry *g, instance *in, RTCScene child,
                               const animated_transform *a, unsigned geom_id, file_loc loc,
                               hz_error *err)
{
    /* pbrt-v4 lerps S from one keyframe to the other: with a reflection at
     * one end only it passes through a singular transform. */
    if (transform_swaps_handedness(&a->start) != transform_swaps_handedness(&a->end))
        return hz_fail_at(err, loc,
                          "the start and end transforms differ in handedness (one mirrors, the "
                          "other does not): the motion would pass through a flat transform");
    struct RTCBounds b;
    rtcGetSceneBounds(child, &b);
    if (!(b.lower_x <= b.upper_x && b.lower_y <= b.upper_y && b.lower_z <= b.upper_z))
        return HZ_OK; /* nothing to intersect */
    vec3 lo = v3(b.lower_x, b.lower_y, b.lower_z), hi = v3(b.upper_x, b.upper_y, b.upper_z);
    int n = 1;
    quat_decomposition *steps = NULL;
    for (;;) {
        quat_decomposition *grown = realloc(steps, (size_t)(n + 1) * sizeof *steps);
        if (!grown) {
            free(steps);
            return hz_fail(err, "out of memory");
        }
        steps = grown;
        if (!animated_transform_time_steps(a, n, steps)) {
            free(steps);
            return hz_fail_at(err, loc, "the animated transform is singular between its keyframes");
        }
        if (n >= GEOMETRY_MAX_SEGMENTS ||
            animated_transform_steps_error(a, steps, n, lo, hi) <= GEOMETRY_MOTION_TOLERANCE)
            break;
        n *= 2;
    }
    in->motion = (geom_motion){a->start_time, a->end_time, n, steps};

    RTCGeometry geom = rtcNewGeometry(g->device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(geom, child);
    rtcSetGeometryTimeStepCount(geom, (unsigned)n + 1);
    for (int k = 0; k <= n; ++k) {
        const quat_decomposition *d = &steps[k];
        struct RTCQuaternionDecomposition qd;
        rtcInitQuaternionDecomposition(&qd);
        rtcQuaternionDecompositionSetScale(&qd, (float)d->scale[0], (float)d->scale[1],
                                           (float)d->scale[2]);
        rtcQuaternionDecompositionSetSkew(&qd, (float)d->skew[0], (float)d->skew[1],
                                          (float)d->skew[2]);
        rtcQuaternionDecompositionSetQuaternion(&qd, (float)d->rotation.w, (float)d->rotation.x,
                                                (float)d->rotation.y, (float)d->rotation.z);
        rtcQuaternionDecompositionSetTranslation(&qd, (float)d->translation.x,
                                                 (float)d->translation.y,
                                                 (float)d->translation.z);
        rtcSetGeometryTransformQuaternion(geom, (unsigned)k, &qd);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(g->scene, geom, geom_id);
    rtcReleaseGeometry(geom);
    g->motion = true;
    return HZ_OK;
}

/* A moving top-level shape: built in object space in a scene of its own,
 * instanced with its motion as Embree geomID i. Like pbrt-v4's animated
 * shapes (created with an identity transform), its normals do not flip with
 * the handedness of the transform. */
hz_status geom_build_moving_shape(geometry *g, scene_desc *sd, size_t i,
                                  const animated_transform *a, const material *materials,
                                  size_t material_count, const material *default_material,
                                  hz_error *err)
{
    instance *in = calloc(1, sizeof *in);
    if (!in)
        return hz_fail(err, "out of memory");
    g->shape_instances[i] = in;
    in->own_scene = geom_new_scene(g->device);
    if (!in->own_scene)
        return geom_new_scene_failed(g->device, err);
    in->shapes = &g->shapes[i];
    shape_entity *se = &sd->shapes[i];
    if (geom_build_shape(g->device, in->own_scene, 0, sd, se, transform_identity(), materials,
                         material_count, default_material, g->textures, &g->shapes[i],
                         err) != HZ_OK)
        return HZ_ERROR;
    rtcCommitScene(in->own_scene);
    if (geom_check_device(g->device, err) != HZ_OK ||
        attach_moving(g, in, in->own_scene, a, (unsigned)i, se->entity.loc, err) != HZ_OK)
        return HZ_ERROR;
    if (in->motion.steps)
        g->shapes[i].motion = &in->motion;
    return HZ_OK;
}

hz_status geom_build_instances(geometry *g, scene_desc *sd, transform render_from_world,
                               hz_error *err)
{
    g->instances = calloc(sd->instance_count ? sd->instance_count : 1, sizeof *g->instances);
    if (!g->instances)
        return hz_fail(err, "out of memory");
    g->instance_count = sd->instance_count;
    for (size_t i = 0; i < sd->instance_count; ++i) {
        instance_entity *ie = &sd->instances[i];
        if (ie->object >= g->object_count)
            return hz_fail_at(err, ie->loc, "instance of unknown object %zu", ie->object);
        instance *in = &g->instances[i];
        in->shapes = g->objects[ie->object].shapes;
        in->render_from_instance = transform_compose(render_from_world, ie->world_from_instance);
        unsigned geom_id = (unsigned)(g->shape_count + i);
        if (geom_moves(&ie->world_from_instance, &ie->world_from_instance_end)) {
            animated_transform a = animated_transform_make(
                in->render_from_instance, sd->transform_start_time,
                transform_compose(render_from_world, ie->world_from_instance_end),
                sd->transform_end_time);
            if (a.animated) {
                if (attach_moving(g, in, g->objects[ie->object].scene, &a, geom_id, ie->loc,
                                  err) != HZ_OK)
                    return HZ_ERROR;
                continue;
            }
        }
        float xfm[12];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                xfm[4 * r + c] = (float)in->render_from_instance.m.m[r][c];
        RTCGeometry geom = rtcNewGeometry(g->device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(geom, g->objects[ie->object].scene);
        rtcSetGeometryTimeStepCount(geom, 1);
        rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(g->scene, geom, geom_id);
        rtcReleaseGeometry(geom);
    }
    return HZ_OK;
}
