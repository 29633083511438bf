/* 4x4 affine/projective transforms with cached inverses, following pbrt-v4's
 * conventions (left-handed; points are column vectors: p' = M p).
 * Name variables `a_from_b` so that compose(a_from_b, b_from_c) reads right. */
#ifndef HAZE_CORE_TRANSFORM_H
#define HAZE_CORE_TRANSFORM_H

#include <stdbool.h>

#include "core/vec.h"

typedef struct {
    double m[4][4];
} mat4;

typedef struct {
    mat4 m, m_inv;
} transform;

mat4 mat4_identity(void);
mat4 mat4_mul(mat4 a, mat4 b);
mat4 mat4_transpose(mat4 a);
/* Returns false (and leaves *out untouched) when `a` is singular. */
bool mat4_inverse(mat4 a, mat4 *out);

transform transform_identity(void);
/* Returns false when `m` is singular. */
bool transform_from_matrix(mat4 m, transform *out);
transform transform_inverse(transform t);
/* a_from_c = compose(a_from_b, b_from_c). */
transform transform_compose(transform a_from_b, transform b_from_c);
bool transform_is_identity(transform t);

transform transform_translate(vec3 delta);
transform transform_scale(vec3 s);
/* Rotation by `degrees` about `axis` (normalised here); pbrt's Rotate. */
transform transform_rotate(double degrees, vec3 axis);
/* pbrt-v4 LookAt: returns camera_from_world. False when eye == look or up is
 * parallel to the viewing direction. */
bool transform_look_at(vec3 eye, vec3 look, vec3 up, transform *camera_from_world);
/* pbrt-v4 Perspective(fov, n, f): screen_from_camera. */
transform transform_perspective(double fov_degrees, double z_near, double z_far);
/* pbrt-v4 Orthographic(n, f): screen_from_camera. */
transform transform_orthographic(double z_near, double z_far);

vec3 transform_point(const transform *t, vec3 p);   /* with homogeneous divide */
vec3 transform_vector(const transform *t, vec3 v);
vec3 transform_normal(const transform *t, vec3 n); /* by the inverse transpose */
/* The bounding box [*out_lo, *out_hi] of the image of the box [lo, hi]
 * (its eight corners mapped: exact for affine transforms). */
void transform_box(const transform *t, vec3 lo, vec3 hi, vec3 *out_lo, vec3 *out_hi);
/* Determinant of the 3x3 (linear) part. */
double transform_det3(const transform *t);
/* True when the transform flips handedness (negative determinant of the 3x3). */
bool transform_swaps_handedness(const transform *t);

#endif
