#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <png.h>

#include "film/exr.h"
#include "film/film.h"
#include "film/png.h"
#include "scene/params.h"
#include "unit/entity_util.h"

static void add_ints4(scene_entity *e, const char *name, double a, double b, double c, double d)
{
    double v[4] = {a, b, c, d};
    add_nums(e, PARAM_INTEGER, name, v, 4);
}

static void add_floats4(scene_entity *e, const char *name, double a, double b, double c, double d)
{
    double v[4] = {a, b, c, d};
    add_nums(e, PARAM_FLOAT, name, v, 4);
}

static film_params params_ok(scene_entity *e)
{
    film_params p;
    hz_error err = {{0}};
    if (film_params_from_entity(e, &p, &err) != HZ_OK)
        fail_msg("%s", err.message);
    entity_free(e);
    return p;
}

static void params_fail(scene_entity *e, const char *needle)
{
    film_params p;
    hz_error err = {{0}};
    assert_int_equal(film_params_from_entity(e, &p, &err), HZ_ERROR);
    if (!strstr(err.message, needle))
        fail_msg("error \"%s\" does not mention \"%s\"", err.message, needle);
    assert_non_null(strstr(err.message, "test.pbrt:3:"));
    entity_free(e);
}

static void test_params_defaults(void **state)
{
    (void)state;
    scene_entity e;
    entity_init(&e, "rgb");
    film_params p = params_ok(&e);
    assert_int_equal(p.xres, 1280);
    assert_int_equal(p.yres, 720);
    assert_int_equal(p.bounds.x0, 0);
    assert_int_equal(p.bounds.y0, 0);
    assert_int_equal(p.bounds.x1, 1280);
    assert_int_equal(p.bounds.y1, 720);
    assert_string_equal(p.filename, "pbrt.exr");
    assert_false(p.savefp16);
    assert_false(p.write_z);
    assert_true(p.iso == 100.0);
    assert_true(isinf(p.max_component_value));
    assert_true(p.diagonal == 35.0);

    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 64);
    add_int(&e, "yresolution", 32);
    add_string(&e, "filename", "out/fog.EXR");
    add_bool(&e, "savefp16", true);
    add_bool(&e, "writedepth", true);
    add_float(&e, "iso", 400);
    add_float(&e, "maxcomponentvalue", 10);
    add_string(&e, "sensor", "cie1931");
    p = params_ok(&e);
    assert_int_equal(p.xres, 64);
    assert_int_equal(p.bounds.y1, 32);
    assert_string_equal(p.filename, "out/fog.EXR");
    assert_true(p.savefp16 && p.write_z);
    assert_true(p.iso == 400.0 && p.max_component_value == 10.0);
}

static void test_params_bounds(void **state)
{
    (void)state;
    scene_entity e;
    /* pbrt-v4: bounds = ceil(res * crop). */
    entity_init(&e, "rgb");
    add_floats4(&e, "cropwindow", 0.25, 0.75, 0.1, 0.9);
    film_params p = params_ok(&e);
    assert_int_equal(p.bounds.x0, 320);
    assert_int_equal(p.bounds.x1, 960);
    assert_int_equal(p.bounds.y0, 72);
    assert_int_equal(p.bounds.y1, 648);

    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 10);
    add_int(&e, "yresolution", 10);
    add_floats4(&e, "cropwindow", 0.05, 0.15, 0.33, 0.41);
    p = params_ok(&e);
    assert_int_equal(p.bounds.x0, 1); /* ceil(0.5) */
    assert_int_equal(p.bounds.x1, 2); /* ceil(1.5) */
    assert_int_equal(p.bounds.y0, 4); /* ceil(3.3) */
    assert_int_equal(p.bounds.y1, 5); /* ceil(4.1) */

    /* pixelbounds [x0 x1 y0 y1] overrides the crop window. */
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 10);
    add_int(&e, "yresolution", 10);
    add_floats4(&e, "cropwindow", 0.0, 0.5, 0.0, 0.5);
    add_ints4(&e, "pixelbounds", 2, 5, 3, 7);
    p = params_ok(&e);
    assert_int_equal(p.bounds.x0, 2);
    assert_int_equal(p.bounds.x1, 5);
    assert_int_equal(p.bounds.y0, 3);
    assert_int_equal(p.bounds.y1, 7);
}

static void test_params_errors(void **state)
{
    (void)state;
    scene_entity e;
    entity_init(&e, "gbuffer");
    params_fail(&e, "\"rgb\"");
    entity_init(&e, "spectral");
    params_fail(&e, "spectral");
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 0);
    params_fail(&e, "xresolution");
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 16000000);
    add_int(&e, "yresolution", 16000000);
    params_fail(&e, "GiB");
    entity_init(&e, "rgb");
    add_string(&e, "filename", "out.png");
    params_fail(&e, ".exr");
    entity_init(&e, "rgb");
    add_floats4(&e, "cropwindow", -0.1, 0.5, 0, 1);
    params_fail(&e, "cropwindow");
    entity_init(&e, "rgb");
    add_floats4(&e, "cropwindow", 0.6, 0.5, 0, 1);
    params_fail(&e, "cropwindow");
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 10);
    add_floats4(&e, "cropwindow", 0.31, 0.39, 0, 1); /* ceil(3.1) == ceil(3.9): no pixel */
    params_fail(&e, "no pixel");
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 10);
    add_ints4(&e, "pixelbounds", 0, 11, 0, 5);
    params_fail(&e, "pixelbounds");
    entity_init(&e, "rgb");
    add_ints4(&e, "pixelbounds", 5, 5, 0, 5);
    params_fail(&e, "pixelbounds");
    entity_init(&e, "rgb");
    add_string(&e, "sensor", "canon_eos_100d");
    params_fail(&e, "cie1931");
    entity_init(&e, "rgb");
    add_float(&e, "xresolution", 100); /* wrong type */
    params_fail(&e, "xresolution");
    entity_init(&e, "rgb");
    add_float(&e, "exposure", 2);
    params_fail(&e, "exposure");
    entity_init(&e, "rgb");
    add_float(&e, "iso", -5);
    params_fail(&e, "iso");
}

static film *small_film(int xres, int yres, pixel_bounds b, bool z, bool fp16)
{
    film_params p;
    film_params_default(&p);
    p.xres = xres;
    p.yres = yres;
    p.bounds = b;
    p.write_z = z;
    p.savefp16 = fp16;
    hz_error err = {{0}};
    film *f = film_create(&p, &err);
    if (!f)
        fail_msg("%s", err.message);
    return f;
}

static void test_accumulation(void **state)
{
    (void)state;
    film *f = small_film(8, 6, (pixel_bounds){2, 1, 7, 5}, false, false);
    /* A constant with arbitrary (even negative) weights stays that constant. */
    double w[] = {0.3, 1.7, -0.2, 0.9, 2.5, -0.05};
    for (int i = 0; i < 6; i++)
        film_add_sample(f, 3, 2, rgb_make(0.25, 0.5, 2.0), w[i], INFINITY);
    rgb v = film_get_pixel(f, 3, 2, 1.0);
    assert_float_equal(v.r, 0.25, 1e-15);
    assert_float_equal(v.g, 0.5, 1e-15);
    assert_float_equal(v.b, 2.0, 1e-15);
    v = film_get_pixel(f, 3, 2, 0.5); /* imaging ratio scales */
    assert_float_equal(v.b, 1.0, 1e-15);
    /* Weighted mean: (1*1 + 3*2)/(1+3). */
    film_add_sample(f, 6, 4, rgb_grey(1.0), 1.0, INFINITY);
    film_add_sample(f, 6, 4, rgb_grey(2.0), 3.0, INFINITY);
    assert_float_equal(film_get_pixel(f, 6, 4, 1.0).g, 7.0 / 4.0, 1e-15);
    /* Untouched pixel: 0. */
    assert_true(rgb_is_black(film_get_pixel(f, 2, 1, 1.0)));
    /* Non-finite samples are counted and dropped. */
    assert_int_equal(film_nonfinite_count(f), 0);
    film_add_sample(f, 6, 4, rgb_make(NAN, 0, 0), 1.0, 1.0);
    film_add_sample(f, 6, 4, rgb_make(0, INFINITY, 0), 1.0, 1.0);
    film_add_sample(f, 6, 4, rgb_grey(1.0), NAN, 1.0);
    assert_int_equal(film_nonfinite_count(f), 3);
    assert_float_equal(film_get_pixel(f, 6, 4, 1.0).g, 7.0 / 4.0, 1e-15);
    film_destroy(f);

    /* maxcomponentvalue scales the sample so its largest component fits. */
    film_params p;
    film_params_default(&p);
    p.xres = p.yres = 2;
    p.bounds = (pixel_bounds){0, 0, 2, 2};
    p.max_component_value = 2.0;
    f = film_create(&p, NULL);
    assert_non_null(f);
    film_add_sample(f, 1, 1, rgb_make(4.0, 2.0, 1.0), 1.0, INFINITY);
    v = film_get_pixel(f, 1, 1, 1.0);
    assert_true(v.r == 2.0 && v.g == 1.0 && v.b == 0.5);
    film_add_sample(f, 0, 0, rgb_make(1.0, 0.5, 0.0), 1.0, INFINITY);
    film_set_imaging_ratio(f, 4.0); /* clamp applies to L * ratio, as pbrt-v4's sensor value */
    film_add_sample(f, 0, 1, rgb_make(1.0, 0.5, 0.0), 1.0, INFINITY);
    assert_true(film_get_pixel(f, 0, 0, 1.0).r == 1.0);
    assert_true(film_get_pixel(f, 0, 1, 4.0).r == 2.0);
    film_destroy(f);

    /* Invalid bounds are refused. */
    p.bounds = (pixel_bounds){0, 0, 3, 2};
    hz_error err = {{0}};
    assert_null(film_create(&p, &err));
    assert_non_null(strstr(err.message, "bounds"));
}

static void test_write_exr(void **state)
{
    (void)state;
    for (int fp16 = 0; fp16 < 2; fp16++) {
        film *f = small_film(8, 6, (pixel_bounds){2, 1, 7, 5}, true, fp16);
        for (int y = 1; y < 5; y++)
            for (int x = 2; x < 7; x++) {
                if (x == 4 && y == 3)
                    continue; /* no sample: A = 0 */
                double d1 = x + 0.5 * y, d2 = x + 0.5 * y + 2.0;
                film_add_sample(f, x, y, rgb_make(x * 0.25, y * 0.5, 1.0), 1.0, d1);
                film_add_sample(f, x, y, rgb_make(x * 0.25, y * 0.5, 1.0), -0.5, d2);
                film_add_sample(f, x, y, rgb_make(x * 0.25, y * 0.5, 1.0), 1.5, INFINITY);
            }
        char path[512];
        snprintf(path, sizeof path, "%s/film_film_%d.exr", HAZE_TMP, fp16);
        hz_error err = {{0}};
        assert_int_equal(film_write_exr(f, path, 2.0, &err), HZ_OK);
        exr_image img;
        assert_int_equal(exr_read(path, &img, &err), HZ_OK);
        assert_int_equal(img.width, 5);
        assert_int_equal(img.height, 4);
        assert_int_equal(img.data_x0, 2);
        assert_int_equal(img.data_y0, 1);
        assert_int_equal(img.display_width, 8);
        assert_int_equal(img.display_height, 6);
        assert_int_equal(img.channel_count, 5);
        const exr_channel *R = exr_find_channel(&img, "R"), *G = exr_find_channel(&img, "G"),
                          *A = exr_find_channel(&img, "A"), *Z = exr_find_channel(&img, "Z");
        assert_true(R && G && A && Z && exr_find_channel(&img, "B"));
        assert_int_equal(R->half, fp16);
        assert_int_equal(A->half, fp16);
        assert_false(Z->half);
        for (int y = 1; y < 5; y++)
            for (int x = 2; x < 7; x++) {
                int i = (y - 1) * 5 + (x - 2);
                rgb v = film_get_pixel(f, x, y, 2.0);
                float r = fp16 ? exr_half_to_float(exr_half_from_float((float)v.r)) : (float)v.r;
                assert_true(R->pixels[i] == r);
                if (x == 4 && y == 3) {
                    assert_true(A->pixels[i] == 0.0f && R->pixels[i] == 0.0f);
                    assert_true(isinf(Z->pixels[i]));
                } else {
                    assert_true(A->pixels[i] == 1.0f);
                    assert_float_equal(G->pixels[i], y * 0.5 * 2.0, 1e-3);
                    /* |w|-weighted mean of the finite depths: (1*d1 + 0.5*d2)/1.5. */
                    double d1 = x + 0.5 * y;
                    assert_float_equal(Z->pixels[i], (d1 + 0.5 * (d1 + 2.0)) / 1.5, 1e-5);
                }
            }
        exr_image_free(&img);
        film_destroy(f);
    }
}

/* Reads an 8-bit RGB PNG with libpng's simplified API. */
static uint8_t *read_png(const char *path, int *w, int *h)
{
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&im, path))
        return NULL;
    im.format = PNG_FORMAT_RGB;
    uint8_t *buf = malloc(PNG_IMAGE_SIZE(im));
    assert_non_null(buf);
    assert_true(png_image_finish_read(&im, NULL, buf, 0, NULL));
    *w = (int)im.width;
    *h = (int)im.height;
    return buf;
}

static void test_write_png(void **state)
{
    (void)state;
    assert_int_equal(png_out_srgb8(0.0), 0);
    assert_int_equal(png_out_srgb8(1.0), 255);
    assert_int_equal(png_out_srgb8(0.5), 188);   /* 1.055*0.5^(1/2.4)-0.055 = 0.7354 */
    assert_int_equal(png_out_srgb8(0.18), 118);  /* 0.4614 */
    assert_int_equal(png_out_srgb8(0.002), 7);   /* linear segment: 12.92*0.002*255 = 6.59 */
    assert_int_equal(png_out_srgb8(-1.0), 0);
    assert_int_equal(png_out_srgb8(NAN), 0);

    film *f = small_film(4, 3, (pixel_bounds){1, 0, 4, 2}, false, false);
    film_add_sample(f, 1, 0, rgb_make(0.25, 0.09, 1.0), 1.0, INFINITY); /* x ratio 2 */
    film_add_sample(f, 3, 1, rgb_make(5.0, -1.0, 0.001), 1.0, INFINITY);
    char path[512];
    snprintf(path, sizeof path, "%s/film_film.png", HAZE_TMP);
    hz_error err = {{0}};
    assert_int_equal(film_write_png(f, path, 2.0, &err), HZ_OK);
    int w = 0, h = 0;
    uint8_t *px = read_png(path, &w, &h);
    assert_non_null(px);
    assert_int_equal(w, 3);
    assert_int_equal(h, 2);
    assert_int_equal(px[0], 188);
    assert_int_equal(px[1], 118);
    assert_int_equal(px[2], 255);
    assert_int_equal(px[3], 0); /* empty pixel */
    int last = (1 * 3 + 2) * 3;
    assert_int_equal(px[last + 0], 255);
    assert_int_equal(px[last + 1], 0);
    assert_int_equal(px[last + 2], 7);
    free(px);
    /* Missing directory: error, nothing written. */
    const char *bad = HAZE_TMP "/film_film_no_dir/x.png";
    assert_int_equal(film_write_png(f, bad, 1.0, &err), HZ_ERROR);
    struct stat st;
    assert_int_not_equal(stat(bad, &st), 0);
    film_destroy(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_accumulation),
        cmocka_unit_test(test_write_exr),
        cmocka_unit_test(test_write_png),
        /* Factories last: they need scene/params. */
        cmocka_unit_test(test_params_defaults),
        cmocka_unit_test(test_params_bounds),
        cmocka_unit_test(test_params_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
