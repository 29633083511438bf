/* The realistic camera (camera/realistic.h, camera/lens_file.h): the lens
 * file reader and its errors, the thick-lens approximation against the
 * lensmaker's formula, focusing against traced rays, and the field of view
 * against the thick lens's magnification. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
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
    assert_non_null(strstr(err.message, "cannot open the lens file"));
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_lens_file),
        cmocka_unit_test(test_bad_lens_files),
        cmocka_unit_test(test_read_lens_file),
        cmocka_unit_test(test_thick_lens_matches_lensmaker),
        cmocka_unit_test(test_focus_images_axis_point_on_film),
        cmocka_unit_test(test_field_of_view_from_thick_lens),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
