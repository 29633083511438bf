#define _POSIX_C_SOURCE 200809L
/* Cameras seen through whole renders of the haze binary: the measured circle of
 * confusion, far-from-origin precision, extreme and illegal parameters. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "cli_util.h"
#include "core/vec.h"
#include "film/exr.h"

/* Writes `text` to HAZE_TMP/name.pbrt, renders it to HAZE_TMP/name.exr and
 * returns haze's exit status; the output is in `out` (stdout+stderr). */
static int render_text(const char *name, const char *text, const char *extra, char *out,
                       size_t out_size)
{
    char scene[1024], args[4096];
    snprintf(scene, sizeof scene, "%s/%s.pbrt", HAZE_TMP, name);
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' -o '%s/%s.exr' --quiet %s", scene, HAZE_TMP, name,
             extra ? extra : "");
    return run_haze(args, out, out_size);
}

static void read_exr_or_fail(const char *name, exr_image *img)
{
    char path[1024];
    hz_error err = {0};
    snprintf(path, sizeof path, "%s/%s.exr", HAZE_TMP, name);
    if (exr_read(path, img, &err) != HZ_OK) {
        print_error("%s\n", err.message);
        fail();
    }
}

static void render_or_fail(const char *name, const char *text, const char *extra, exr_image *img)
{
    char out[8192];
    int rc = render_text(name, text, extra, out, sizeof out);
    if (rc != 0) {
        print_error("haze exited %d: %s\n", rc, out);
        fail();
    }
    if (strstr(out, "non-finite")) {
        print_error("%s\n", out);
        fail();
    }
    read_exr_or_fail(name, img);
}

static const float *channel(const exr_image *img, const char *name)
{
    const exr_channel *c = exr_find_channel(img, name);
    assert_non_null(c);
    return c->pixels;
}

/* Second radial moment of the luminance about its centroid, per unit energy. */
static double radial_moment(const exr_image *img)
{
    const float *g = channel(img, "G");
    double sum = 0, sx = 0, sy = 0;
    for (int y = 0; y < img->height; ++y)
        for (int x = 0; x < img->width; ++x) {
            double v = g[y * img->width + x];
            sum += v;
            sx += v * (x + 0.5);
            sy += v * (y + 0.5);
        }
    double cx = sx / sum, cy = sy / sum, m = 0;
    for (int y = 0; y < img->height; ++y)
        for (int x = 0; x < img->width; ++x) {
            double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
            m += g[y * img->width + x] * (dx * dx + dy * dy);
        }
    return m / sum;
}

static const char disc_scene[] =
    "LookAt 0 0 0  0 0 1  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 40 \"float lensradius\" %g \"float focaldistance\" 2\n"
    "Film \"rgb\" \"integer xresolution\" 128 \"integer yresolution\" 128\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 256\n"
    "PixelFilter \"box\"\n"
    "WorldBegin\n"
    "AttributeBegin\n"
    "  Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
    "  AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n"
    "  Translate 0 0 10\n"
    "  Shape \"disk\" \"float radius\" 1\n"
    "AttributeEnd\n";

/* A thin lens spreads every point at depth z into a disc; the image of a flat
 * emitter at that depth is the pinhole image convolved with the disc, so
 * second moments add: d^2/8 = M(lens) - M(pinhole) (the pixel box cancels). */
static void test_blur_disc_diameter(void **state)
{
    (void)state;
    const double R = 0.2, zf = 2.0, z = 10.0, fov = 40.0, n_short = 128.0;
    double expected = 2 * R * fabs(1 / zf - 1 / z) * (n_short / 2) / tan(hz_radians(fov) / 2);
    char text[4096];
    exr_image pin = {0}, lens = {0};
    snprintf(text, sizeof text, disc_scene, 0.0);
    render_or_fail("coc_pinhole", text, NULL, &pin);
    snprintf(text, sizeof text, disc_scene, R);
    render_or_fail("coc_lens", text, NULL, &lens);
    double measured = sqrt(8.0 * (radial_moment(&lens) - radial_moment(&pin)));
    print_message("circle of confusion: formula %.3f px, measured %.3f px\n", expected, measured);
    assert_true(fabs(measured - expected) < 0.02 * expected);
    exr_image_free(&pin);
    exr_image_free(&lens);
}

static const char room_scene[] =
    "LookAt %.17g %.17g %.17g  %.17g %.17g %.17g  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 50 %s\n"
    "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 8\n"
    "WorldBegin\n"
    "Translate %.17g %.17g %.17g\n"
    "LightSource \"point\" \"point3 from\" [1 2 -3] \"rgb I\" [5 5 5]\n"
    "LightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-4 -1 -4  4 -1 -4  4 -1 4  -4 -1 4]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-4 -1 3  4 -1 3  4 3 3  -4 3 3]\n"
    "AttributeBegin\n"
    "  Translate 0.3 0 0.5\n"
    "  Shape \"sphere\" \"float radius\" 0.8\n"
    "AttributeEnd\n";

static void render_room(const char *name, double offset, const char *camera_extra, int w, int h,
                        exr_image *img)
{
    char text[8192];
    snprintf(text, sizeof text, room_scene, offset, offset + 0.5, offset - 5, offset, offset,
             offset, camera_extra, w, h, offset, offset, offset);
    render_or_fail(name, text, NULL, img);
}

static void test_far_from_origin_same_image(void **state)
{
    (void)state;
    const char *cameras[] = {"", "\"float lensradius\" 0.1 \"float focaldistance\" 5"};
    for (int c = 0; c < 2; ++c) {
        exr_image near = {0}, far = {0};
        render_room("far_origin", 0.0, cameras[c], 48, 32, &near);
        render_room("far_1e7", 1e7, cameras[c], 48, 32, &far);
        const char *names[] = {"R", "G", "B"};
        double worst = 0;
        for (int ch = 0; ch < 3; ++ch) {
            const float *a = channel(&near, names[ch]), *b = channel(&far, names[ch]);
            for (int i = 0; i < near.width * near.height; ++i) {
                double rel = fabs(a[i] - b[i]) / fmax(fabs(a[i]), 1e-3);
                worst = fmax(worst, rel);
            }
        }
        print_message("camera %d: worst relative difference at 1e7: %.3g\n", c, worst);
        assert_true(worst <= 1e-4);
        exr_image_free(&near);
        exr_image_free(&far);
    }
}

static void assert_finite_image(const exr_image *img)
{
    const char *names[] = {"R", "G", "B", "A"};
    double sum = 0;
    for (int ch = 0; ch < 4; ++ch) {
        const float *p = channel(img, names[ch]);
        for (int i = 0; i < img->width * img->height; ++i) {
            assert_true(isfinite(p[i]));
            assert_true(p[i] >= 0.0f);
            sum += p[i];
        }
    }
    assert_true(sum > 0.0);
}

static void test_extreme_legal_values(void **state)
{
    (void)state;
    struct {
        const char *camera;
        int w, h;
    } cases[] = {
        {"\"float fov\" 0.001", 16, 16},
        {"\"float fov\" 179.9", 16, 16},
        {"\"float lensradius\" 0.5 \"float focaldistance\" 0.0001", 16, 16},
        {"\"float lensradius\" 0.5 \"float focaldistance\" 1e8", 16, 16},
        {"\"float lensradius\" 1e-9 \"float focaldistance\" 5", 16, 16},
        {"\"float lensradius\" 1000 \"float focaldistance\" 5", 16, 16},
        {"", 1, 1},
        {"", 4096, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char camera[256];
        /* "fov" appears in the template; drop it when the case sets its own. */
        snprintf(camera, sizeof camera, "%s", cases[i].camera);
        exr_image img = {0};
        char text[8192];
        snprintf(text, sizeof text, room_scene, 0.0, 0.5, -5.0, 0.0, 0.0, 0.0, camera, cases[i].w,
                 cases[i].h, 0.0, 0.0, 0.0);
        if (strstr(camera, "fov")) {
            /* Replace the template's fov with the case's. */
            char *p = strstr(text, "\"float fov\" 50 ");
            assert_non_null(p);
            memset(p, ' ', strlen("\"float fov\" 50 "));
        }
        print_message("extreme case: %s %dx%d\n", cases[i].camera, cases[i].w, cases[i].h);
        render_or_fail("extreme", text, NULL, &img);
        assert_int_equal(img.width, cases[i].w);
        assert_int_equal(img.height, cases[i].h);
        assert_finite_image(&img);
        exr_image_free(&img);
    }
}

static void test_illegal_values_are_located_errors(void **state)
{
    (void)state;
    struct {
        const char *camera, *film, *expect;
    } cases[] = {
        {"\"float fov\" 0", "", "fov"},
        {"\"float fov\" 180", "", "fov"},
        {"\"float fov\" -5", "", "fov"},
        {"\"float lensradius\" -1", "", "lensradius"},
        {"\"float focaldistance\" -1", "", "focaldistance"},
        {"\"float focaldistance\" 0", "", "focaldistance"},
        {"", "\"integer xresolution\" 0", "xresolution"},
        {"", "\"integer yresolution\" -3", "yresolution"},
        {"\"float shutteropen\" 1 \"float shutterclose\" 0", "", "shutteropen"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char text[2048], out[4096], expect[1200];
        snprintf(text, sizeof text,
                 "LookAt 0 0 -5  0 0 0  0 1 0\n"
                 "Camera \"perspective\" %s\n"
                 "Film \"rgb\" %s\n"
                 "WorldBegin\n",
                 cases[i].camera, cases[i].film);
        assert_int_equal(render_text("illegal", text, NULL, out, sizeof out), 1);
        snprintf(expect, sizeof expect, "%s/illegal.pbrt:%d:", HAZE_TMP,
                 cases[i].film[0] ? 3 : 2);
        print_message("%s", out);
        assert_non_null(strstr(out, expect));
        assert_non_null(strstr(out, cases[i].expect));
    }
}

static void test_lens_radius_zero_is_pinhole(void **state)
{
    (void)state;
    char text[8192], out[4096], a[1024], b[1024];
    snprintf(text, sizeof text, room_scene, 0.0, 0.5, -5.0, 0.0, 0.0, 0.0, "", 40, 30, 0.0, 0.0,
             0.0);
    assert_int_equal(render_text("pinhole", text, NULL, out, sizeof out), 0);
    snprintf(text, sizeof text, room_scene, 0.0, 0.5, -5.0, 0.0, 0.0, 0.0,
             "\"float lensradius\" 0 \"float focaldistance\" 3", 40, 30, 0.0, 0.0, 0.0);
    assert_int_equal(render_text("lens0", text, NULL, out, sizeof out), 0);
    snprintf(a, sizeof a, "%s/pinhole.exr", HAZE_TMP);
    snprintf(b, sizeof b, "%s/lens0.exr", HAZE_TMP);
    size_t na, nb;
    unsigned char *da = read_exr_pixels(a, &na), *db = read_exr_pixels(b, &nb);
    assert_non_null(da);
    assert_non_null(db);
    assert_int_equal(na, nb);
    assert_memory_equal(da, db, na);
    free(da);
    free(db);
}

/* A moving camera: an orthographic camera that slides 2 units (16 pixels) along
 * +x during the shutter over an emitting square 8 pixels wide. Each pixel sees
 * the fraction of the shutter during which the square covers it: the static
 * square convolved with a 16-pixel box. Energy is conserved. */
static const char *motion_scene_fmt =
    "LookAt 0 0 0  0 0 1  0 1 0\n"
    "%s"
    "Camera \"orthographic\" %s\n"
    "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 16\n"
    "PixelFilter \"box\" \"float xradius\" 0.5 \"float yradius\" 0.5\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 256\n"
    "WorldBegin\n"
    "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n"
    "Shape \"bilinearmesh\" \"point3 P\" [-0.5 -0.5 5  0.5 -0.5 5  -0.5 0.5 5  0.5 0.5 5]\n";

static void render_motion(const char *name, const char *motion, const char *camera_params,
                          exr_image *img)
{
    char text[2048];
    snprintf(text, sizeof text, motion_scene_fmt, motion, camera_params);
    render_or_fail(name, text, NULL, img);
}

/* Fraction of pixel [x, x+1] x shutter [0, 1] covered by the square whose
 * raster span is [c - 4, c + 4], c = c0 + v u. */
static double covered(int x, double c0, double v)
{
    const int n = 400;
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            double px = x + (i + 0.5) / n, c = c0 + v * (j + 0.5) / n;
            sum += fabs(px - c) < 4.0;
        }
    return sum / ((double)n * n);
}

static void test_moving_camera_streak(void **state)
{
    (void)state;
    exr_image moving, still;
    render_motion("motion_moving", "ActiveTransform EndTime\nTranslate -2 0 0\nActiveTransform All\n",
                  "", &moving);
    render_motion("motion_still", "", "", &still);
    const float *m = channel(&moving, "G"), *s = channel(&still, "G");
    double e_moving = 0, e_still = 0, worst = 0;
    for (int x = 0; x < 64; ++x) {
        double mean = 0;
        for (int y = 4; y < 12; ++y) /* rows inside the square */
            mean += m[y * 64 + x] / 8.0;
        worst = fmax(worst, fabs(mean - covered(x, 32.0, -16.0)));
        for (int y = 0; y < 16; ++y) {
            e_moving += m[y * 64 + x];
            e_still += s[y * 64 + x];
        }
    }
    print_message("moving camera: worst row-profile error %.4f, energy %.4f vs %.4f\n", worst,
                  e_moving, e_still);
    assert_true(worst < 0.02);
    assert_true(fabs(e_still - 64.0) < 1e-3); /* 8 x 8 pixels of radiance 1 */
    assert_true(fabs(e_moving / e_still - 1.0) < 0.005);
    exr_image_free(&moving);
    exr_image_free(&still);

    /* A very short shutter at mid-time with iso compensating (imaging ratio 1)
     * is the static image of the camera halfway, at x = +1. */
    exr_image brief, halfway;
    render_motion("motion_brief", "ActiveTransform EndTime\nTranslate -2 0 0\nActiveTransform All\n",
                  "\"float shutteropen\" 0.5 \"float shutterclose\" 0.500001", &brief);
    render_motion("motion_halfway", "Translate -1 0 0\n", "", &halfway);
    const float *b = channel(&brief, "G"), *h = channel(&halfway, "G");
    double diff = 0;
    for (int i = 0; i < 64 * 16; ++i)
        diff = fmax(diff, fabs(b[i] * 1e6 - h[i]));
    print_message("short shutter vs static halfway: worst pixel difference %.2e\n", diff);
    assert_true(diff < 1e-3);
    exr_image_free(&brief);
    exr_image_free(&halfway);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_blur_disc_diameter),
        cmocka_unit_test(test_moving_camera_streak),
        cmocka_unit_test(test_far_from_origin_same_image),
        cmocka_unit_test(test_extreme_legal_values),
        cmocka_unit_test(test_illegal_values_are_located_errors),
        cmocka_unit_test(test_lens_radius_zero_is_pinhole),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
