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
    hz_error err = {0};
    if (film_params_from_entity(e, &p, &err) != HZ_OK)
        fail_msg("%s", err.message);
    entity_free(e);
    return p;
}

static void params_fail(scene_entity *e, const char *needle)
{
    film_params p;
    hz_error err = {0};
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
    add_float(&e, "scale", 2.5);
    p = params_ok(&e);
    assert_true(p.scale == 2.5);
    assert_int_equal(p.xres, 64);
    assert_int_equal(p.bounds.y1, 32);
    assert_string_equal(p.filename, "out/fog.EXR");
    assert_true(p.savefp16 && p.write_z);
    assert_true(p.iso == 400.0 && p.max_component_value == 10.0);
    assert_false(p.write_variance || p.write_sample_count);

    entity_init(&e, "rgb");
    add_bool(&e, "writevariance", true);
    add_bool(&e, "writesamplecount", true);
    p = params_ok(&e);
    assert_true(p.write_variance && p.write_sample_count);
    assert_false(film_params_writes_png(&p));

    /* pbrt-v4 writes the format the name gives; haze, PNG too. */
    entity_init(&e, "rgb");
    add_string(&e, "filename", "out/fog.PNG");
    p = params_ok(&e);
    assert_string_equal(p.filename, "out/fog.PNG");
    assert_true(film_params_writes_png(&p));
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
    entity_init(&e, "spectral");
    params_fail(&e, "spectral");
    entity_init(&e, "spectral");
    params_fail(&e, "\"gbuffer\"");
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 0);
    params_fail(&e, "xresolution");
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 16000000);
    add_int(&e, "yresolution", 16000000);
    params_fail(&e, "GiB");
    entity_init(&e, "rgb");
    add_string(&e, "filename", "out.tif");
    params_fail(&e, "must end in .exr or .png");
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
    add_string(&e, "sensor", "canon_eos_101d");
    params_fail(&e, "canon_eos_100d"); /* the error lists the known sensors */
    entity_init(&e, "rgb");
    add_float(&e, "whitebalance", 500);
    params_fail(&e, "whitebalance");
    entity_init(&e, "rgb");
    add_float(&e, "xresolution", 100); /* wrong type */
    params_fail(&e, "xresolution");
    entity_init(&e, "rgb");
    add_float(&e, "exposure", 2);
    params_fail(&e, "exposure");
    entity_init(&e, "rgb");
    add_float(&e, "iso", -5);
    params_fail(&e, "iso");
    /* The statistics count in the memory estimate: 40000 x 25000 pixels need
     * 1e9 * 48 bytes = 44.7 GiB plain (accepted), 1e9 * 124 bytes = 115.5 GiB
     * with variance (refused). */
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 40000);
    add_int(&e, "yresolution", 25000);
    params_ok(&e);
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 40000);
    add_int(&e, "yresolution", 25000);
    add_bool(&e, "writevariance", true);
    params_fail(&e, "115.5 GiB");
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 40000);
    add_int(&e, "yresolution", 25000);
    add_bool(&e, "writesamplecount", true); /* 56 bytes: 52.2 GiB, still accepted */
    params_ok(&e);
    entity_init(&e, "rgb");
    add_int(&e, "xresolution", 50000);
    add_int(&e, "yresolution", 25000);
    add_bool(&e, "writesamplecount", true); /* 1.25e9 * 56 bytes = 65.2 GiB */
    params_fail(&e, "65.2 GiB");
}

static film *film_with(const film_params *p)
{
    hz_error err = {0};
    film *f = film_create(p, &err);
    if (!f)
        fail_msg("%s", err.message);
    return f;
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
    return film_with(&p);
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

    /* maxcomponentvalue scales the sample so the largest component of its
     * sensor RGB fits: XYZ for pbrt-v4's default "cie1931" sensor. sRGB
     * (4, 2, 1) is XYZ (2.5452, 2.3531, 1.2665); blue (0, 0, 1) has X, Y, Z
     * at most 0.9503, so a clamp at 0.95 scales it (one on sRGB would not). */
    film_params p;
    film_params_default(&p);
    p.xres = p.yres = 2;
    p.bounds = (pixel_bounds){0, 0, 2, 2};
    p.max_component_value = 2.0;
    f = film_create(&p, NULL);
    assert_non_null(f);
    film_add_sample(f, 1, 1, rgb_make(4.0, 2.0, 1.0), 1.0, INFINITY);
    v = film_get_pixel(f, 1, 1, 1.0);
    double k = 2.0 / (0.4123908 * 4.0 + 0.3575843 * 2.0 + 0.1804808 * 1.0);
    assert_float_equal(v.r, 4.0 * k, 1e-5);
    assert_float_equal(v.g, 2.0 * k, 1e-5);
    assert_float_equal(v.b, 1.0 * k, 1e-5);
    film_add_sample(f, 0, 0, rgb_make(1.0, 0.5, 0.0), 1.0, INFINITY);
    film_set_imaging_ratio(f, 4.0); /* clamp applies to L * ratio, as pbrt-v4's sensor value */
    film_add_sample(f, 0, 1, rgb_make(1.0, 0.5, 0.0), 1.0, INFINITY);
    assert_true(film_get_pixel(f, 0, 0, 1.0).r == 1.0);
    /* X = 0.5911 * 4 = 2.364 > 2 */
    assert_float_equal(film_get_pixel(f, 0, 1, 1.0).r, 0.5 / (0.4123908 + 0.5 * 0.3575843), 1e-5);
    film_destroy(f);
    p.max_component_value = 0.95;
    f = film_create(&p, NULL);
    assert_non_null(f);
    film_add_sample(f, 0, 0, rgb_make(0.0, 0.0, 1.0), 1.0, INFINITY);
    assert_float_equal(film_get_pixel(f, 0, 0, 1.0).b, 0.95 / 0.9505321, 1e-5);
    film_destroy(f);
    p.max_component_value = 2.0;

    /* pbrt-v4's old Film "scale" multiplies the image written, after the
     * clamp: (4, 2, 1) clamped to k (4, 2, 1), written times 3. */
    p.scale = 3.0;
    f = film_create(&p, NULL);
    assert_non_null(f);
    film_add_sample(f, 1, 1, rgb_make(4.0, 2.0, 1.0), 1.0, INFINITY);
    char path[512];
    snprintf(path, sizeof path, "%s/film_scale.exr", HAZE_TMP);
    hz_error werr = {0};
    assert_int_equal(film_write_exr(f, path, 1.0, &werr), HZ_OK);
    exr_image img;
    assert_int_equal(exr_read(path, &img, &werr), HZ_OK);
    const exr_channel *R = exr_find_channel(&img, "R"), *B = exr_find_channel(&img, "B");
    assert_float_equal(R->pixels[3], 3.0 * 4.0 * k, 1e-5);
    assert_float_equal(B->pixels[3], 3.0 * 1.0 * k, 1e-5);
    exr_image_free(&img);
    film_destroy(f);
    p.scale = 1.0;

    /* Invalid bounds are refused. */
    p.bounds = (pixel_bounds){0, 0, 3, 2};
    hz_error err = {0};
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
        hz_error err = {0};
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

/* A film of w x h pixels from the origin with the statistics AOVs. */
static film *stats_film(int w, int h, bool fp16, double max_component)
{
    film_params p;
    film_params_default(&p);
    p.xres = w;
    p.yres = h;
    p.bounds = (pixel_bounds){0, 0, w, h};
    p.write_variance = p.write_sample_count = true;
    p.savefp16 = fp16;
    p.max_component_value = max_component;
    return film_with(&p);
}

/* Deterministic samples: a large offset (so a naive sum-of-squares formula
 * would lose digits) plus a spread, per component. */
static double sample_value(int i, int c)
{
    uint32_t h = (uint32_t)i * 2654435761u ^ (uint32_t)(c + 1) * 40503u;
    h ^= h >> 15;
    h *= 2246822519u;
    h ^= h >> 13;
    return 1000.0 * (c + 1) + (double)(h % 100000u) / 100000.0 * (c + 0.5);
}

/* Two-pass reference: |w|-weighted mean, M2 = sum |w| (x - mean)^2, n_eff =
 * W^2/W2 and (M2/W)/(n_eff - 1). */
static double two_pass_variance(const double *x, const double *w, int n)
{
    double W = 0, W2 = 0, S = 0;
    for (int i = 0; i < n; i++) {
        W += fabs(w[i]);
        W2 += w[i] * w[i];
        S += fabs(w[i]) * x[i];
    }
    double mean = S / W, M2 = 0;
    for (int i = 0; i < n; i++)
        M2 += fabs(w[i]) * (x[i] - mean) * (x[i] - mean);
    double neff = W * W / W2;
    return neff > 1.0 ? (M2 / W) / (neff - 1.0) : 0.0;
}

static void assert_rel(double got, double want, double rel)
{
    if (!(fabs(got - want) <= rel * fabs(want)))
        fail_msg("got %.17g, want %.17g (relative tolerance %g)", got, want, rel);
}

static void test_variance_equal_weights(void **state)
{
    (void)state;
    enum { N = 1000 };
    film *f = stats_film(3, 2, false, INFINITY);
    static double x[3][N], w[N];
    /* Equal weights (pbrt-v4's sampled positive filters): exactly s^2 / n. The
     * weight is the gaussian filter's tabulated integral, not 1. */
    for (int i = 0; i < N; i++) {
        for (int c = 0; c < 3; c++)
            x[c][i] = sample_value(i, c);
        w[i] = 0.7268;
        film_add_sample(f, 2, 1, rgb_make(x[0][i], x[1][i], x[2][i]), w[i], INFINITY);
    }
    for (double ratio = 1.0; ratio <= 3.0; ratio += 2.0) {
        rgb v = film_get_variance(f, 2, 1, ratio);
        double got[3] = {v.r, v.g, v.b};
        for (int c = 0; c < 3; c++) {
            double mean = 0, ss = 0;
            for (int i = 0; i < N; i++)
                mean += x[c][i];
            mean /= N;
            for (int i = 0; i < N; i++)
                ss += (x[c][i] - mean) * (x[c][i] - mean);
            double s2_over_n = ss / (N - 1) / N;
            assert_rel(got[c], ratio * ratio * s2_over_n, 1e-10);
            assert_rel(got[c], ratio * ratio * two_pass_variance(x[c], w, N), 1e-10);
        }
    }
    assert_int_equal(film_get_sample_count(f, 2, 1), N);
    /* The mean is untouched by the extra state. */
    double mean0 = 0;
    for (int i = 0; i < N; i++)
        mean0 += x[0][i];
    assert_rel(film_get_pixel(f, 2, 1, 1.0).r, mean0 / N, 1e-13);

    /* No sample, or one: n_eff <= 1 gives 0. Two samples 1 and 3: s^2/n = 2/2. */
    rgb z = film_get_variance(f, 0, 0, 1.0);
    assert_true(z.r == 0.0 && z.g == 0.0 && z.b == 0.0);
    assert_int_equal(film_get_sample_count(f, 0, 0), 0);
    film_add_sample(f, 0, 0, rgb_make(5.0, 6.0, 7.0), 2.5, INFINITY);
    z = film_get_variance(f, 0, 0, 1.0);
    assert_true(z.r == 0.0 && z.g == 0.0 && z.b == 0.0);
    assert_int_equal(film_get_sample_count(f, 0, 0), 1);
    film_add_sample(f, 1, 0, rgb_grey(1.0), 1.0, INFINITY);
    film_add_sample(f, 1, 0, rgb_grey(3.0), 1.0, INFINITY);
    assert_true(film_get_variance(f, 1, 0, 1.0).g == 1.0);
    assert_true(film_get_variance(f, 1, 0, 2.0).g == 4.0); /* imaging ratio squared */
    film_destroy(f);
}

/* film_add_black is film_add_sample of a black sample at no depth: the
 * same pixel, variance, sample count and non-finite count, bit for bit,
 * for positive, negative, zero and NaN weights, after coloured samples too. */
static void test_black_samples(void **state)
{
    (void)state;
    film *a = stats_film(3, 2, false, 10.0), *b = stats_film(3, 2, false, 10.0);
    double w[] = {0.7268, -0.2, 0.0, 1.5, NAN, 0.3};
    for (int i = 0; i < 6; i++) {
        film_add_sample(a, 1, 1, rgb_grey(0.0), w[i], INFINITY);
        film_add_black(b, 1, 1, w[i]);
        if (i == 3) { /* pixel (2, 0): colour, then black */
            film_add_sample(a, 2, 0, rgb_make(0.5, 2.0, 30.0), 0.8, 1.0);
            film_add_sample(b, 2, 0, rgb_make(0.5, 2.0, 30.0), 0.8, 1.0);
        }
        film_add_sample(a, 2, 0, rgb_grey(0.0), w[i], INFINITY);
        film_add_black(b, 2, 0, w[i]);
    }
    for (int py = 0; py < 2; py++)
        for (int px = 0; px < 3; px++) {
            rgb pa = film_get_pixel(a, px, py, 1.0), pb = film_get_pixel(b, px, py, 1.0);
            rgb va = film_get_variance(a, px, py, 1.0), vb = film_get_variance(b, px, py, 1.0);
            assert_memory_equal(&pa, &pb, sizeof pa);
            assert_memory_equal(&va, &vb, sizeof va);
            assert_int_equal(film_get_sample_count(a, px, py), film_get_sample_count(b, px, py));
        }
    assert_int_equal(film_get_sample_count(b, 1, 1), 5);
    assert_true(film_get_pixel(b, 2, 0, 1.0).g > 0.0);
    assert_true(film_get_variance(b, 2, 0, 1.0).b > 0.0);
    assert_int_equal(film_nonfinite_count(a), 2);
    assert_int_equal(film_nonfinite_count(b), 2);
    film_destroy(a);
    film_destroy(b);
}

static void test_variance_weighted(void **state)
{
    (void)state;
    enum { N = 257 };
    film *f = stats_film(2, 2, false, INFINITY);
    static double x[3][N], w[N];
    for (int i = 0; i < N; i++) {
        for (int c = 0; c < 3; c++)
            x[c][i] = sample_value(i + 7, c);
        /* Unequal weights of both signs (a filter with negative lobes):
         * the variance uses |w|. */
        w[i] = (0.2 + (i % 5) * 0.45) * (i % 7 == 3 ? -1.0 : 1.0);
        film_add_sample(f, 1, 1, rgb_make(x[0][i], x[1][i], x[2][i]), w[i], INFINITY);
    }
    rgb v = film_get_variance(f, 1, 1, 0.5);
    double got[3] = {v.r, v.g, v.b};
    for (int c = 0; c < 3; c++)
        assert_rel(got[c], 0.25 * two_pass_variance(x[c], w, N), 1e-10);
    assert_int_equal(film_get_sample_count(f, 1, 1), N);

    /* Positive unequal weights: the estimate equals sum w^2 s_w^2 / W^2 with
     * the unbiased weighted variance s_w^2 = M2 / (W - W2/W), i.e. the variance
     * of the weighted mean for independent samples. */
    double xs[4] = {1.0, 2.0, 4.0, 8.0}, ws[4] = {1.0, 2.0, 0.5, 1.5};
    for (int i = 0; i < 4; i++)
        film_add_sample(f, 0, 1, rgb_grey(xs[i]), ws[i], INFINITY);
    double W = 5.0, W2 = 1 + 4 + 0.25 + 2.25, mean = (1 + 4 + 2 + 12) / W, M2 = 0;
    for (int i = 0; i < 4; i++)
        M2 += ws[i] * (xs[i] - mean) * (xs[i] - mean);
    double sw2 = M2 / (W - W2 / W);
    assert_rel(film_get_variance(f, 0, 1, 1.0).b, W2 * sw2 / (W * W), 1e-14);

    /* Zero weights add nothing to the moments but count as samples. */
    film_add_sample(f, 1, 0, rgb_grey(1.0), 1.0, INFINITY);
    film_add_sample(f, 1, 0, rgb_grey(100.0), 0.0, INFINITY);
    film_add_sample(f, 1, 0, rgb_grey(3.0), 1.0, INFINITY);
    assert_true(film_get_variance(f, 1, 0, 1.0).r == 1.0);
    assert_int_equal(film_get_sample_count(f, 1, 0), 3);
    /* Non-finite samples are dropped: not in the moments, not counted. */
    film_add_sample(f, 1, 0, rgb_make(NAN, 1, 1), 1.0, INFINITY);
    film_add_sample(f, 1, 0, rgb_grey(1.0), INFINITY, INFINITY);
    assert_true(film_get_variance(f, 1, 0, 1.0).r == 1.0);
    assert_int_equal(film_get_sample_count(f, 1, 0), 3);
    film_destroy(f);

    /* The moments see the clamped values the mean sees: red 4 has X =
     * 4 * 0.412391 = 1.64956 and clamps to 4 * 1.2 / 1.64956 = 2.9099. */
    f = stats_film(1, 1, false, 1.2);
    film_add_sample(f, 0, 0, rgb_make(4.0, 0.0, 0.0), 1.0, INFINITY);
    film_add_sample(f, 0, 0, rgb_make(1.0, 0.0, 0.0), 1.0, INFINITY);
    double c = 4.0 * 1.2 / (4.0 * 0.4123908);
    assert_float_equal(film_get_pixel(f, 0, 0, 1.0).r, (c + 1.0) / 2.0, 1e-6);
    rgb cv = film_get_variance(f, 0, 0, 1.0);
    assert_float_equal(cv.r, (c - 1.0) * (c - 1.0) / 4.0, 1e-6); /* s^2 / n */
    assert_true(cv.g == 0.0 && cv.b == 0.0);
    film_destroy(f);
}

static void test_write_statistics(void **state)
{
    (void)state;
    for (int fp16 = 0; fp16 < 2; fp16++) {
        film *f = stats_film(4, 3, fp16, INFINITY);
        for (int y = 0; y < 3; y++)
            for (int x = 0; x < 4; x++)
                for (int i = 0; i < x + 4 * y; i++) /* pixel (x, y) gets x + 4y samples */
                    film_add_sample(f, x, y, rgb_make(sample_value(i, 0) - 1000.0, 0.001 * i, 1e-4 * i * i),
                                    1.0, INFINITY);
        char path[512];
        snprintf(path, sizeof path, "%s/film_stats_%d.exr", HAZE_TMP, fp16);
        hz_error err = {0};
        assert_int_equal(film_write_exr(f, path, 1.5, &err), HZ_OK);
        exr_image img;
        assert_int_equal(exr_read(path, &img, &err), HZ_OK);
        assert_int_equal(img.channel_count, 8);
        const char *names[] = {"R", "G", "B", "A", "Variance.R", "Variance.G", "Variance.B", "SampleCount.Y"};
        for (int c = 0; c < 8; c++) {
            const exr_channel *ch = exr_find_channel(&img, names[c]);
            if (!ch)
                fail_msg("no channel %s", names[c]);
            assert_int_equal(ch->half, fp16 && c < 4); /* the statistics stay float */
        }
        const exr_channel *V[3] = {exr_find_channel(&img, "Variance.R"), exr_find_channel(&img, "Variance.G"),
                                   exr_find_channel(&img, "Variance.B")};
        const exr_channel *S = exr_find_channel(&img, "SampleCount.Y");
        for (int y = 0; y < 3; y++)
            for (int x = 0; x < 4; x++) {
                int i = y * 4 + x;
                rgb v = film_get_variance(f, x, y, 1.5);
                assert_true(V[0]->pixels[i] == (float)v.r);
                assert_true(V[1]->pixels[i] == (float)v.g);
                assert_true(V[2]->pixels[i] == (float)v.b);
                assert_true(S->pixels[i] == (float)(x + 4 * y));
                if (x + 4 * y >= 2)
                    assert_true(v.g > 0.0);
            }
        /* Pixel (3, 0): 3 samples of G = 0, 0.001, 0.002: s^2/n = 1e-6/3, times 1.5^2. */
        assert_float_equal(V[1]->pixels[3], 2.25e-6 / 3.0, 1e-12);
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
    hz_error err = {0};
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

/* A gbuffer pixel: pbrt-v4's per-sample variance (not the mean's) and
 * RelativeVariance = variance / mean; the surface channels average the hits
 * (albedo over every sample, misses count 0); a pixel with no hit is 0. */
static void test_gbuffer_pixel(void **state)
{
    (void)state;
    film_params p;
    film_params_default(&p);
    p.xres = p.yres = 2;
    p.bounds = (pixel_bounds){0, 0, 2, 2};
    p.gbuffer = p.write_variance = true;
    film *f = film_with(&p);
    film_set_output_from_render(f, transform_translate(v3(0.0, 0.0, 10.0)));
    const double values[4] = {1.0, 2.0, 3.0, 6.0};
    for (int i = 0; i < 4; ++i) {
        film_add_sample(f, 1, 0, rgb_grey(values[i]), 1.0, INFINITY);
        film_surface s = {.hit = i < 2, .p = v3(i, 0.0, 1.0), .n = v3(0.0, 0.0, 1.0),
                          .ns = v3(0.0, 1.0, 0.0), .dpdx = v3(0.0, 0.0, -0.5),
                          .u = 0.25 * i, .v = 1.0, .albedo = rgb_make(0.4, 0.8, 0.2)};
        film_add_surface(f, 1, 0, 1.0, &s);
    }
    char path[512];
    snprintf(path, sizeof path, "%s/film_gbuffer.exr", HAZE_TMP);
    hz_error err = {0};
    assert_int_equal(film_write_exr(f, path, 1.0, &err), HZ_OK);
    film_destroy(f);
    exr_image img;
    assert_int_equal(exr_read(path, &img, &err), HZ_OK);
    struct {
        const char *name;
        double pixel1, pixel0;
    } want[] = {
        {"Variance.G", 14.0 / 3.0, 0.0}, {"RelativeVariance.G", 14.0 / 9.0, 0.0},
        {"Albedo.R", 0.2, 0.0},          {"Albedo.G", 0.4, 0.0},
        {"P.X", 0.5, 0.0},               {"P.Z", 11.0, 0.0},
        {"N.Z", 1.0, 0.0},               {"Ns.Y", 1.0, 0.0},
        {"dzdx", 0.5, 0.0},              {"dzdy", 0.0, 0.0},
        {"u", 0.125, 0.0},               {"v", 1.0, 0.0},
    };
    for (size_t k = 0; k < sizeof want / sizeof want[0]; ++k) {
        const exr_channel *c = exr_find_channel(&img, want[k].name);
        assert_non_null(c);
        assert_float_equal(c->pixels[1], want[k].pixel1, 1e-6);
        assert_float_equal(c->pixels[0], want[k].pixel0, 0.0);
    }
    exr_image_free(&img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_accumulation),
        cmocka_unit_test(test_write_exr),
        cmocka_unit_test(test_variance_equal_weights),
        cmocka_unit_test(test_variance_weighted),
        cmocka_unit_test(test_black_samples),
        cmocka_unit_test(test_write_statistics),
        cmocka_unit_test(test_write_png),
        cmocka_unit_test(test_gbuffer_pixel),
        /* Factories last: they need scene/params. */
        cmocka_unit_test(test_params_defaults),
        cmocka_unit_test(test_params_bounds),
        cmocka_unit_test(test_params_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
