#define _POSIX_C_SOURCE 200809L
/* The realistic camera through whole renders of the haze binary: the field
 * of view the thick lens and the film's diagonal predict, and the corners a
 * wide-open double Gauss darkens. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "camera/realistic.h"
#include "cli_util.h"
#include "core/vec.h"
#include "film/exr.h"

static void render_or_fail(const char *name, const char *text, exr_image *img)
{
    char scene[1024], args[4096], out[8192];
    snprintf(scene, sizeof scene, "%s/%s.pbrt", HAZE_TMP, name);
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' -o '%s/%s.exr' --quiet", scene, HAZE_TMP, name);
    int rc = run_haze(args, out, sizeof out);
    if (rc != 0)
        fail_msg("haze exited %d: %s", rc, out);
    char path[1024];
    hz_error err = {0};
    snprintf(path, sizeof path, "%s/%s.exr", HAZE_TMP, name);
    if (exr_read(path, img, &err) != HZ_OK)
        fail_msg("%s", err.message);
}

static const float *channel(const exr_image *img, const char *name)
{
    const exr_channel *c = exr_find_channel(img, name);
    assert_non_null(c);
    return c->pixels;
}

static void write_lens(const char *name, const char *text)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", HAZE_TMP, name);
    write_text_file(path, text);
}

/* A stop 1 mm wide in front of a biconvex lens (R1 80 mm, R2 -120 mm,
 * 10 mm of n 1.5), focused at 3 m; an emitter on that plane covers camera
 * x >= x0, x0 chosen by the thick lens to image at raster column 48 of 64. */
static void test_field_of_view(void **state)
{
    (void)state;
    static const char lens[] = "0 5 1 20\n80 10 1.5 20\n-120 60 1 20\n";
    write_lens("realistic-fov.dat", lens);
    lens_table t;
    hz_error err = {0};
    assert_int_equal(lens_file_parse("lens", lens, &t, &err), HZ_OK);
    realistic_lens l;
    bool clamped;
    realistic_elements(&t, 1.0, APERTURE_CIRCLE, 35.0, 64, 32, &l, &clamped);
    assert_int_equal(realistic_focus(&l, 3.0, &err), HZ_OK);
    double pz[2], fz[2];
    assert_int_equal(realistic_thick_lens(&l, pz, fz, &err), HZ_OK);
    double x0 = 0.5 * l.film_half[0] * (3.0 + pz[1]) / -pz[0];
    char text[2048];
    snprintf(text, sizeof text,
             "Camera \"realistic\" \"string lensfile\" \"realistic-fov.dat\"\n"
             "  \"float focusdistance\" 3\n"
             "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 32\n"
             "PixelFilter \"box\" \"float xradius\" 0.5 \"float yradius\" 0.5\n"
             "Sampler \"independent\" \"integer pixelsamples\" 256\n"
             "WorldBegin\n"
             "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "  \"point3 P\" [%.9g -5 3  20 -5 3  20 5 3  %.9g 5 3]\n",
             x0, x0);
    exr_image img;
    render_or_fail("realistic-fov", text, &img);
    const float *g = channel(&img, "G");
    /* The plateau right of the edge, then the number of lit columns. */
    double plateau = 0.0, lit = 0.0;
    for (int y = 12; y < 20; ++y) {
        for (int x = 52; x < 60; ++x)
            plateau += g[y * 64 + x] / 64.0;
    }
    for (int y = 12; y < 20; ++y)
        for (int x = 0; x < 64; ++x)
            lit += g[y * 64 + x] / plateau / 8.0;
    double edge = 64.0 - lit;
    print_message("emitter edge at x0 = %.5g m: image edge at column %.3f (thick lens: 48)\n",
                  x0, edge);
    assert_true(plateau > 0.0);
    assert_true(fabs(edge - 48.0) < 0.25);
    exr_image_free(&img);
}

/* pbrt's 50 mm double Gauss (US patent 2,673,491) wide open before a white
 * sky: the mean of rings about the image centre falls from the centre out. */
static void test_vignetting_darkens_corners(void **state)
{
    (void)state;
    write_lens("realistic-dgauss.dat", "29.475 3.76 1.67 25.2\n84.83 0.12 1 25.2\n"
                                       "19.275 4.025 1.67 23\n40.77 3.275 1.699 23\n"
                                       "12.75 5.705 1 18\n0 4.5 1 17.1\n"
                                       "-14.495 1.18 1.603 17\n40.77 6.065 1.658 20\n"
                                       "-20.385 0.19 1 20\n437.065 3.22 1.717 20\n"
                                       "-39.73 5.0 1 20\n");
    exr_image img;
    render_or_fail("realistic-vignette",
                   "Camera \"realistic\" \"string lensfile\" \"realistic-dgauss.dat\"\n"
                   "  \"float aperturediameter\" 17.1 \"float focusdistance\" 5\n"
                   "Film \"rgb\" \"integer xresolution\" 96 \"integer yresolution\" 64\n"
                   "  \"float diagonal\" 60\n"
                   "Sampler \"independent\" \"integer pixelsamples\" 64\n"
                   "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n",
                   &img);
    const float *g = channel(&img, "G");
    enum { RINGS = 8 };
    double sum[RINGS] = {0}, n[RINGS] = {0}, rmax = hypot(48.0, 32.0);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 96; ++x) {
            int k = (int)(hypot(x + 0.5 - 48.0, y + 0.5 - 32.0) / rmax * RINGS);
            sum[k] += g[y * 96 + x];
            n[k] += 1.0;
        }
    for (int k = 0; k < RINGS; ++k) {
        print_message("ring %d: mean %.4f\n", k, sum[k] / n[k]);
        if (k > 0)
            assert_true(sum[k] / n[k] < sum[k - 1] / n[k - 1]);
    }
    assert_true(sum[RINGS - 1] / n[RINGS - 1] < 0.5 * sum[0] / n[0]);
    exr_image_free(&img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_field_of_view),
        cmocka_unit_test(test_vignetting_darkens_corners),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
