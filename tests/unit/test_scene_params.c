#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/scene_desc.h"
#include "scene/spectrum.h"

/* Parses one Camera with the given parameters and hands back its list. */
static param_list *camera_params(scene_desc *sd, const char *params)
{
    char src[512];
    snprintf(src, sizeof src, "Camera \"perspective\" %s\nWorldBegin", params);
    hz_error err;
    if (scene_parse_string(src, "p.pbrt", sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    return &sd->camera.entity.params;
}

static void test_getters_and_defaults(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(&sd, "\"float fov\" 30 \"integer n\" [4] \"float arr\" [1 2 3]");
    assert_true(params_float(pl, "fov", 90) == 30.0);
    assert_true(params_float(pl, "absent", 90) == 90.0);
    assert_int_equal(params_int(pl, "n", 0), 4);
    size_t n;
    const double *a = params_floats(pl, "arr", &n);
    assert_int_equal(n, 3);
    assert_true(a[2] == 3.0);
    assert_null(params_floats(pl, "none", &n));
    assert_int_equal(n, 0);
    hz_error err;
    assert_int_equal(params_finish(pl, "Camera \"perspective\"", &err), HZ_OK);
    scene_desc_free(&sd);
}

static void test_unused_is_reported(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(&sd, "\"float fov\" 30 \"float fvo\" 40");
    assert_true(params_float(pl, "fov", 90) == 30.0);
    hz_error err;
    assert_int_equal(params_finish(pl, "Camera \"perspective\"", &err), HZ_ERROR);
    assert_string_equal(err.message,
                        "p.pbrt:1:37: unused parameter \"float fvo\" for Camera \"perspective\"");
    scene_desc_free(&sd);
}

static void test_type_mismatch(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(&sd, "\"integer fov\" 30");
    /* Strict as pbrt-v4: the integer is not read as a float... */
    assert_true(params_float(pl, "fov", 90) == 90.0);
    hz_error err;
    assert_int_equal(params_finish(pl, "Camera \"perspective\"", &err), HZ_ERROR);
    /* ...but the message says what was meant. */
    assert_string_equal(err.message, "p.pbrt:1:22: parameter \"fov\" must be float, not integer");
    scene_desc_free(&sd);

    pl = camera_params(&sd, "\"float fov\" [30 40]");
    assert_true(params_float(pl, "fov", 90) == 90.0);
    assert_int_equal(params_finish(pl, "Camera", &err), HZ_ERROR);
    assert_string_equal(err.message, "p.pbrt:1:22: parameter \"float fov\" takes 1 value, got 2");
    scene_desc_free(&sd);
}

static void test_reject_and_loc(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(&sd, "\n  \"float fov\" -3");
    assert_int_equal(params_loc(pl, "fov").line, 2);
    assert_int_equal(params_loc(pl, "fov").column, 3);
    assert_int_equal(params_loc(pl, "nope").line, 1); /* the directive */
    params_reject(pl, "fov", "fov must be in (0, 180), got %g", -3.0);
    hz_error err;
    assert_int_equal(params_finish(pl, "Camera", &err), HZ_ERROR);
    assert_string_equal(err.message, "p.pbrt:2:3: fov must be in (0, 180), got -3");
    scene_desc_free(&sd);
}

static void test_copy_is_deep(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(&sd, "\"string s\" \"abc\" \"float f\" [1 2]");
    param_list c;
    assert_true(params_copy(&c, pl));
    assert_int_equal(c.count, 2);
    assert_ptr_not_equal(c.items[0].strs[0], pl->items[0].strs[0]);
    assert_string_equal(params_string(&c, "s", ""), "abc");
    assert_false(pl->items[0].used);
    params_free(&c);
    scene_desc_free(&sd);
}

static void test_spectrum_values(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(
        &sd, "\"spectrum a\" 0.25 \"spectrum b\" [300 1 900 1] \"spectrum c\" [300 .5 900 .5] "
             "\"spectrum d\" [300 0 550 0 551 1 900 1] \"blackbody e\" 6504 \"blackbody f\" 2000");
    rgb a = params_rgb(pl, "a", rgb_grey(-1));
    assert_true(a.r == 0.25 && a.g == 0.25 && a.b == 0.25);
    /* A constant spectrum gives the grey of the same value (the normalisation). */
    rgb b = params_rgb(pl, "b", rgb_grey(-1));
    assert_float_equal(b.r, 1.0, 1e-9);
    assert_float_equal(b.g, 1.0, 1e-9);
    assert_float_equal(b.b, 1.0, 1e-9);
    rgb c = params_rgb(pl, "c", rgb_grey(-1));
    assert_float_equal(c.g, 0.5, 1e-9);
    /* Long wavelengths only: red-yellow, no blue. */
    rgb d = params_rgb(pl, "d", rgb_grey(-1));
    assert_true(d.r > d.g && d.g > d.b);
    assert_true(d.b < 0.05);
    /* Blackbody: luminance 1; 6504 K is close to D65 white; 2000 K is orange. */
    rgb e = params_rgb(pl, "e", rgb_grey(-1));
    assert_float_equal(rgb_luminance(e), 1.0, 2e-3);
    assert_float_equal(e.r, 1.0, 0.06);
    assert_float_equal(e.g, 1.0, 0.06);
    assert_float_equal(e.b, 1.0, 0.1);
    rgb f = params_rgb(pl, "f", rgb_grey(-1));
    assert_float_equal(rgb_luminance(f), 1.0, 2e-3);
    assert_true(f.r > 1.3 && f.b < 0.3);
    assert_int_equal(pl->items[5].type, PARAM_BLACKBODY);
    scene_desc_free(&sd);
}

/* Reflectances: a spectrum within [0, 1] and rgb values within rounding of
 * [0, 1] come back inside it; what is really outside comes back as given. */
static void test_reflectance_values(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(
        &sd, "\"spectrum w\" [400 1 700 1] \"spectrum x\" [400 1.01 700 1.01] "
             "\"rgb y\" [1.0000001 1 -1e-9] \"rgb z\" [1.01 1 -0.001] \"spectrum g\" [500 0 550 1 600 0]");
    rgb w = params_rgb(pl, "w", rgb_grey(-1));
    assert_true(w.g > 1.001); /* the CIE-to-sRGB reduction, not the spectrum */
    w = params_reflectance(pl, "w", rgb_grey(-1));
    assert_true(w.g == 1.0);
    assert_float_equal(w.r, 0.996, 1e-3);
    rgb x = params_reflectance(pl, "x", rgb_grey(-1));
    assert_true(x.g > 1.01);
    rgb y = params_reflectance(pl, "y", rgb_grey(-1));
    assert_true(y.r == 1.0 && y.g == 1.0 && y.b == 0.0);
    rgb z = params_reflectance(pl, "z", rgb_grey(-1));
    assert_true(z.r == 1.01 && z.b == -0.001);
    /* A narrow green band lies outside sRGB (a negative channel): clamped. */
    rgb g = params_rgb(pl, "g", rgb_grey(-1));
    assert_true(g.r < 0.0 || g.b < 0.0);
    g = params_reflectance(pl, "g", rgb_grey(-1));
    assert_true(g.r >= 0.0 && g.b >= 0.0 && g.g <= 1.0);
    assert_true(params_reflectance(pl, "absent", rgb_grey(0.5)).g == 0.5);
    scene_desc_free(&sd);
}

/* Lights' spectra as pbrt-v4 normalises them: luminance 1 whatever the
 * spectrum's scale, its own chromaticity (an equal-energy spectrum is
 * pinkish beside sRGB's D65 white); rgb values untouched; blackbody as rgb. */
static void test_illuminant_values(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = camera_params(&sd, "\"spectrum a\" 5 \"spectrum b\" [360 5 830 5] "
                                        "\"spectrum c\" [400 0 500 3 600 1 700 2] "
                                        "\"rgb d\" [2 3 4] \"blackbody e\" 3000 "
                                        "\"spectrum f\" [300 0 350 1]");
    rgb a = params_illuminant(pl, "a", rgb_grey(-1)), b = params_illuminant(pl, "b", rgb_grey(-1));
    assert_float_equal(rgb_luminance(a), 1.0, 1e-3);
    assert_float_equal(a.r, b.r, 1e-12);
    assert_float_equal(a.b, b.b, 1e-12);
    assert_true(a.r > a.g && a.g > a.b); /* equal energy: redder than D65 */
    rgb c = params_illuminant(pl, "c", rgb_grey(-1));
    assert_float_equal(rgb_luminance(c), 1.0, 1e-3);
    assert_true(c.g > c.b && c.b > c.r);
    rgb d = params_illuminant(pl, "d", rgb_grey(-1));
    assert_true(d.r == 2 && d.g == 3 && d.b == 4);
    rgb e = params_illuminant(pl, "e", rgb_grey(-1)), e_rgb = params_rgb(pl, "e", rgb_grey(-1));
    assert_true(e.r == e_rgb.r && e.g == e_rgb.g && e.b == e_rgb.b);
    rgb f = params_illuminant(pl, "f", rgb_grey(-1)); /* ultraviolet only: no light */
    assert_true(f.r == 0 && f.g == 0 && f.b == 0);
    /* The reflectance reading of the same spectra is unchanged. */
    assert_float_equal(params_rgb(pl, "a", rgb_grey(-1)).g, 5.0, 1e-12);
    scene_desc_free(&sd);
}

static void test_cmf_fit(void **state)
{
    (void)state;
    /* Spot values of the CIE 1931 2-degree observer (interpolated from 10 nm). */
    vec3 at555 = spectrum_cie_xyz(555.0);
    assert_float_equal(at555.y, 1.0, 0.002);
    vec3 at450 = spectrum_cie_xyz(450.0);
    assert_float_equal(at450.z, 1.77211, 1e-9); /* a table point: exact */
    vec3 at600 = spectrum_cie_xyz(600.0);
    assert_float_equal(at600.x, 1.0622, 1e-9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_getters_and_defaults), cmocka_unit_test(test_unused_is_reported),
        cmocka_unit_test(test_type_mismatch),        cmocka_unit_test(test_reject_and_loc),
        cmocka_unit_test(test_copy_is_deep),         cmocka_unit_test(test_spectrum_values),
        cmocka_unit_test(test_cmf_fit),       cmocka_unit_test(test_illuminant_values),
        cmocka_unit_test(test_reflectance_values),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
