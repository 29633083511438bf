/* The extremes suite, ray half: legal values that once produced rays Embree
 * cannot trace (it asserted and aborted) or paths dropped without a word.
 * Every value that passes parsing gives finite rays; a value that cannot be
 * represented is refused at its file:line:column (core/ray.h, HZ_MAX_COORD). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "film/exr.h"
#include "render/cli_util.h"

#define DIR HAZE_TMP "/extremes_rays"

static const char header[] = "LookAt 0 0 -5  0 0 0  0 1 0\n"
                             "Camera \"perspective\" \"float fov\" 40 %s\n"
                             "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                             "Sampler \"zsobol\" \"integer pixelsamples\" 16\n";

/* Writes DIR/NAME.pbrt: header (with camera parameters `cam`), then `before`
 * the header (media, medium interface) and `world` after WorldBegin. */
static void scene(const char *name, const char *before, const char *cam, const char *world)
{
    char path[512], text[16384], head[1024];
    snprintf(head, sizeof head, header, cam);
    snprintf(text, sizeof text, "%s%sWorldBegin\n%s", before, head, world);
    snprintf(path, sizeof path, DIR "/%s.pbrt", name);
    write_text_file(path, text);
}

static int render(const char *name, char *out, size_t n)
{
    char args[1024];
    snprintf(args, sizeof args, "render '" DIR "/%s.pbrt' -o '" DIR "/%s.exr' --quiet", name, name);
    return run_haze(args, out, n);
}

/* Mean of R, G, B over the image; fails on a non-finite value. */
static double image_mean(const char *name)
{
    char path[512];
    snprintf(path, sizeof path, DIR "/%s.exr", name);
    exr_image img;
    hz_error err;
    if (exr_read(path, &img, &err) != HZ_OK)
        fail_msg("%s", err.message);
    double sum = 0.0;
    long n = 0;
    for (int c = 0; c < img.channel_count; ++c) {
        const char *ch = img.channels[c].name;
        if (strcmp(ch, "R") && strcmp(ch, "G") && strcmp(ch, "B"))
            continue;
        for (long i = 0; i < (long)img.width * img.height; ++i) {
            float v = img.channels[c].pixels[i];
            assert_true(isfinite(v));
            sum += v;
            ++n;
        }
    }
    exr_image_free(&img);
    assert_true(n > 0);
    return sum / (double)n;
}

static const char sphere_lit[] = "LightSource \"point\" \"point3 from\" [0 2 -2] \"rgb I\" [5 5 5]\n"
                                 "Shape \"sphere\" \"float radius\" 1\n";

/* A camera inside a medium of sigma_s 1e-18: sampled scattering distances
 * reach 1e18 and beyond, where a shadow ray's origin is past Embree's range.
 * The medium is all but transparent: the image equals the one without it. */
static void test_vanishing_camera_medium(void **state)
{
    (void)state;
    char out[4096];
    scene("clear", "", "", sphere_lit);
    assert_int_equal(render("clear", out, sizeof out), 0);
    scene("thin",
          "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] "
          "\"rgb sigma_s\" [1e-18 1e-18 1e-18]\nMediumInterface \"m\"\n",
          "", sphere_lit);
    if (render("thin", out, sizeof out) != 0)
        fail_msg("%s", out);
    double clear = image_mean("clear"), thin = image_mean("thin");
    assert_true(clear > 0.01);
    assert_true(fabs(thin - clear) <= 1e-6 * clear);

    /* The same medium filling all space under a uniform sky: the camera sees
     * the sky through it (the path ends at HZ_FAR_COORD: transmittance there
     * exp(-1e-18 x 1e17) = 0.905, the rest made up by in-scattering). */
    scene("thinsky",
          "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] "
          "\"rgb sigma_s\" [1e-18 1e-18 1e-18]\nMediumInterface \"m\"\n",
          "", "LightSource \"infinite\" \"rgb L\" [1 1 1]\n");
    if (render("thinsky", out, sizeof out) != 0)
        fail_msg("%s", out);
    double sky = image_mean("thinsky");
    assert_true(sky > 0.9 && sky <= 1.0 + 1e-6);

    /* The same under multiple scattering: no crash; the point-lit sphere as
     * without the medium (volpath's own noise aside), the sky returned. */
    scene("thin_vp",
          "Integrator \"volpath\"\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" "
          "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [1e-18 1e-18 1e-18]\nMediumInterface \"m\"\n",
          "", sphere_lit);
    if (render("thin_vp", out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_true(fabs(image_mean("thin_vp") - clear) <= 0.05 * clear);
    scene("thinsky_vp",
          "Integrator \"volpath\"\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" "
          "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [1e-18 1e-18 1e-18]\nMediumInterface \"m\"\n",
          "", "LightSource \"infinite\" \"rgb L\" [1 1 1]\n");
    if (render("thinsky_vp", out, sizeof out) != 0)
        fail_msg("%s", out);
    sky = image_mean("thinsky_vp");
    assert_true(sky > 0.85 && sky <= 1.0 + 1e-6);
}

/* Values no ray can hold are refused where they are written. */
static void test_unrepresentable_positions_refused(void **state)
{
    (void)state;
    char out[4096];
    scene("farlight", "", "",
          "LightSource \"point\" \"point3 from\" [0 2e18 0] \"rgb I\" [5 5 5]\n"
          "Shape \"sphere\" \"float radius\" 1\n");
    assert_int_equal(render("farlight", out, sizeof out), 1);
    assert_non_null(strstr(out, "farlight.pbrt:6:21: light position"));
    scene("farspot", "", "",
          "Translate 0 0 3e17\nLightSource \"spot\" \"rgb I\" [5 5 5]\n"
          "Shape \"sphere\" \"float radius\" 1\n");
    assert_int_equal(render("farspot", out, sizeof out), 1);
    assert_non_null(strstr(out, "farspot.pbrt:7:1: light position"));
    scene("biglens", "", "\"float lensradius\" 1e19 \"float focaldistance\" 5", sphere_lit);
    assert_int_equal(render("biglens", out, sizeof out), 1);
    assert_non_null(strstr(out, "\"lensradius\" must be in [0, 1e+16], got 1e+19"));
    /* The largest accepted values render, finite. */
    scene("nearlimit", "", "\"float lensradius\" 1e15 \"float focaldistance\" 5",
          "LightSource \"point\" \"point3 from\" [0 9e15 0] \"rgb I\" [5 5 5]\n"
          "Shape \"sphere\" \"float radius\" 1\n");
    if (render("nearlimit", out, sizeof out) != 0)
        fail_msg("%s", out);
    image_mean("nearlimit");
}

/* 40 nested interface spheres: a camera ray crosses 80 interfaces, more than
 * WALK_MAX_CROSSINGS. It is dropped (black) and haze says so. */
static void test_too_many_crossings_warns(void **state)
{
    (void)state;
    char world[8192] = "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                       "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" "
                       "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0 0 0]\n"
                       "Material \"interface\"\nMediumInterface \"m\" \"\"\n";
    for (int i = 0; i < 40; ++i) {
        size_t n = strlen(world);
        snprintf(world + n, sizeof world - n, "Shape \"sphere\" \"float radius\" %g\n",
                 1.0 + 0.01 * i);
    }
    scene("nested", "", "", world);
    char out[4096];
    if (render("nested", out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_non_null(strstr(out, "rays crossed more than 64 interfaces and were dropped"));
    scene("nested_vp", "Integrator \"volpath\"\n", "", world);
    if (render("nested_vp", out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_non_null(strstr(out, "rays crossed more than 64 interfaces and were dropped"));
    /* Fewer crossings than the limit (the first 10 spheres: 20): no
     * warning, the sky everywhere. */
    char few[8192];
    snprintf(few, sizeof few, "%.*s",
             (int)(strstr(world, "Shape \"sphere\" \"float radius\" 1.1\n") - world), world);
    scene("nested_few", "", "", few);
    if (render("nested_few", out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_null(strstr(out, "dropped"));
    assert_true(fabs(image_mean("nested_few") - 1.0) < 1e-6);
}

int main(void)
{
    mkdir(HAZE_TMP, 0755);
    mkdir(DIR, 0755);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vanishing_camera_medium),
        cmocka_unit_test(test_unrepresentable_positions_refused),
        cmocka_unit_test(test_too_many_crossings_warns),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
