/* ColorSpace (pbrt-v4): "rgb" values that follow are in that space (converted
 * to haze's sRGB when parsed, restored by AttributeEnd); a Film after it
 * writes its image in it (EXR chromaticities), the PNG preview in sRGB. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "core/color_space.h"
#include "render_test_util.h"

static rgb convert(color_space from, color_space to, rgb v)
{
    double m[9];
    color_space_convert_matrix(from, to, m);
    return rgb_make(m[0] * v.r + m[1] * v.g + m[2] * v.b, m[3] * v.r + m[4] * v.g + m[5] * v.b,
                    m[6] * v.r + m[7] * v.g + m[8] * v.b);
}

static rgb material_rgb(scene_desc *sd, size_t i)
{
    return params_rgb(&sd->materials[i].entity.params, "reflectance", rgb_grey(-1.0));
}

static void expect_rgb(rgb got, rgb want)
{
    assert_true(fabs(got.r - want.r) < 1e-12 && fabs(got.g - want.g) < 1e-12 &&
                fabs(got.b - want.b) < 1e-12);
}

static void test_rgb_values_converted(void **state)
{
    (void)state;
    const char *text = "WorldBegin\n"
                       "MakeNamedMaterial \"a\" \"string type\" \"diffuse\""
                       " \"rgb reflectance\" [0.5 0.2 0.1]\n"
                       "ColorSpace \"rec2020\"\n"
                       "MakeNamedMaterial \"b\" \"string type\" \"diffuse\""
                       " \"rgb reflectance\" [0.5 0.2 0.1]\n"
                       "AttributeBegin\n"
                       "  ColorSpace \"ACES2065-1\"\n"
                       "  MakeNamedMaterial \"c\" \"string type\" \"diffuse\""
                       " \"rgb reflectance\" [0.5 0.2 0.1]\n"
                       "AttributeEnd\n"
                       "MakeNamedMaterial \"d\" \"string type\" \"diffuse\""
                       " \"rgb reflectance\" [0.5 0.2 0.1]\n";
    scene_desc sd;
    hz_error err = {0};
    if (scene_parse_string(text, "t.pbrt", &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    rgb v = rgb_make(0.5, 0.2, 0.1);
    expect_rgb(material_rgb(&sd, 0), v);
    expect_rgb(material_rgb(&sd, 1), convert(COLOR_SPACE_REC2020, COLOR_SPACE_SRGB, v));
    expect_rgb(material_rgb(&sd, 2), convert(COLOR_SPACE_ACES2065_1, COLOR_SPACE_SRGB, v));
    expect_rgb(material_rgb(&sd, 3), convert(COLOR_SPACE_REC2020, COLOR_SPACE_SRGB, v));
    /* a Rec. 2020 red is outside sRGB: negative green and blue */
    rgb red = convert(COLOR_SPACE_REC2020, COLOR_SPACE_SRGB, rgb_make(1, 0, 0));
    assert_true(red.r > 1.0 && red.g < 0.0 && red.b < 0.0);
    assert_int_equal(sd.film_color_space, COLOR_SPACE_SRGB);
    scene_desc_free(&sd);
}

static void test_unknown_refused(void **state)
{
    (void)state;
    scene_desc sd;
    hz_error err = {0};
    assert_int_equal(scene_parse_string("ColorSpace \"adobergb\"\n", "t.pbrt", &sd, &err),
                     HZ_ERROR);
    assert_non_null(strstr(err.message, "t.pbrt:1:1: unknown ColorSpace \"adobergb\""));
    assert_non_null(strstr(err.message, "rec2020"));
}

/* A sky of sRGB (0.3, 0.5, 0.7) seen by a Film under ColorSpace "rec2020":
 * the pixels are that colour in Rec. 2020 RGB; the same Film under "srgb",
 * the colour as given. */
static void test_film_in_color_space(void **state)
{
    (void)state;
    const char *spaces[] = {"srgb", "rec2020", "dci-p3"};
    const color_space ids[] = {COLOR_SPACE_SRGB, COLOR_SPACE_REC2020, COLOR_SPACE_DCI_P3};
    for (int s = 0; s < 3; ++s) {
        char text[1024];
        snprintf(text, sizeof text,
                 "ColorSpace \"%s\"\n"
                 "Camera \"perspective\"\n"
                 "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                 "Sampler \"independent\" \"integer pixelsamples\" 2\n"
                 "WorldBegin\n"
                 "ColorSpace \"srgb\"\n"
                 "LightSource \"infinite\" \"rgb L\" [0.3 0.5 0.7]\n",
                 spaces[s]);
        render_scene *rs = build_scene_or_fail(text, NULL);
        render_expect_finite(rs);
        rgb got = film_get_pixel(render_scene_film(rs), 1, 2, 1.0);
        rgb want = convert(COLOR_SPACE_SRGB, ids[s], rgb_make(0.3, 0.5, 0.7));
        if (!(fabs(got.r - want.r) < 1e-9 && fabs(got.g - want.g) < 1e-9 &&
              fabs(got.b - want.b) < 1e-9))
            fail_msg("%s: got %.9g %.9g %.9g, want %.9g %.9g %.9g", spaces[s], got.r, got.g,
                     got.b, want.r, want.g, want.b);
        assert_int_equal(film_get_params(render_scene_film(rs))->color_space, ids[s]);
        render_scene_destroy(rs);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rgb_values_converted),
        cmocka_unit_test(test_unknown_refused),
        cmocka_unit_test(test_film_in_color_space),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
