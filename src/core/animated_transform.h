/* pbrt-v4's AnimatedTransform: two keyframe transforms at times t0 and t1,
 * interpolated by decomposing each into translation T, rotation R (a unit
 * quaternion, slerped) and the remaining scale/shear S (lerped elementwise):
 * M = T R S. Times before t0 (after t1) give the start (end) transform. A
 * transform whose keyframes are equal is static and never decomposed, so a
 * scene without motion pays nothing. Rotations are interpolated along the
 * shorter arc. */
#ifndef HAZE_CORE_ANIMATED_TRANSFORM_H
#define HAZE_CORE_ANIMATED_TRANSFORM_H

#include <stdbool.h>

#include "core/transform.h"
#include "core/vec.h"

typedef struct {
    double x, y, z, w;
} quat;

typedef struct {
    transform start, end;
    double start_time, end_time;
    bool animated;
    /* decomposition of start and end (animated only) */
    vec3 translation[2];
    quat rotation[2];
    mat4 scale[2];
} animated_transform;

animated_transform animated_transform_make(transform start, double start_time, transform end,
                                           double end_time);
/* A static one. */
animated_transform animated_transform_static(transform t);

transform animated_transform_at(const animated_transform *a, double time);

/* Polar decomposition of the affine part of m: m = T R S with R a rotation
 * (det +1; a reflection is moved into S). */
void transform_decompose(const mat4 *m, vec3 *translation, quat *rotation, mat4 *scale);
/* The rotation of a unit quaternion (column-vector convention, as transform.h). */
mat4 quat_to_mat4(quat q);
quat quat_from_mat4(const mat4 *rotation);
/* Spherical linear interpolation, t in [0, 1] (pbrt-v4's Slerp). */
quat quat_slerp(double t, quat a, quat b);

#endif
