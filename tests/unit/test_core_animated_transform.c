/* pbrt-v4's AnimatedTransform: decomposition, slerp and interpolation. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "core/animated_transform.h"
#include "unit/assert_util.h"

static void assert_mat_near(const mat4 *a, const mat4 *b, double tol)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            assert_near(a->m[i][j], b->m[i][j], tol);
}

static transform random_trs(uint64_t *s, bool reflect)
{
    vec3 axis = v3(rng_next(s) - 0.5, rng_next(s) - 0.5, rng_next(s) - 0.5);
    transform t = transform_compose(
        transform_translate(v3(10 * rng_next(s), -5 * rng_next(s), rng_next(s))),
        transform_compose(transform_rotate(360 * rng_next(s), axis),
                          transform_scale(v3((reflect ? -1 : 1) * (0.2 + rng_next(s)),
                                             0.2 + 3 * rng_next(s), 0.2 + rng_next(s)))));
    return t;
}

/* T R S reproduces the matrix, R is a proper rotation, for reflections too. */
static void test_decompose_round_trip(void **state)
{
    (void)state;
    uint64_t s = 7;
    for (int k = 0; k < 200; ++k) {
        transform t = random_trs(&s, k % 3 == 0);
        vec3 tr;
        quat q;
        mat4 sc;
        transform_decompose(&t.m, &tr, &q, &sc);
        assert_near(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 1.0, 1e-12);
        mat4 m = mat4_mul(quat_to_mat4(q), sc);
        m.m[0][3] = tr.x;
        m.m[1][3] = tr.y;
        m.m[2][3] = tr.z;
        assert_mat_near(&m, &t.m, 1e-9);
        /* S is symmetric for a rotation times a scale: the polar factor */
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                assert_near(sc.m[i][j], sc.m[j][i], 1e-9);
    }
}

static void test_quat_matrix_round_trip(void **state)
{
    (void)state;
    uint64_t s = 11;
    for (int k = 0; k < 500; ++k) {
        /* include the trace <= 0 branches: angles near 180 degrees */
        double deg = k % 2 ? 170 + 10 * rng_next(&s) : 360 * rng_next(&s);
        transform r = transform_rotate(deg, v3(rng_next(&s) - .5, rng_next(&s) - .5,
                                               rng_next(&s) - .5));
        quat q = quat_from_mat4(&r.m);
        mat4 back = quat_to_mat4(q);
        assert_mat_near(&back, &r.m, 1e-12);
    }
}

static double quat_angle_deg(quat a, quat b)
{
    double d = fabs(a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w);
    return 2.0 * acos(fmin(1.0, d)) * 180.0 / HZ_PI;
}

/* Slerp moves at constant angular speed along the shorter arc. */
static void test_slerp(void **state)
{
    (void)state;
    transform a = transform_rotate(10, v3(1, 2, 3)), b = transform_rotate(150, v3(1, 2, 3));
    quat qa = quat_from_mat4(&a.m), qb = quat_from_mat4(&b.m);
    for (int i = 0; i <= 10; ++i) {
        double t = i / 10.0;
        quat q = quat_slerp(t, qa, qb);
        assert_near(quat_angle_deg(q, qa), 140 * t, 1e-9);
        transform want = transform_rotate(10 + 140 * t, v3(1, 2, 3));
        mat4 got = quat_to_mat4(q);
        assert_mat_near(&got, &want.m, 1e-12);
    }
    /* equal quaternions: no division by zero */
    quat q = quat_slerp(0.3, qa, qa);
    assert_near(quat_angle_deg(q, qa), 0.0, 1e-6);
}

static void test_interpolation(void **state)
{
    (void)state;
    transform t0 = transform_compose(transform_translate(v3(1, 2, 3)), transform_scale(v3(1, 1, 1)));
    transform t1 = transform_compose(
        transform_translate(v3(3, 2, -1)),
        transform_compose(transform_rotate(90, v3(0, 0, 1)), transform_scale(v3(3, 1, 1))));
    animated_transform a = animated_transform_make(t0, 2.0, t1, 4.0);
    assert_true(a.animated);
    /* the keyframes themselves, exactly, and clamping outside [t0, t1] */
    transform x = animated_transform_at(&a, 2.0);
    assert_memory_equal(&x, &t0, sizeof x);
    x = animated_transform_at(&a, -100.0);
    assert_memory_equal(&x, &t0, sizeof x);
    x = animated_transform_at(&a, 4.0);
    assert_memory_equal(&x, &t1, sizeof x);
    x = animated_transform_at(&a, 1e9);
    assert_memory_equal(&x, &t1, sizeof x);
    /* halfway: translation lerped, 45 degrees, scale 2 along the object's x */
    x = animated_transform_at(&a, 3.0);
    transform want = transform_compose(
        transform_translate(v3(2, 2, 1)),
        transform_compose(transform_rotate(45, v3(0, 0, 1)), transform_scale(v3(2, 1, 1))));
    assert_mat_near(&x.m, &want.m, 1e-12);
    mat4 id;
    id = mat4_mul(x.m, x.m_inv);
    mat4 ident = mat4_identity();
    assert_mat_near(&id, &ident, 1e-12);
    /* a rotation is not a matrix lerp: points keep their distance to the axis */
    transform r0 = transform_identity(), r1 = transform_rotate(120, v3(0, 1, 0));
    animated_transform ar = animated_transform_make(r0, 0, r1, 1);
    for (int i = 0; i <= 16; ++i) {
        transform ti = animated_transform_at(&ar, i / 16.0);
        vec3 p = transform_point(&ti, v3(1, 0, 0));
        assert_near(v3_length(p), 1.0, 1e-12);
        assert_near(atan2(-p.z, p.x) * 180 / HZ_PI, 120.0 * i / 16.0, 1e-9);
    }
}

/* Equal keyframes, or an empty time span, are static: never decomposed. */
static void test_static(void **state)
{
    (void)state;
    uint64_t s = 3;
    transform t = random_trs(&s, false);
    animated_transform a = animated_transform_make(t, 0, t, 1);
    assert_false(a.animated);
    transform x = animated_transform_at(&a, 0.37);
    assert_memory_equal(&x, &t, sizeof x);
    animated_transform b = animated_transform_make(t, 1, transform_identity(), 1);
    assert_false(b.animated);
    x = animated_transform_at(&b, 5);
    assert_memory_equal(&x, &t, sizeof x);
}

/* ---- Embree's quaternion motion ---- */

/* A random affine transform with shear: T times a random 3x3 with det > 0
 * (or < 0 with `reflect`). */
static transform random_affine(uint64_t *s, bool reflect)
{
    mat4 m = mat4_identity();
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j)
            m.m[i][j] = 2.0 * rng_next(s) - 1.0 + (i == j ? 1.5 : 0.0);
        m.m[i][3] = 10.0 * rng_next(s) - 5.0;
    }
    if (reflect)
        for (int i = 0; i < 3; ++i)
            m.m[i][0] = -m.m[i][0];
    transform t;
    assert_true(transform_from_matrix(m, &t));
    return t;
}

/* m = T R U exactly, U upper triangular with U00, U11 > 0 and U22 of the
 * determinant's sign, R a rotation (a unit quaternion). */
static void test_qr_round_trip(void **state)
{
    (void)state;
    uint64_t s = 5;
    for (int k = 0; k < 300; ++k) {
        bool reflect = k % 4 == 1;
        transform t = k % 2 ? random_affine(&s, reflect) : random_trs(&s, reflect);
        quat_decomposition d;
        assert_true(transform_decompose_qr(&t.m, &d));
        quat q = d.rotation;
        assert_near(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 1.0, 1e-12);
        mat4 back = quat_decomposition_matrix(&d);
        assert_mat_near(&back, &t.m, 1e-12);
        assert_true(d.scale[0] > 0.0 && d.scale[1] > 0.0);
        assert_true((d.scale[2] < 0.0) == transform_swaps_handedness(&t));
    }
    mat4 flat = mat4_identity();
    flat.m[2][2] = 0.0;
    quat_decomposition d;
    assert_false(transform_decompose_qr(&flat, &d));
    mat4 projective = mat4_identity();
    projective.m[3][2] = 1.0;
    assert_false(transform_decompose_qr(&projective, &d));
}

/* With pbrt's S diagonal at both keyframes (translations, rotations, scales
 * along the object's axes, reflections), one Embree segment is pbrt's
 * AnimatedTransform: to 1e-12 for rotations above 3.6 degrees, where Embree
 * slerps, and within the 1.0e-6 rad of its normalised lerp below. */
static void test_embree_matches_pbrt_for_diagonal_scale(void **state)
{
    (void)state;
    uint64_t s = 17;
    double worst_slerp = 0.0, worst_nlerp = 0.0;
    for (int k = 0; k < 200; ++k) {
        bool reflect = k % 3 == 0, small = k % 2 == 1;
        transform t0 = random_trs(&s, reflect);
        vec3 axis = v3(rng_next(&s) - 0.5, rng_next(&s) - 0.5, rng_next(&s) - 0.5);
        double deg = small ? 3.5 * rng_next(&s) : 4.0 + 170.0 * rng_next(&s);
        vec3 sc = v3(0.3 + rng_next(&s), 0.3 + rng_next(&s), 0.3 + rng_next(&s));
        /* end = T' R' R0 S' (R0 S0's rotation, turned further): S stays diagonal */
        vec3 tr;
        quat q0;
        mat4 s0;
        transform_decompose(&t0.m, &tr, &q0, &s0);
        transform r0 = {quat_to_mat4(q0), mat4_transpose(quat_to_mat4(q0))};
        transform t1 = transform_compose(
            transform_translate(v3(rng_next(&s), rng_next(&s), -rng_next(&s))),
            transform_compose(transform_rotate(deg, axis),
                              transform_compose(r0, transform_scale(v3((reflect ? -1 : 1) * sc.x,
                                                                       sc.y, sc.z)))));
        animated_transform a = animated_transform_make(t0, 1.0, t1, 3.0);
        quat_decomposition steps[2];
        assert_true(animated_transform_time_steps(&a, 1, steps));
        for (int i = 0; i <= 20; ++i) {
            double u = i / 20.0;
            transform want = animated_transform_at(&a, 1.0 + 2.0 * u);
            mat4 got = quat_motion_at(steps, 1, u);
            double err = 0.0;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 4; ++c)
                    err = fmax(err, fabs(got.m[r][c] - want.m.m[r][c]) /
                                        (c == 3 ? 1.0 + fabs(want.m.m[r][c]) : 1.0));
            if (small)
                worst_nlerp = fmax(worst_nlerp, err);
            else
                worst_slerp = fmax(worst_slerp, err);
        }
    }
    print_message("Embree vs pbrt, diagonal S: worst %.3g (slerp), %.3g (normalised lerp)\n",
                  worst_slerp, worst_nlerp);
    assert_true(worst_slerp < 1e-12);
    /* 1.0e-6 rad of rotation times matrix entries of up to ~4 */
    assert_true(worst_nlerp < 5e-6);
}

/* A shear, or a scale along turning axes, is not T R U with pbrt's R: one
 * segment strays from pbrt's path, and doubling the time steps shrinks the
 * error about fourfold (second order) down to the geometry's tolerance. */
static void test_steps_converge_for_shear(void **state)
{
    (void)state;
    transform t0 = transform_translate(v3(0, 0, 4));
    transform t1 = transform_compose(
        t0, transform_compose(transform_rotate(120, v3(1, 1, 0)),
                              transform_compose(transform_scale(v3(2, 0.5, 1)),
                                                transform_rotate(40, v3(0, 0, 1)))));
    animated_transform a = animated_transform_make(t0, 0.0, t1, 1.0);
    quat_decomposition steps[129];
    double prev = INFINITY;
    for (int n = 1; n <= 128; n *= 2) {
        assert_true(animated_transform_time_steps(&a, n, steps));
        /* the keyframes exactly */
        mat4 first = quat_motion_at(steps, n, 0.0), last = quat_motion_at(steps, n, 1.0);
        assert_mat_near(&first, &t0.m, 1e-12);
        assert_mat_near(&last, &t1.m, 1e-12);
        double err = animated_transform_steps_error(&a, steps, n, v3(-1, -1, -1), v3(1, 1, 1));
        print_message("shear: %3d segments, relative error %.3g\n", n, err);
        if (n == 1)
            assert_true(err > 1e-2);
        else
            assert_true(err < prev / 3.0);
        prev = err;
    }
    assert_true(prev < 1e-5);
    /* between the steps, exactly at them */
    assert_true(animated_transform_time_steps(&a, 4, steps));
    for (int k = 0; k <= 4; ++k) {
        mat4 got = quat_motion_at(steps, 4, k / 4.0);
        transform want = animated_transform_at(&a, k / 4.0);
        assert_mat_near(&got, &want.m, 1e-12);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decompose_round_trip),
        cmocka_unit_test(test_quat_matrix_round_trip),
        cmocka_unit_test(test_slerp),
        cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_static),
        cmocka_unit_test(test_qr_round_trip),
        cmocka_unit_test(test_embree_matches_pbrt_for_diagonal_scale),
        cmocka_unit_test(test_steps_converge_for_shear),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
