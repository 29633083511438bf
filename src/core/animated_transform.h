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

/* ---- Embree's quaternion motion ------------------------------------------
 * Embree moves an instance between time steps given as
 * RTCQuaternionDecomposition: M = T R U, U upper triangular (scales on the
 * diagonal, skews above it), R a unit quaternion, T a translation. Between
 * two steps Embree lerps T and U and slerps R along the shorter arc, with a
 * normalised lerp when cos(angle) > 0.9995 (rotations under 3.6 degrees).
 *
 * When pbrt's S of both keyframes is diagonal (rotations, translations and
 * scales along the object's axes, reflections included) the QR factors below
 * are pbrt's T R S, so one Embree segment moves exactly as the
 * AnimatedTransform (up to the normalised lerp, whose angle is off by at most
 * 1.0e-6 rad). A non-diagonal S (shear, or a scale along rotated axes) has no
 * such form: pbrt interpolates the symmetric S, Embree the triangular U, and
 * the paths differ between the steps; more steps sampled from the
 * AnimatedTransform bring them together (animated_transform_steps_error). */
typedef struct {
    double scale[3]; /* U00, U11, U22 */
    double skew[3];  /* U01 (xy), U02 (xz), U12 (yz) */
    quat rotation;   /* unit */
    vec3 translation;
} quat_decomposition;

/* The QR factorisation of the affine part of m: m = T R U with R a rotation,
 * U upper triangular with positive U00 and U11 (U22 carries the sign of the
 * determinant). False when m is not affine or its 3x3 part is singular. */
bool transform_decompose_qr(const mat4 *m, quat_decomposition *out);
/* T R U of a decomposition. */
mat4 quat_decomposition_matrix(const quat_decomposition *d);
/* Embree 3's interpolation between time steps a (u = 0) and b (u = 1). */
mat4 quat_decomposition_interpolate(const quat_decomposition *a, const quat_decomposition *b,
                                    double u);
/* `segments` + 1 time steps of an animated `a` at equal intervals of
 * [start_time, end_time], each the QR decomposition of animated_transform_at
 * (the first and last are the keyframes), quaternions on the shorter arc from
 * their predecessor. False when a step is singular. */
bool animated_transform_time_steps(const animated_transform *a, int segments,
                                   quat_decomposition *steps);
/* Embree's motion over `segments` + 1 time steps at u in [0, 1]: the segment
 * floor(u * segments) (clamped), interpolated at the fraction left. */
mat4 quat_motion_at(const quat_decomposition *steps, int segments, double u);
/* How far Embree's interpolation of `steps` strays from `a`: the largest
 * distance between the two images of a corner of the box [lo, hi] (in a's
 * source space) at the quarter points of every segment, divided by the largest
 * distance of those corners from the origin (render space: the camera). */
double animated_transform_steps_error(const animated_transform *a,
                                      const quat_decomposition *steps, int segments, vec3 lo,
                                      vec3 hi);

#endif
