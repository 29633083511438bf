/* core/color_space: pbrt-v4's RGB colour spaces and the matrices between
 * them: the published Rec. 709 -> Rec. 2020 matrix (ITU-R BT.2087), white
 * preserved between spaces of one white point, exact round trips, names. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdbool.h>

#include "core/color_space.h"

static void apply(const double m[9], const double v[3], double out[3])
{
    for (int r = 0; r < 3; ++r)
        out[r] = m[3 * r] * v[0] + m[3 * r + 1] * v[1] + m[3 * r + 2] * v[2];
}

static void test_rec709_to_rec2020(void **state)
{
    (void)state;
    /* ITU-R BT.2087-0, the linear Rec. 709 -> Rec. 2020 matrix */
    const double want[9] = {0.6274, 0.3293, 0.0433, 0.0691, 0.9195, 0.0114,
                            0.0164, 0.0880, 0.8956};
    double m[9];
    color_space_convert_matrix(COLOR_SPACE_SRGB, COLOR_SPACE_REC2020, m);
    for (int i = 0; i < 9; ++i)
        assert_true(fabs(m[i] - want[i]) < 1.5e-4);
}

static void test_white_and_round_trips(void **state)
{
    (void)state;
    const double white[3] = {1, 1, 1}, v[3] = {0.7, 0.2, 0.05};
    for (int a = 0; a < COLOR_SPACE_COUNT; ++a)
        for (int b = 0; b < COLOR_SPACE_COUNT; ++b) {
            double ab[9], ba[9], w[3], x[3], y[3];
            color_space_convert_matrix((color_space)a, (color_space)b, ab);
            color_space_convert_matrix((color_space)b, (color_space)a, ba);
            apply(ab, v, x);
            apply(ba, x, y);
            for (int k = 0; k < 3; ++k)
                assert_true(fabs(y[k] - v[k]) < 1e-12);
            /* D65 spaces keep white; ACES (D60) does not: no adaptation */
            bool d65 = a != COLOR_SPACE_ACES2065_1 && b != COLOR_SPACE_ACES2065_1;
            apply(ab, white, w);
            for (int k = 0; k < 3; ++k)
                if (d65 || a == b)
                    assert_true(fabs(w[k] - 1.0) < 1e-12);
            if (!d65 && a != b)
                assert_true(fabs(w[0] - 1.0) > 1e-3 || fabs(w[2] - 1.0) > 1e-3);
        }
}

static void test_names(void **state)
{
    (void)state;
    color_space cs;
    assert_true(color_space_lookup("srgb", &cs) && cs == COLOR_SPACE_SRGB);
    assert_true(color_space_lookup("Rec2020", &cs) && cs == COLOR_SPACE_REC2020);
    assert_true(color_space_lookup("ACES2065-1", &cs) && cs == COLOR_SPACE_ACES2065_1);
    assert_true(color_space_lookup("dci-p3", &cs) && cs == COLOR_SPACE_DCI_P3);
    assert_false(color_space_lookup("adobergb", &cs));
    assert_false(color_space_lookup("srgbx", &cs));
    assert_false(color_space_lookup("", &cs));
    assert_string_equal(color_space_name(COLOR_SPACE_DCI_P3), "dci-p3");
    double xy[8];
    color_space_chromaticities(COLOR_SPACE_REC2020, xy);
    assert_true(xy[0] == 0.708 && xy[7] == 0.3290);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rec709_to_rec2020),
        cmocka_unit_test(test_white_and_round_trips),
        cmocka_unit_test(test_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
