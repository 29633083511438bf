/* Alpha cut-outs (pbrt-v4's "alpha" on shapes): alpha 0 removes a surface
 * from camera and shadow rays alike; a fractional alpha keeps each hit with
 * that probability, each surface along a ray deciding on its own (a sphere of
 * alpha 1/2 stops 3/4 of the rays through its middle: its front or, failing
 * that, its back); a float texture cuts a pattern. An orthographic camera
 * looks down -z at black shapes over a white sky: a pixel's value is the
 * fraction of its rays that pass. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <unistd.h>

#include <cmocka.h>

#include "render/cli_util.h"

enum { RES = 32 };

static const char *head = "LookAt 0 0 5  0 0 0  0 1 0\n"
                          "Camera \"orthographic\"\n"
                          "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
                          "Sampler \"independent\" \"integer pixelsamples\" %d\n"
                          "PixelFilter \"box\"\n"
                          "Integrator \"volpath\" \"integer maxdepth\" 1\n"
                          "WorldBegin\n";

/* Renders head + world at spp into NAME.exr and returns the mean of G over
 * pixels [x0, x1) x [y0, y1). */
static double region_mean(const char *name, int spp, const char *world, int x0, int x1, int y0,
                          int y1)
{
    char scene[1200], exr[1200], text[4096], args[3000], out[4096];
    snprintf(scene, sizeof scene, "%s/alpha_%s-%ld.pbrt", HAZE_TMP, name, (long)getpid());
    snprintf(exr, sizeof exr, "%s/alpha_%s-%ld.exr", HAZE_TMP, name, (long)getpid());
    int n = snprintf(text, sizeof text, head, spp);
    snprintf(text + n, sizeof text - (size_t)n, "%s", world);
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet", scene, exr);
    int status = run_haze(args, out, sizeof out);
    if (status != 0)
        fail_msg("%s: exit %d: %s", name, status, out);
    exr_image img;
    hz_error err;
    assert_int_equal(exr_read(exr, &img, &err), HZ_OK);
    const exr_channel *g = exr_find_channel(&img, "G");
    double sum = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            sum += g->pixels[y * img.width + x];
    exr_image_free(&img);
    remove(scene); /* the test's own temporaries */
    remove(exr);
    return sum / ((x1 - x0) * (y1 - y0));
}

#define SKY "LightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
#define QUAD "Shape \"trianglemesh\" \"point3 P\" [-0.8 -0.8 0 0.8 -0.8 0 0.8 0.8 0 -0.8 0.8 0] " \
             "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1] "

/* Within k standard errors of a mean of n Bernoulli(p) draws. */
static void expect_fraction(double got, double p, double n, const char *what)
{
    double se = sqrt(p * (1.0 - p) / n);
    print_message("%s: %.5f, want %.5f +- %.5f\n", what, got, p, 4.0 * se);
    if (!(fabs(got - p) <= 4.0 * se + 1e-9))
        fail_msg("%s: %g, want %g within 4 standard errors (%g)", what, got, p, se);
}

static void test_constant_alpha(void **state)
{
    (void)state;
    /* The middle 16x16 pixels lie on the quad. */
    expect_fraction(region_mean("opaque", 16, SKY QUAD "\n", 8, 24, 8, 24), 0.0, 4096, "opaque");
    expect_fraction(region_mean("clear", 16, SKY QUAD "\"float alpha\" 0\n", 8, 24, 8, 24), 1.0,
                    4096, "alpha 0");
    expect_fraction(region_mean("half", 64, SKY QUAD "\"float alpha\" 0.5\n", 8, 24, 8, 24), 0.5,
                    16384, "alpha 0.5");
    expect_fraction(region_mean("quarter", 64, SKY QUAD "\"float alpha\" 0.25\n", 8, 24, 8, 24),
                    0.75, 16384, "alpha 0.25");
    /* A sphere of alpha 1/2: front and back decide apart, 1/4 passes. */
    expect_fraction(region_mean("sphere", 64,
                                SKY "Shape \"sphere\" \"float radius\" 0.9 \"float alpha\" 0.5\n",
                                14, 18, 14, 18),
                    0.25, 1024, "sphere of alpha 0.5");
}

/* A float checkerboard (2x2 checks over the quad): the checks where it is 0
 * vanish, those where it is 1 stay. */
static void test_textured_alpha(void **state)
{
    (void)state;
    const char *world = SKY
        "Texture \"c\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 2 "
        "\"float tex1\" 0 \"float tex2\" 1\n" QUAD "\"texture alpha\" \"c\"\n";
    /* The quad spans pixels [3.2, 28.8); the camera's x is the world's -x
     * (pbrt-v4's LookAt), so check (0, 0) (u, v < 1/2: alpha 0) is at the
     * image's bottom right. */
    expect_fraction(region_mean("check00", 16, world, 18, 27, 18, 27), 1.0, 1296, "check (0, 0)");
    expect_fraction(region_mean("check10", 16, world, 5, 14, 18, 27), 0.0, 1296, "check (1, 0)");
    expect_fraction(region_mean("check11", 16, world, 5, 14, 5, 14), 1.0, 1296, "check (1, 1)");
}

/* Shadow rays see the same cut-out: a plane lit from straight above under an
 * occluder of alpha 0 is lit as without it; under alpha 0.5, half as much. */
static void test_shadows(void **state)
{
    (void)state;
    const char *lit = "LightSource \"distant\" \"point3 from\" [0 0 1] \"point3 to\" [0 0 0] "
                      "\"rgb L\" [3.14159265358979 3.14159265358979 3.14159265358979]\n"
                      "Material \"diffuse\" \"rgb reflectance\" [1 1 1]\n"
                      "Shape \"trianglemesh\" \"point3 P\" [-3 -3 -1 3 -3 -1 3 3 -1 -3 3 -1] "
                      "\"integer indices\" [0 1 2 0 2 3]\n"
                      "Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
                      "AttributeBegin\nTranslate 0 0 1\n"
                      "Shape \"trianglemesh\" \"point3 P\" [-3 -3 0 3 -3 0 3 3 0 -3 3 0] "
                      "\"integer indices\" [0 1 2 0 2 3] \"float alpha\" %s\nAttributeEnd\n";
    char world[2048];
    snprintf(world, sizeof world, lit, "0");
    expect_fraction(region_mean("shadow0", 16, world, 8, 24, 8, 24), 1.0, 4096, "alpha 0 occluder");
    snprintf(world, sizeof world, lit, "0.5");
    /* Camera ray and shadow ray each pass with 1/2: a quarter reaches the
     * plane lit (the black occluder returns nothing). */
    expect_fraction(region_mean("shadow5", 64, world, 8, 24, 8, 24), 0.25, 16384,
                    "alpha 0.5 occluder");
}

/* Emitters with an alpha (pbrt-v4's DiffuseAreaLight::AlphaMasked): their
 * light is hidden wherever the alpha masks the point. Seen directly through
 * an alpha of 1/2, pbrt-v4 tests twice, the hit (as any surface) and the
 * emission (by a hash of the point): a quarter of the rays see it. A
 * checkerboard alpha hiding half of a quad lights a floor as the other half
 * alone does (light samples that land on the hidden half bring nothing). */
static void test_masked_emitters(void **state)
{
    (void)state;
    const char *direct = "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n" QUAD
                         "\"float alpha\" 0.5\n";
    expect_fraction(region_mean("emit5", 64, direct, 8, 24, 8, 24), 0.25, 16384,
                    "alpha 0.5 emitter seen");
    const char *halves = "Texture \"half\" \"float\" \"checkerboard\" \"float uscale\" 2 "
                         "\"float tex1\" 0 \"float tex2\" 1\n"
                         "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n" QUAD
                         "\"texture alpha\" \"half\"\n";
    /* Screen x runs along world -x here: u >= 1/2 (alpha 1) is on the left. */
    expect_fraction(region_mean("emit_left", 4, halves, 4, 14, 8, 24), 1.0, 640, "shown half");
    expect_fraction(region_mean("emit_right", 4, halves, 18, 28, 8, 24), 0.0, 640, "hidden half");
    const char *floor_fmt = "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
                            "Shape \"trianglemesh\" \"point3 P\" [-3 -3 -1 3 -3 -1 3 3 -1 -3 3 -1] "
                            "\"integer indices\" [0 1 2 0 2 3]\n"
                            "AttributeBegin\nReverseOrientation\n"
                            "AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
                            "Shape \"trianglemesh\" \"point3 P\" [1.2 -1 0.5 %s -1 0.5 %s 1 0.5 "
                            "1.2 1 0.5] \"integer indices\" [0 1 2 0 2 3] "
                            "\"point2 uv\" [0 0 1 0 1 1 0 1] %s\nAttributeEnd\n";
    char masked[2048], half[2048];
    snprintf(masked, sizeof masked, "Texture \"half\" \"float\" \"checkerboard\" "
             "\"float uscale\" 2 \"float tex1\" 1 \"float tex2\" 0\n%s", floor_fmt);
    char m2[2048];
    snprintf(m2, sizeof m2, masked, "3.2", "3.2", "\"texture alpha\" \"half\"");
    snprintf(half, sizeof half, floor_fmt, "2.2", "2.2", "");
    double a = region_mean("floor_masked", 256, m2, 0, 32, 0, 32);
    double b = region_mean("floor_half", 256, half, 0, 32, 0, 32);
    print_message("floor under a half-masked emitter %.5f, under the half %.5f\n", a, b);
    assert_true(b > 0.01);
    assert_true(fabs(a / b - 1.0) < 0.02);
}

/* A constant alpha of 0 on an emitter is pbrt-v4's invisible light: no ray
 * sees it, and it lights the scene fully through light samples (which then
 * take no MIS weight: were they weighted against BSDF samples that can never
 * hit it, the floor would come out darker). */
static void test_invisible_emitter(void **state)
{
    (void)state;
    const char *seen = "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n" QUAD "\"float alpha\" 0\n";
    expect_fraction(region_mean("emit0", 64, seen, 8, 24, 8, 24), 0.0, 16384,
                    "alpha 0 emitter seen");
    const char *floor_fmt = "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
                            "Shape \"trianglemesh\" \"point3 P\" [-3 -3 -1 3 -3 -1 3 3 -1 -3 3 -1] "
                            "\"integer indices\" [0 1 2 0 2 3]\n"
                            "AttributeBegin\nReverseOrientation\n"
                            "AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
                            "Shape \"trianglemesh\" \"point3 P\" [1.2 -1 0.5 2.2 -1 0.5 2.2 1 0.5 "
                            "1.2 1 0.5] \"integer indices\" [0 1 2 0 2 3] %s\nAttributeEnd\n";
    char invisible[2048], opaque[2048];
    snprintf(invisible, sizeof invisible, floor_fmt, "\"float alpha\" 0");
    snprintf(opaque, sizeof opaque, floor_fmt, "");
    double a = region_mean("floor_invisible", 256, invisible, 0, 32, 0, 32);
    double b = region_mean("floor_opaque", 256, opaque, 0, 32, 0, 32);
    print_message("floor under an invisible emitter %.5f, under the same opaque one %.5f\n", a, b);
    assert_true(b > 0.01);
    assert_true(fabs(a / b - 1.0) < 0.01);
}

static void test_refused(void **state)
{
    (void)state;
    char scene[1200], text[4096], args[2000], out[4096];
    snprintf(scene, sizeof scene, "%s/alpha_light-%ld.pbrt", HAZE_TMP, (long)getpid());
    int n = snprintf(text, sizeof text, head, 4);
    snprintf(text + n, sizeof text - (size_t)n, "%s",
             "Shape \"sphere\" \"texture alpha\" \"none\"\n");
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' --quiet", scene);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, ":8:16: \"texture alpha\": no float texture named \"none\""));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_alpha),
        cmocka_unit_test(test_textured_alpha),
        cmocka_unit_test(test_shadows),
        cmocka_unit_test(test_masked_emitters),
        cmocka_unit_test(test_invisible_emitter),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
