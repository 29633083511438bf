/* Film "gbuffer" (pbrt-v4's GBufferFilm): an orthographic camera at
 * (0, 0, 5) looks down -z at the tilted plane z = x / 2 (uv over
 * [-2, 2]^2) of a diffuse material, with pixel jitter off so that every
 * sample of a pixel sees its centre: each channel is a closed form of the
 * pixel's screen position (x_s, y_s). Camera space (pbrt-v4's LookAt):
 * x_c = -x, y_c = y, z_c = 5 - z, so the visible point is (x_s, y_s,
 * 5 + x_s / 2) and its normal, facing the camera, (1, 0, -2) / sqrt(5). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <unistd.h>

#include <cmocka.h>

#include "render/cli_util.h"

enum { RES = 16 };

static const char *scene_fmt =
    "Option \"bool disablepixeljitter\" true\n"
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "Camera \"orthographic\"\n"
    "Film \"gbuffer\" \"integer xresolution\" 16 \"integer yresolution\" 16 %s\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 8\n"
    "Integrator \"volpath\" \"integer maxdepth\" 1\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
    "Material \"diffuse\" \"rgb reflectance\" [0.2 0.4 0.6]\n"
    "Shape \"trianglemesh\" \"point3 P\" [-2 -2 -1  2 -2 1  2 2 1  -2 2 -1]\n"
    "  \"point2 uv\" [0 0 1 0 1 1 0 1] \"integer indices\" [0 1 2 0 2 3]\n";

/* Renders the scene with `film_extra` and reads the EXR into *img. */
static void render_gbuffer(const char *film_extra, const char *name, exr_image *img)
{
    char scene[1400], path[1200], text[2048], args[3000], out[4096];
    snprintf(scene, sizeof scene, "%s/%s-%ld.pbrt", HAZE_TMP, name, (long)getpid());
    snprintf(path, sizeof path, "%s/%s-%ld.exr", HAZE_TMP, name, (long)getpid());
    snprintf(text, sizeof text, scene_fmt, film_extra);
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet", scene, path);
    int status = run_haze(args, out, sizeof out);
    if (status != 0)
        fail_msg("exit %d: %s", status, out);
    hz_error err;
    assert_int_equal(exr_read(path, img, &err), HZ_OK);
}

static double at(const exr_image *img, const char *channel, int x, int y)
{
    const exr_channel *c = exr_find_channel(img, channel);
    if (!c)
        fail_msg("no channel %s", channel);
    return c->pixels[y * img->width + x];
}

static void expect(const exr_image *img, const char *channel, int x, int y, double want,
                   double tol)
{
    double got = at(img, channel, x, y);
    if (!(fabs(got - want) <= tol))
        fail_msg("%s at (%d, %d): %.7g, want %.7g", channel, x, y, got, want);
}

/* pbrt-v4's channel list (haze adds A); an EXR stores channels sorted by
 * name, so the file's order is not the writer's. */
static void test_channels(void **state)
{
    (void)state;
    exr_image img;
    render_gbuffer("", "gbuffer_channels", &img);
    static const char *want[] = {"R", "G", "B", "A", "Albedo.R", "Albedo.G", "Albedo.B",
                                 "P.X", "P.Y", "P.Z", "dzdx", "dzdy", "N.X", "N.Y", "N.Z",
                                 "Ns.X", "Ns.Y", "Ns.Z", "u", "v", "Variance.R", "Variance.G",
                                 "Variance.B", "RelativeVariance.R", "RelativeVariance.G",
                                 "RelativeVariance.B"};
    assert_int_equal(img.channel_count, (int)(sizeof want / sizeof want[0]));
    for (size_t c = 0; c < sizeof want / sizeof want[0]; ++c)
        if (!exr_find_channel(&img, want[c]))
            fail_msg("no channel %s", want[c]);
    exr_image_free(&img);
}

static void test_camera_space(void **state)
{
    (void)state;
    exr_image img;
    render_gbuffer("", "gbuffer_camera", &img);
    double k = 1.0 / sqrt(5.0);
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            double xs = -1.0 + (x + 0.5) * 2.0 / RES, ys = 1.0 - (y + 0.5) * 2.0 / RES;
            expect(&img, "P.X", x, y, xs, 1e-5);
            expect(&img, "P.Y", x, y, ys, 1e-5);
            expect(&img, "P.Z", x, y, 5.0 + 0.5 * xs, 1e-5);
            expect(&img, "N.X", x, y, k, 1e-5);
            expect(&img, "N.Y", x, y, 0.0, 1e-5);
            expect(&img, "N.Z", x, y, -2.0 * k, 1e-5);
            expect(&img, "Ns.Z", x, y, -2.0 * k, 1e-5);
            /* One pixel is 2 / RES in x_s; z_c changes by half of it. */
            expect(&img, "dzdx", x, y, 0.5 * 2.0 / RES, 1e-5);
            expect(&img, "dzdy", x, y, 0.0, 1e-5);
            /* World x = -x_s: u = (x + 2) / 4, v = (y + 2) / 4. */
            expect(&img, "u", x, y, (2.0 - xs) / 4.0, 1e-5);
            expect(&img, "v", x, y, (ys + 2.0) / 4.0, 1e-5);
            /* A diffuse BSDF's directional albedo is its reflectance. */
            expect(&img, "Albedo.R", x, y, 0.2, 1e-5);
            expect(&img, "Albedo.G", x, y, 0.4, 1e-5);
            expect(&img, "Albedo.B", x, y, 0.6, 1e-5);
            assert_true(at(&img, "Variance.G", x, y) >= 0.0);
        }
    exr_image_free(&img);
}

static void test_world_space(void **state)
{
    (void)state;
    exr_image img;
    render_gbuffer("\"string coordinatesystem\" \"world\"", "gbuffer_world", &img);
    double k = 1.0 / sqrt(5.0);
    for (int y = 0; y < RES; y += 3)
        for (int x = 0; x < RES; x += 3) {
            double xs = -1.0 + (x + 0.5) * 2.0 / RES, ys = 1.0 - (y + 0.5) * 2.0 / RES;
            expect(&img, "P.X", x, y, -xs, 1e-5);
            expect(&img, "P.Y", x, y, ys, 1e-5);
            expect(&img, "P.Z", x, y, -0.5 * xs, 1e-5);
            expect(&img, "N.X", x, y, -k, 1e-5);
            expect(&img, "N.Z", x, y, 2.0 * k, 1e-5);
            /* pbrt-v4 writes the world-space z slope here. */
            expect(&img, "dzdx", x, y, 0.5 * 2.0 / RES, 1e-5);
        }
    exr_image_free(&img);
}

static void test_refused(void **state)
{
    (void)state;
    char scene[1200], text[2048], args[1400], out[4096];
    snprintf(scene, sizeof scene, "%s/gbuffer_bad-%ld.pbrt", HAZE_TMP, (long)getpid());
    snprintf(text, sizeof text, scene_fmt, "\"string coordinatesystem\" \"screen\"");
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' --quiet", scene);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, ":4:"));
    assert_non_null(strstr(out, "coordinatesystem"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_channels),
        cmocka_unit_test(test_camera_space),
        cmocka_unit_test(test_world_space),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
