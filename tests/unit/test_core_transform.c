/* core/transform: pbrt-v4's Transform conventions checked against matrices
 * computed by hand. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "core/transform.h"
#include "unit/assert_util.h"

static void assert_mat4_near(mat4 got, mat4 want, double tol)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            assert_near(got.m[i][j], want.m[i][j], tol);
}

static mat4 mat4_rows(const double r[16])
{
    mat4 m;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            m.m[i][j] = r[4 * i + j];
    return m;
}

static void test_inverse_of_general_matrix(void **state)
{
    (void)state;
    /* Needs pivoting: m[0][0] is 0. Inverse computed by hand (det = -2). */
    mat4 a = mat4_rows((const double[16]){0, 1, 0, 0, 2, 0, 0, 0, 0, 0, 1, 3, 0, 0, 0, 1});
    mat4 want = mat4_rows((const double[16]){0, 0.5, 0, 0, 1, 0, 0, 0, 0, 0, 1, -3, 0, 0, 0, 1});
    mat4 inv;
    assert_true(mat4_inverse(a, &inv));
    assert_mat4_near(inv, want, 1e-15);
    assert_mat4_near(mat4_mul(a, inv), mat4_identity(), 1e-15);

    mat4 b = mat4_rows((const double[16]){4, 7, 2, 1, 3, 6, 1, 0, 2, 5, 3, 2, 1, 1, 1, 5});
    assert_true(mat4_inverse(b, &inv));
    assert_mat4_near(mat4_mul(b, inv), mat4_identity(), 1e-13);
    assert_mat4_near(mat4_mul(inv, b), mat4_identity(), 1e-13);
}

static void test_inverse_of_singular_matrix_fails(void **state)
{
    (void)state;
    mat4 s = mat4_rows((const double[16]){1, 2, 3, 4, 2, 4, 6, 8, 0, 0, 1, 0, 0, 0, 0, 1});
    mat4 out = mat4_identity();
    out.m[0][1] = 42.0;
    assert_false(mat4_inverse(s, &out));
    assert_true(out.m[0][1] == 42.0); /* left untouched */
    transform t;
    assert_false(transform_from_matrix(s, &t));
}

static void test_translate_and_scale(void **state)
{
    (void)state;
    transform t = transform_translate(v3(1, 2, 3));
    assert_v3_near(transform_point(&t, v3(1, 1, 1)), v3(2, 3, 4), 0);
    assert_v3_near(transform_vector(&t, v3(1, 1, 1)), v3(1, 1, 1), 0);
    transform ti = transform_inverse(t);
    assert_v3_near(transform_point(&ti, v3(2, 3, 4)), v3(1, 1, 1), 0);

    transform s = transform_scale(v3(2, 4, -8));
    assert_v3_near(transform_point(&s, v3(1, 1, 1)), v3(2, 4, -8), 0);
    /* Normals go by the inverse transpose: a plane y = c scaled by 4 in y keeps
     * its normal direction but the normal shrinks by 1/4. */
    assert_v3_near(transform_normal(&s, v3(0, 1, 0)), v3(0, 0.25, 0), 0);
    assert_true(transform_swaps_handedness(&s));
    assert_false(transform_swaps_handedness(&t));
    assert_mat4_near(mat4_mul(s.m, s.m_inv), mat4_identity(), 0);
}

static void test_compose_order(void **state)
{
    (void)state;
    /* compose(a_from_b, b_from_c) applies b_from_c first. */
    transform t = transform_translate(v3(1, 0, 0));
    transform s = transform_scale(v3(2, 2, 2));
    transform ts = transform_compose(t, s);
    transform st = transform_compose(s, t);
    assert_v3_near(transform_point(&ts, v3(1, 1, 1)), v3(3, 2, 2), 0);
    assert_v3_near(transform_point(&st, v3(1, 1, 1)), v3(4, 2, 2), 0);
    /* The cached inverse is the inverse of the product. */
    transform tsi = transform_inverse(ts);
    assert_v3_near(transform_point(&tsi, v3(3, 2, 2)), v3(1, 1, 1), 0);
    assert_mat4_near(mat4_mul(ts.m, ts.m_inv), mat4_identity(), 1e-15);
    assert_true(transform_is_identity(transform_compose(ts, tsi)));
}

static void test_is_identity_ignores_signed_zeros(void **state)
{
    (void)state;
    /* Exporters write "-0" in Transform matrices; -0.0 == 0.0 is still the
     * identity (a byte comparison said otherwise). */
    mat4 m = mat4_identity();
    m.m[0][1] = -0.0;
    m.m[2][3] = -0.0;
    transform t;
    assert_true(transform_from_matrix(m, &t));
    assert_true(transform_is_identity(t));
    assert_false(transform_is_identity(transform_translate(v3(0, 0, 1e-300))));
    assert_false(transform_is_identity(transform_scale(v3(1, 1, -1))));
    assert_true(transform_is_identity(transform_identity()));
}

static void test_rotate(void **state)
{
    (void)state;
    /* pbrt's RotateX/Y/Z matrices: counter-clockwise looking down the axis. */
    transform rz = transform_rotate(90, v3(0, 0, 1));
    assert_v3_near(transform_point(&rz, v3(1, 0, 0)), v3(0, 1, 0), 1e-15);
    assert_v3_near(transform_point(&rz, v3(0, 1, 0)), v3(-1, 0, 0), 1e-15);
    transform rx = transform_rotate(90, v3(1, 0, 0));
    assert_v3_near(transform_point(&rx, v3(0, 1, 0)), v3(0, 0, 1), 1e-15);
    transform ry = transform_rotate(90, v3(0, 2, 0)); /* axis normalised */
    assert_v3_near(transform_point(&ry, v3(1, 0, 0)), v3(0, 0, -1), 1e-15);
    assert_v3_near(transform_point(&ry, v3(0, 0, 1)), v3(1, 0, 0), 1e-15);

    /* 120 degrees about (1,1,1) cycles the axes. */
    transform r = transform_rotate(120, v3(1, 1, 1));
    assert_v3_near(transform_point(&r, v3(1, 0, 0)), v3(0, 1, 0), 1e-15);
    assert_v3_near(transform_point(&r, v3(0, 1, 0)), v3(0, 0, 1), 1e-15);

    /* 30 degrees about z, by hand. */
    transform r30 = transform_rotate(30, v3(0, 0, 1));
    assert_v3_near(transform_point(&r30, v3(2, 0, 5)), v3(sqrt(3.0), 1, 5), 1e-15);
    assert_mat4_near(mat4_mul(r30.m, r30.m_inv), mat4_identity(), 1e-15);
    assert_false(transform_swaps_handedness(&r30));
    /* Rotations keep normals as they are (inverse transpose = itself). */
    assert_v3_near(transform_normal(&r30, v3(1, 0, 0)), transform_vector(&r30, v3(1, 0, 0)), 1e-15);
}

static void test_look_at_identity_and_translation(void **state)
{
    (void)state;
    transform cfw;
    assert_true(transform_look_at(v3(0, 0, 0), v3(0, 0, 5), v3(0, 1, 0), &cfw));
    assert_mat4_near(cfw.m, mat4_identity(), 0);
    assert_true(transform_look_at(v3(1, 2, 3), v3(1, 2, 4), v3(0, 3, 0), &cfw));
    assert_mat4_near(cfw.m, transform_translate(v3(-1, -2, -3)).m, 0);
    assert_mat4_near(cfw.m_inv, transform_translate(v3(1, 2, 3)).m, 0);
}

static void test_look_at_down_x(void **state)
{
    (void)state;
    /* dir = +x, right = up x dir = (0,1,0) x (1,0,0) = (0,0,-1), up' = dir x
     * right = (0,1,0). world_from_camera has columns right, up', dir, eye; so
     * camera_from_world (its inverse) has rows right, up', dir (plus -R eye). */
    transform cfw;
    assert_true(transform_look_at(v3(1, 2, 3), v3(2, 2, 3), v3(0, 1, 0), &cfw));
    mat4 want = mat4_rows((const double[16]){0, 0, -1, 3, 0, 1, 0, -2, 1, 0, 0, -1, 0, 0, 0, 1});
    assert_mat4_near(cfw.m, want, 1e-15);
    assert_v3_near(transform_point(&cfw, v3(2, 2, 3)), v3(0, 0, 1), 1e-15); /* in front */
    assert_v3_near(transform_point(&cfw, v3(1, 3, 3)), v3(0, 1, 0), 1e-15); /* above */
    assert_v3_near(transform_point(&cfw, v3(1, 2, 2)), v3(1, 0, 0), 1e-15); /* right */
    assert_false(transform_swaps_handedness(&cfw));
}

static void test_look_at_degenerate(void **state)
{
    (void)state;
    transform cfw = transform_identity();
    assert_false(transform_look_at(v3(1, 1, 1), v3(1, 1, 1), v3(0, 1, 0), &cfw));
    assert_false(transform_look_at(v3(0, 0, 0), v3(0, 5, 0), v3(0, 1, 0), &cfw));
    assert_false(transform_look_at(v3(0, 0, 0), v3(0, 0, 1), v3(0, 0, 0), &cfw));
    assert_true(transform_is_identity(cfw));
}

static void test_perspective(void **state)
{
    (void)state;
    double n = 1e-2, f = 1000.0;
    transform p = transform_perspective(90, n, f);
    /* Screen = (x/z, y/z) / tan(fov/2), z' = f (z - n) / (z (f - n)). */
    vec3 q = transform_point(&p, v3(1, 2, 4));
    assert_v3_near(q, v3(0.25, 0.5, f * (4 - n) / (4 * (f - n))), 1e-15);
    assert_near(transform_point(&p, v3(0, 0, n)).z, 0.0, 1e-15);
    assert_near(transform_point(&p, v3(0, 0, f)).z, 1.0, 1e-15);

    transform p60 = transform_perspective(60, n, f);
    assert_v3_near(transform_point(&p60, v3(1, -1, 2)),
                   v3(sqrt(3.0) / 2, -sqrt(3.0) / 2, f * (2 - n) / (2 * (f - n))), 1e-14);
    /* The edge of the field of view maps to screen x = 1. */
    assert_near(transform_point(&p60, v3(tan(HZ_PI / 6), 0, 1)).x, 1.0, 1e-15);
    /* The cached inverse undoes the projection. */
    transform pi = transform_inverse(p60);
    assert_v3_near(transform_point(&pi, transform_point(&p60, v3(0.3, -0.7, 5))), v3(0.3, -0.7, 5),
                   1e-12);
}

static void test_orthographic(void **state)
{
    (void)state;
    transform o = transform_orthographic(0, 1);
    assert_v3_near(transform_point(&o, v3(3, -2, 0.5)), v3(3, -2, 0.5), 0);
    transform o2 = transform_orthographic(2, 6);
    assert_v3_near(transform_point(&o2, v3(3, -2, 4)), v3(3, -2, 0.5), 1e-15);
    assert_v3_near(transform_point(&o2, v3(0, 0, 2)), v3(0, 0, 0), 1e-15);
    transform oi = transform_inverse(o2);
    assert_v3_near(transform_point(&oi, v3(0, 0, 1)), v3(0, 0, 6), 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_inverse_of_general_matrix),
        cmocka_unit_test(test_inverse_of_singular_matrix_fails),
        cmocka_unit_test(test_translate_and_scale),
        cmocka_unit_test(test_compose_order),
        cmocka_unit_test(test_is_identity_ignores_signed_zeros),
        cmocka_unit_test(test_rotate),
        cmocka_unit_test(test_look_at_identity_and_translation),
        cmocka_unit_test(test_look_at_down_x),
        cmocka_unit_test(test_look_at_degenerate),
        cmocka_unit_test(test_perspective),
        cmocka_unit_test(test_orthographic),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
