/* The realistic camera (camera/realistic.h, camera/lens_file.h): the lens
 * file reader and its errors, the thick-lens approximation against the
 * lensmaker's formula, focusing against traced rays, and the field of view
 * against the thick lens's magnification. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <setjmp.h>
#include <cmocka.h>

#include "camera/camera.h"
#include "camera/lens_file.h"
#include "camera/realistic.h"

static void expect_parse_error(const char *text, const char *want)
{
    lens_table t;
    hz_error err = {0};
    assert_int_equal(lens_file_parse("lens.dat", text, &t, &err), HZ_ERROR);
    if (!strstr(err.message, want))
        fail_msg("got \"%s\", want \"%s\"", err.message, want);
}

static void test_parse_lens_file(void **state)
{
    (void)state;
    lens_table t;
    hz_error err = {0};
    const char *text = "# a comment line\n"
                       "  80  10 1.5 20   # front\n"
                       "\n"
                       "0 5 1 4\n"
                       "-120 50.5 1 2.0e1\n";
    assert_int_equal(lens_file_parse("lens.dat", text, &t, &err), HZ_OK);
    assert_int_equal(t.count, 3);
    assert_true(t.rows[0].radius == 80.0 && t.rows[0].thickness == 10.0);
    assert_true(t.rows[0].eta == 1.5 && t.rows[0].aperture == 20.0);
    assert_true(t.rows[1].radius == 0.0 && t.rows[1].aperture == 4.0);
    assert_true(t.rows[2].radius == -120.0 && t.rows[2].thickness == 50.5);
    assert_true(t.rows[2].aperture == 20.0);
}

static void test_bad_lens_files(void **state)
{
    (void)state;
    expect_parse_error("80 10 1.5 20\n-120 50 1\n",
                       "lens.dat:2:10: a lens element row has four values");
    expect_parse_error("80 10 1.5 20\n-120 50 1 20 7\n", "lens.dat:2:14: a lens element row "
                                                         "has four values");
    expect_parse_error("80 10 glass 20\n", "lens.dat:1:7: expected a number in the lens "
                                           "file, got \"glass\"");
    expect_parse_error("80 10 1.5 20mm\n", "lens.dat:1:11: expected a number");
    expect_parse_error("# only comments\n\n", "lens.dat:1:1: the lens file has no lens elements");
    expect_parse_error("", "lens.dat:1:1: the lens file has no lens elements");
    expect_parse_error("80 10 1.5 20\n0 5 1 -4\n",
                       "lens.dat:2:7: lens element aperture diameter must be > 0");
    expect_parse_error("80 -1 1.5 20\n", "lens.dat:1:4: lens element thickness must be >= 0");
    expect_parse_error("80 1 -1.5 20\n", "lens.dat:1:6: lens element index of refraction");
    expect_parse_error("80 1 nan 20\n", "lens.dat:1:6: lens element index of refraction is "
                                        "not finite");
}

static void test_read_lens_file(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/realistic-%ld.dat", HAZE_TMP, (long)getpid());
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("35 5 1.6 20\n-35 40 1 20\n", f);
    fclose(f);
    lens_table t;
    hz_error err = {0};
    assert_int_equal(lens_file_read(path, &t, &err), HZ_OK);
    assert_int_equal(t.count, 2);
    assert_true(t.rows[1].radius == -35.0);
    remove(path);
    assert_int_equal(lens_file_read(path, &t, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "cannot read the lens file"));
    /* A FIFO is refused at once, not waited on. */
    assert_int_equal(mkfifo(path, 0600), 0);
    assert_int_equal(lens_file_read(path, &t, &err), HZ_ERROR);
    remove(path);
    assert_non_null(strstr(err.message, "cannot read the lens file: is a FIFO"));
}

/* A biconvex thick lens R1 = 80 mm, R2 = -120 mm, 10 mm of n = 1.5. */
static const char biconvex[] = "80 10 1.5 20\n-120 60 1 20\n";
/* The same behind an aperture stop 5 mm in front of it (1 mm by default). */
static const char stopped_biconvex[] = "0 5 1 20\n80 10 1.5 20\n-120 60 1 20\n";

static realistic_lens lens_from(const char *text, double aperture_mm)
{
    lens_table t;
    hz_error err = {0};
    if (lens_file_parse("lens.dat", text, &t, &err) != HZ_OK)
        fail_msg("%s", err.message);
    realistic_lens l;
    bool clamped;
    realistic_elements(&t, aperture_mm, APERTURE_CIRCLE, 35.0, 64, 32, &l, &clamped);
    return l;
}

static void test_thick_lens_matches_lensmaker(void **state)
{
    (void)state;
    realistic_lens l = lens_from(biconvex, 100.0);
    double pz[2], fz[2];
    hz_error err = {0};
    assert_int_equal(realistic_thick_lens(&l, pz, fz, &err), HZ_OK);
    double n = 1.5, r1 = 0.080, r2 = -0.120, d = 0.010;
    double f_lensmaker = 1.0 / ((n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * d / (n * r1 * r2)));
    double f = fz[0] - pz[0], f_scene = pz[1] - fz[1];
    print_message("EFL %.12g m, lensmaker %.12g m (rel %.3g); scene side %.12g\n", f,
                  f_lensmaker, fabs(f / f_lensmaker - 1.0), f_scene);
    assert_true(fabs(f / f_lensmaker - 1.0) < 1e-6);
    assert_true(fabs(f_scene / f_lensmaker - 1.0) < 1e-6);
    /* The rear principal plane: h2 = -f (n - 1) d / (n R1) behind the rear vertex. */
    double rear_vertex = -0.060, h2 = -f_lensmaker * (n - 1.0) * d / (n * r1);
    assert_true(fabs(pz[0] - (rear_vertex + h2)) < 1e-6 * f_lensmaker);
}

/* Rays from the on-axis point focus_distance in front of the film, through
 * the lens within `height` of the axis: their largest distance from the axis
 * where they cross the film plane z = film_z (camera space). */
static double spot_radius(const realistic_lens *l, double focus_distance, double height,
                          double film_z)
{
    double worst = 0.0, front = realistic_front_z(l);
    for (int i = 0; i <= 20; ++i)
        for (int j = 0; j < 8; ++j) {
            double h = height * i / 20.0, phi = 2.0 * 3.14159265358979 * j / 8.0;
            vec3 o = v3(0.0, 0.0, focus_distance);
            lens_ray in = {o, v3_sub(v3(h * cos(phi), h * sin(phi), front), o)}, out;
            assert_true(realistic_trace_from_scene(l, in, &out));
            double t = (film_z - out.o.z) / out.d.z;
            worst = fmax(worst, hypot(out.o.x + t * out.d.x, out.o.y + t * out.d.y));
        }
    return worst;
}

static void test_focus_images_axis_point_on_film(void **state)
{
    (void)state;
    const double distances[] = {0.5, 2.0, 10.0};
    for (size_t k = 0; k < sizeof distances / sizeof distances[0]; ++k) {
        realistic_lens l = lens_from(biconvex, 100.0);
        hz_error err = {0};
        assert_int_equal(realistic_focus(&l, distances[k], &err), HZ_OK);
        double at = spot_radius(&l, distances[k], 0.0005, 0.0);
        double off = spot_radius(&l, distances[k], 0.0005, 0.0005);
        print_message("focus %g m: film at %.6g mm, spot radius %.3g um (0.5 mm off: %.3g um)\n",
                      distances[k], 1000.0 * realistic_rear_z(&l), 1e6 * at, 1e6 * off);
        assert_true(at < 0.1e-6);
        assert_true(off > 50.0 * at);
    }
}

/* The camera's rays through raster point (x, 16) of a 64x32 film: their
 * mean crossing of the plane z = focus (camera space) in *mean_x, the
 * largest |y| there in *blur; the number of rays. */
static int edge_rays(const camera *c, double x, double focus, double *mean_x, double *blur)
{
    double sum = 0.0;
    int n = 0;
    *blur = 0.0;
    for (int i = 0; i < 16; ++i)
        for (int j = 0; j < 16; ++j) {
            camera_sample s = {v2(x, 16.0), v2((i + 0.5) / 16, (j + 0.5) / 16), 0.5, 1.0};
            ray r;
            if (camera_generate_ray_weighted(c, s, &r) == 0.0)
                continue;
            vec3 p = v3_add(r.o, v3_scale(r.d, (focus - r.o.z) / r.d.z));
            *blur = fmax(*blur, fabs(p.y));
            sum += p.x;
            ++n;
        }
    *mean_x = n ? sum / n : 0.0;
    return n;
}

/* The thick lens's magnification: film height h images the object height
 * h s_o / s_i on the plane in focus (s_o, s_i from the principal planes);
 * the camera's rays through the raster point at h meet there, up to the
 * single lens's distortion (which grows as h^3). */
static void test_field_of_view_from_thick_lens(void **state)
{
    (void)state;
    realistic_lens l = lens_from(stopped_biconvex, 2.0);
    hz_error err = {0};
    double focus = 3.0;
    assert_int_equal(realistic_focus(&l, focus, &err), HZ_OK);
    realistic_bound_pupil(&l, 1 << 16);
    double pz[2], fz[2];
    assert_int_equal(realistic_thick_lens(&l, pz, fz, &err), HZ_OK);
    double s_i = -pz[0], s_o = focus + pz[1];
    camera_config cfg = camera_config_default(CAMERA_REALISTIC, 64, 32);
    cfg.realistic = &l;
    camera c;
    assert_int_equal(camera_init(&cfg, &c, &err), HZ_OK);
    const double raster_x[2] = {40.0, 64.0}, tolerance[2] = {5e-4, 5e-3};
    for (int k = 0; k < 2; ++k) {
        double h = l.film_half[0] * (raster_x[k] - 32.0) / 32.0, want = h * s_o / s_i;
        double got, blur;
        int n = edge_rays(&c, raster_x[k], focus, &got, &blur);
        print_message("raster x %g images x = %.6g m at %g m (blur %.3g m), thick lens says "
                      "%.6g (%d rays)\n",
                      raster_x[k], got, focus, blur, want, n);
        assert_true(n > 100);
        assert_true(fabs(got - want) < tolerance[k] * want);
    }
}

/* The camera weight's integral over the rear element's plane for raster
 * point p, by brute force over a fine grid of the box pbrt-v4 samples
 * (+-1.5 rear radii): what realistic_generate estimates with its pupil
 * bounds, when they hold the pupil. */
static double pupil_integral(const realistic_lens *l, vec2 p, int xres, int yres)
{
    double fx = -l->film_half[0] + 2.0 * l->film_half[0] * p.x / xres;
    double fy = -l->film_half[1] + 2.0 * l->film_half[1] * p.y / yres;
    vec3 p_film = v3(-fx, fy, 0.0);
    double rz = realistic_rear_z(l), half = 1.5 * l->e[l->count - 1].aperture_radius;
    enum { N = 600 };
    double cell = 2.0 * half / N, sum = 0.0;
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            vec3 q = v3(-half + (i + 0.5) * cell, -half + (j + 0.5) * cell, rz);
            lens_ray r = {p_film, v3_sub(q, p_film)};
            double w = realistic_trace_from_film(l, r, NULL), c = v3_normalize(r.d).z;
            sum += w * c * c * c * c / (rz * rz);
        }
    return sum * cell * cell;
}

/* realistic_generate's mean over a stratified grid of lens samples. */
static double generate_mean(const realistic_lens *l, vec2 p, int xres, int yres)
{
    enum { N = 400 };
    double sum = 0.0;
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            lens_ray r;
            sum += realistic_generate(l, p, v2((i + 0.5) / N, (j + 0.5) / N), xres, yres, &r);
        }
    return sum / (N * N);
}

/* pbrt-v4 bounds the exit pupil for film points on +x and rotates the bounds
 * to each film point's angle: right for a round stop, but a square stop's
 * pupil does not turn with the film point, so pbrt-v4 loses its corners
 * (9.4% of the light of its double Gauss under a white sky). haze's bounds
 * hold the pupil at every angle: the estimate equals the brute-force
 * integral off the axes and near the centre, for every shape. */
static void test_pupil_bounds_hold_shaped_stops(void **state)
{
    (void)state;
    const aperture_shape shapes[] = {APERTURE_CIRCLE, APERTURE_SQUARE, APERTURE_PENTAGON,
                                     APERTURE_STAR, APERTURE_GAUSSIAN};
    const vec2 points[] = {{32.4, 16.3}, {44.0, 5.0}, {8.0, 27.0}};
    for (size_t k = 0; k < sizeof shapes / sizeof shapes[0]; ++k) {
        lens_table t;
        hz_error err = {0};
        assert_int_equal(lens_file_parse("lens", stopped_biconvex, &t, &err), HZ_OK);
        realistic_lens l;
        bool clamped;
        realistic_elements(&t, 8.0, shapes[k], 35.0, 64, 32, &l, &clamped);
        assert_int_equal(realistic_focus(&l, 3.0, &err), HZ_OK);
        realistic_bound_pupil(&l, REALISTIC_PUPIL_SAMPLES);
        for (size_t i = 0; i < sizeof points / sizeof points[0]; ++i) {
            double want = pupil_integral(&l, points[i], 64, 32);
            double got = generate_mean(&l, points[i], 64, 32);
            print_message("shape %d at (%g, %g): estimate %.6g, integral %.6g (ratio %.4f)\n",
                          (int)shapes[k], points[i].x, points[i].y, got, want, got / want);
            assert_true(want > 0.0);
            assert_true(fabs(got / want - 1.0) < 0.01);
        }
    }
}

/* A stop 16 mm behind a wide biconvex lens, its last element: a ray from
 * the film to the point (x, y) of the stop's plane crosses the stop there. */
static const char rear_stop[] = "80 10 1.5 60\n-120 5 1 60\n0 40 1 20\n";

static double stop_weight(const realistic_lens *l, double x, double y)
{
    lens_ray r = {v3(0.0, 0.0, 0.0), v3(x, y, realistic_rear_z(l))};
    return realistic_trace_from_film(l, r, NULL);
}

/* An aperture image covers the stop's square, the file's top row at +y (as
 * pbrt-v4 flips it), read bilinearly between texel centres and black
 * outside, scaled to a mean of pi/4: a 2x2 image whose top-left texel alone
 * is lit transmits pi there, and pi/4 halfway to the centre. */
static void test_aperture_image(void **state)
{
    (void)state;
    lens_table t;
    hz_error err = {0};
    assert_int_equal(lens_file_parse("lens", rear_stop, &t, &err), HZ_OK);
    realistic_lens l;
    bool clamped;
    realistic_elements(&t, 20.0, APERTURE_CIRCLE, 35.0, 64, 32, &l, &clamped);
    float *v = malloc(4 * sizeof *v);
    assert_non_null(v);
    v[0] = 2.0f, v[1] = v[2] = v[3] = 0.0f; /* file order: top row first */
    assert_int_equal(realistic_set_aperture_image(&l, 2, 2, v, &err), HZ_OK);
    assert_int_equal(l.shape, APERTURE_IMAGE);
    double r = 0.010, pi = 3.14159265358979;
    assert_true(fabs(stop_weight(&l, -0.5 * r, 0.5 * r) - pi) < 1e-5);
    assert_true(fabs(stop_weight(&l, -0.9 * r, 0.9 * r) - pi * 0.6 * 0.6) < 1e-5);
    assert_true(fabs(stop_weight(&l, 0.0, 0.0) - pi / 4.0) < 1e-5);
    assert_true(stop_weight(&l, 0.5 * r, 0.5 * r) == 0.0);
    assert_true(stop_weight(&l, -0.5 * r, -0.5 * r) == 0.0);
    /* Beyond the stop's circle, inside its square: an image is not clipped
     * to the circle (as pbrt-v4). */
    assert_true(stop_weight(&l, -0.74 * r, 0.74 * r) > 0.0);
    realistic_lens_free(&l);
    assert_int_equal(l.shape, APERTURE_CIRCLE);
    assert_null(l.image.values);

    float *black = calloc(4, sizeof *black), *neg = malloc(4 * sizeof *neg);
    assert_non_null(black);
    assert_non_null(neg);
    assert_int_equal(realistic_set_aperture_image(&l, 2, 2, black, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "the aperture image is black"));
    neg[0] = 1.0f, neg[1] = -0.5f, neg[2] = neg[3] = 1.0f;
    assert_int_equal(realistic_set_aperture_image(&l, 2, 2, neg, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "negative or non-finite value at texel (1, 0)"));
    assert_int_equal(l.shape, APERTURE_CIRCLE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_lens_file),
        cmocka_unit_test(test_bad_lens_files),
        cmocka_unit_test(test_read_lens_file),
        cmocka_unit_test(test_thick_lens_matches_lensmaker),
        cmocka_unit_test(test_focus_images_axis_point_on_film),
        cmocka_unit_test(test_field_of_view_from_thick_lens),
        cmocka_unit_test(test_pupil_bounds_hold_shaped_stops),
        cmocka_unit_test(test_aperture_image),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
