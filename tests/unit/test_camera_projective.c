/* camera: pbrt-v4's projective cameras built from a camera_config (no scene
 * parsing): raster/camera/screen mappings, field of view, differentials,
 * render space, extreme and illegal values. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "camera/camera.h"
#include "camera/footprint.h"
#include "unit/assert_util.h"
#include "unit/camera_util.h"

/* Bit-for-bit equality of the ray's fields (memcmp on the struct would read padding). */
static void assert_ray_identical(const ray *a, const ray *b)
{
    assert_memory_equal(&a->o, &b->o, sizeof a->o);
    assert_memory_equal(&a->d, &b->d, sizeof a->d);
    assert_memory_equal(&a->time, &b->time, sizeof a->time);
    assert_int_equal(a->medium, b->medium);
}

static camera_sample at(double x, double y)
{
    return (camera_sample){v2(x, y), v2(0.5, 0.5), 0.5, 1.0};
}

static double angle_deg(vec3 a, vec3 b)
{
    return acos(hz_clamp(v3_dot(a, b) / (v3_length(a) * v3_length(b)), -1, 1)) * 180.0 / HZ_PI;
}

static void test_raster_camera_round_trip(void **state)
{
    (void)state;
    for (int k = 0; k < 2; ++k) {
        camera_config cfg =
            camera_config_default(k ? CAMERA_ORTHOGRAPHIC : CAMERA_PERSPECTIVE, 320, 240);
        cfg.fov = 40;
        camera c = make_camera(cfg);
        for (double y = 0; y <= 240; y += 37.5)
            for (double x = 0; x <= 320; x += 41.25) {
                vec3 pc = transform_point(&c.camera_from_raster, v3(x, y, 0));
                assert_v3_near(transform_point(&c.raster_from_camera, pc), v3(x, y, 0), 1e-9);
                /* Every point along the (pinhole) ray projects back onto the same pixel. */
                ray r;
                assert_true(camera_generate_ray(&c, at(x, y), &r));
                vec3 far = transform_point(&c.raster_from_camera, ray_at(&r, 57.0));
                assert_near(far.x, x, 1e-9);
                assert_near(far.y, y, 1e-9);
            }
    }
}

static void test_image_corners_map_to_screen_window_corners(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, 200, 100);
    assert_near(cfg.screen_window[0], -2, 0);
    assert_near(cfg.screen_window[1], 2, 0);
    assert_near(cfg.screen_window[2], -1, 0);
    assert_near(cfg.screen_window[3], 1, 0);
    double custom[4] = {-0.5, 1.5, -0.25, 0.75};
    memcpy(cfg.screen_window, custom, sizeof custom);
    for (int k = 0; k < 2; ++k) {
        cfg.kind = k ? CAMERA_ORTHOGRAPHIC : CAMERA_PERSPECTIVE;
        camera c = make_camera(cfg);
        transform screen_from_raster =
            transform_compose(c.screen_from_camera, c.camera_from_raster);
        /* Raster origin is the top-left corner: screen (xmin, ymax). */
        vec3 tl = transform_point(&screen_from_raster, v3(0, 0, 0));
        vec3 br = transform_point(&screen_from_raster, v3(200, 100, 0));
        vec3 tr = transform_point(&screen_from_raster, v3(200, 0, 0));
        vec3 bl = transform_point(&screen_from_raster, v3(0, 100, 0));
        assert_v3_near(tl, v3(-0.5, 0.75, 0), 1e-12);
        assert_v3_near(br, v3(1.5, -0.25, 0), 1e-12);
        assert_v3_near(tr, v3(1.5, 0.75, 0), 1e-12);
        assert_v3_near(bl, v3(-0.5, -0.25, 0), 1e-12);
    }
}

static void test_fov_spans_shorter_axis_landscape(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, 200, 100);
    cfg.fov = 60;
    camera c = make_camera(cfg);
    ray top, bottom, right, centre;
    camera_generate_ray(&c, at(100, 0), &top);
    camera_generate_ray(&c, at(100, 100), &bottom);
    camera_generate_ray(&c, at(200, 50), &right);
    camera_generate_ray(&c, at(100, 50), &centre);
    assert_v3_near(centre.d, v3(0, 0, 1), 1e-15);
    assert_near(angle_deg(top.d, bottom.d), 60.0, 1e-9); /* vertical = shorter axis */
    assert_true(top.d.y > 0);                            /* raster y = 0 is the top */
    assert_near(angle_deg(right.d, centre.d), atan(2 * tan(HZ_PI / 6)) * 180 / HZ_PI, 1e-9);
    assert_true(right.d.x > 0);
}

static void test_fov_spans_shorter_axis_portrait(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, 100, 200);
    cfg.fov = 60;
    camera c = make_camera(cfg);
    ray left, right, top, centre;
    camera_generate_ray(&c, at(0, 100), &left);
    camera_generate_ray(&c, at(100, 100), &right);
    camera_generate_ray(&c, at(50, 0), &top);
    camera_generate_ray(&c, at(50, 100), &centre);
    assert_near(angle_deg(left.d, right.d), 60.0, 1e-9); /* horizontal = shorter axis */
    assert_near(angle_deg(top.d, centre.d), atan(2 * tan(HZ_PI / 6)) * 180 / HZ_PI, 1e-9);
}

static void test_orthographic_rays(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_ORTHOGRAPHIC, 200, 100);
    camera c = make_camera(cfg);
    ray_differential rd;
    assert_true(camera_generate_ray_differential(&c, at(10.25, 70.5), &rd));
    assert_true(rd.has_differentials);
    /* Screen [-2,2]x[-1,1] over 200x100 pixels: 0.02 units a pixel, y down. */
    assert_v3_near(rd.r.o, v3(-2 + 10.25 * 0.02, 1 - 70.5 * 0.02, 0), 1e-13);
    assert_v3_near(rd.r.d, v3(0, 0, 1), 0);
    assert_v3_near(v3_sub(rd.rx_o, rd.r.o), v3(0.02, 0, 0), 1e-13);
    assert_v3_near(v3_sub(rd.ry_o, rd.r.o), v3(0, -0.02, 0), 1e-13);
    assert_v3_near(rd.rx_d, rd.r.d, 0);
    assert_v3_near(rd.ry_d, rd.r.d, 0);
    /* The differentials are the neighbouring pixels' rays. */
    ray nx, ny;
    camera_generate_ray(&c, at(11.25, 70.5), &nx);
    camera_generate_ray(&c, at(10.25, 71.5), &ny);
    assert_v3_near(rd.rx_o, nx.o, 1e-13);
    assert_v3_near(rd.ry_o, ny.o, 1e-13);
}

/* Differentials must equal the rays one pixel over, with the same lens point. */
static void check_differentials_are_neighbours(camera_config cfg)
{
    camera c = make_camera(cfg);
    const vec2 films[] = {{0.5, 0.5}, {123.25, 17.75}, {319.9, 239.1}, {160, 120}};
    const vec2 lenses[] = {{0.5, 0.5}, {0.1, 0.9}, {0.97, 0.3}};
    for (size_t i = 0; i < sizeof films / sizeof films[0]; ++i)
        for (size_t j = 0; j < sizeof lenses / sizeof lenses[0]; ++j) {
            camera_sample s = {films[i], lenses[j], 0.25, 1.0};
            ray_differential rd;
            ray main, nx, ny;
            assert_true(camera_generate_ray_differential(&c, s, &rd));
            assert_true(camera_generate_ray(&c, s, &main));
            assert_ray_identical(&rd.r, &main);
            camera_sample sx = s, sy = s;
            sx.p_film.x += 1;
            sy.p_film.y += 1;
            camera_generate_ray(&c, sx, &nx);
            camera_generate_ray(&c, sy, &ny);
            assert_v3_near(rd.rx_o, nx.o, 1e-12);
            assert_v3_near(rd.rx_d, nx.d, 1e-12);
            assert_v3_near(rd.ry_o, ny.o, 1e-12);
            assert_v3_near(rd.ry_d, ny.d, 1e-12);
        }
}

static void test_differentials_equal_neighbouring_rays(void **state)
{
    (void)state;
    transform cfw;
    assert_true(transform_look_at(v3(3, 4, 5), v3(0, 1, 0), v3(0.2, 1, 0), &cfw));
    for (int k = 0; k < 2; ++k)
        for (int lens = 0; lens < 2; ++lens) {
            camera_config cfg =
                camera_config_default(k ? CAMERA_ORTHOGRAPHIC : CAMERA_PERSPECTIVE, 320, 240);
            cfg.camera_from_world = cfw;
            cfg.fov = 35;
            if (lens) {
                cfg.lens_radius = 0.2;
                cfg.focal_distance = 6;
            }
            check_differentials_are_neighbours(cfg);
            cfg.blades = 5;
            check_differentials_are_neighbours(cfg);
        }
}

static void test_perspective_pinhole_differential_direction(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, 100, 100);
    cfg.fov = 90;
    camera c = make_camera(cfg);
    /* At fov 90 a pixel is 2/100 screen units = 0.02 * near in camera space. */
    assert_v3_near(c.dx_camera, v3(0.02 * 1e-2, 0, 0), 1e-17);
    assert_v3_near(c.dy_camera, v3(0, -0.02 * 1e-2, 0), 1e-17);
    ray_differential rd;
    camera_generate_ray_differential(&c, at(50, 50), &rd);
    assert_v3_near(rd.rx_o, rd.r.o, 0);
    assert_v3_near(rd.rx_d, v3_normalize(v3(0.02, 0, 1)), 1e-15);
    assert_v3_near(rd.ry_d, v3_normalize(v3(0, -0.02, 1)), 1e-15);
}

static void test_lens_radius_zero_is_the_pinhole_bit_for_bit(void **state)
{
    (void)state;
    transform cfw;
    assert_true(transform_look_at(v3(-2, 7, 1.5), v3(4, 0.5, 3), v3(0, 1, 0), &cfw));
    for (int k = 0; k < 2; ++k) {
        camera_config cfg =
            camera_config_default(k ? CAMERA_ORTHOGRAPHIC : CAMERA_PERSPECTIVE, 64, 48);
        cfg.camera_from_world = cfw;
        cfg.fov = 50;
        cfg.lens_radius = 0.0;
        cfg.focal_distance = 3.0;
        camera c = make_camera(cfg);
        cfg.blades = 6;
        camera cb = make_camera(cfg);
        for (int i = 0; i < 50; ++i) {
            vec2 pf = v2(64.0 * i / 50.0 + 0.3, 48.0 * ((i * 7) % 50) / 50.0);
            vec2 pl = v2((i * 13 % 50) / 50.0, (i * 29 % 50) / 50.0);
            ray r, rb, rc;
            assert_true(camera_generate_ray(&c, (camera_sample){pf, pl, 0.3, 1}, &r));
            camera_generate_ray(&cb, (camera_sample){pf, pl, 0.3, 1}, &rb);
            camera_generate_ray(&c, (camera_sample){pf, v2(0.5, 0.5), 0.3, 1}, &rc);
            /* The pinhole ray computed independently of the camera module, in
             * pbrt-v4's order; the perspective camera folds its transforms
             * into one matrix (camera.pinhole): the same to rounding. */
            vec3 pc = transform_point(&c.camera_from_raster, v3(pf.x, pf.y, 0));
            vec3 o = k ? pc : v3(0, 0, 0);
            vec3 d = k ? v3(0, 0, 1) : v3_normalize(pc);
            ray want = {transform_point(&c.render_from_camera, o),
                        v3_normalize(transform_vector(&c.render_from_camera, d)),
                        hz_lerp(0.3, 0.0, 1.0), -1};
            if (k) {
                assert_ray_identical(&r, &want);
            } else {
                assert_true(c.pinhole);
                assert_v3_near(r.o, want.o, 1e-15);
                assert_v3_near(r.d, want.d, 4e-16);
                assert_true(r.time == want.time && r.medium == want.medium);
            }
            assert_ray_identical(&r, &rb);
            assert_ray_identical(&r, &rc);
        }
    }
}

static void test_render_space_far_from_origin(void **state)
{
    (void)state;
    /* Offsets are integers so that eye + offset is exact at 1e7. */
    vec3 eye_far = v3(1e7, -3e7, 2.5e7);
    vec3 dir = v3(1, 2, -3), up = v3(0, 1, 0);
    for (int k = 0; k < 2; ++k)
        for (int lens = 0; lens < 2; ++lens) {
            camera_config cfg =
                camera_config_default(k ? CAMERA_ORTHOGRAPHIC : CAMERA_PERSPECTIVE, 160, 90);
            cfg.fov = 45;
            cfg.lens_radius = lens ? 0.05 : 0.0;
            cfg.focal_distance = 4;
            assert_true(transform_look_at(v3(0, 0, 0), dir, up, &cfg.camera_from_world));
            camera near = make_camera(cfg);
            assert_true(
                transform_look_at(eye_far, v3_add(eye_far, dir), up, &cfg.camera_from_world));
            camera far = make_camera(cfg);
            assert_v3_near(transform_point(&far.world_from_render, v3(0, 0, 0)), eye_far, 0);
            assert_v3_near(transform_point(&far.render_from_camera, v3(0, 0, 0)), v3(0, 0, 0), 0);
            for (int i = 0; i < 20; ++i) {
                camera_sample s = {v2(8.0 * i + 0.5, 4.5 * i), v2(0.05 * i, 1 - 0.05 * i), 0.5, 1};
                ray_differential a, b;
                camera_generate_ray_differential(&near, s, &a);
                camera_generate_ray_differential(&far, s, &b);
                assert_v3_near(a.r.o, b.r.o, 1e-12);
                assert_v3_near(a.r.d, b.r.d, 1e-12);
                assert_v3_near(a.rx_o, b.rx_o, 1e-12);
                assert_v3_near(a.rx_d, b.rx_d, 1e-12);
                assert_v3_near(a.ry_d, b.ry_d, 1e-12);
                /* And back in world space the far camera's ray starts at its eye. */
                if (!k && !lens)
                    assert_v3_near(transform_point(&far.world_from_render, b.r.o), eye_far, 0);
            }
        }
}

static void test_time_and_imaging_ratio(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, 10, 10);
    cfg.shutter_open = 0.25;
    cfg.shutter_close = 0.75;
    camera c = make_camera(cfg);
    assert_int_equal(c.medium, -1);
    ray r;
    camera_sample s = at(5, 5);
    s.time = 0.0;
    camera_generate_ray(&c, s, &r);
    assert_near(r.time, 0.25, 0);
    s.time = 0.5;
    camera_generate_ray(&c, s, &r);
    assert_near(r.time, 0.5, 1e-15);
    film_params fp = {0};
    fp.iso = 200;
    assert_near(camera_imaging_ratio(&c, &fp), 1.0, 1e-15);
    fp.iso = 100;
    assert_near(camera_imaging_ratio(&c, &fp), 0.5, 1e-15);
}

static void check_ray_sane(const ray *r)
{
    assert_true(v3_is_finite(r->o));
    assert_true(v3_is_finite(r->d));
    assert_near(v3_length(r->d), 1.0, 1e-12);
}

static void test_extreme_legal_values_give_finite_normalised_rays(void **state)
{
    (void)state;
    const double fovs[] = {1e-3, 179.9, 90};
    const double fds[] = {1e-4, 1e8};
    const double lrs[] = {0, 1e-9, 1e3};
    const int res[][2] = {{1, 1}, {4096, 1}, {1, 4096}};
    transform cfw;
    assert_true(transform_look_at(v3(1e6, 2, -3), v3(1e6 + 1, 2, -3), v3(0, 1, 0), &cfw));
    for (int k = 0; k < 2; ++k)
        for (size_t a = 0; a < 3; ++a)
            for (size_t b = 0; b < 2; ++b)
                for (size_t l = 0; l < 3; ++l)
                    for (size_t q = 0; q < 3; ++q) {
                        camera_config cfg = camera_config_default(
                            k ? CAMERA_ORTHOGRAPHIC : CAMERA_PERSPECTIVE, res[q][0], res[q][1]);
                        cfg.camera_from_world = cfw;
                        cfg.fov = fovs[a];
                        cfg.focal_distance = fds[b];
                        cfg.lens_radius = lrs[l];
                        cfg.blades = (int)(l * 3); /* 0, 3, 6 */
                        camera c = make_camera(cfg);
                        double xs[] = {0, 0.5 * res[q][0], (double)res[q][0]};
                        double ys[] = {0, 0.5 * res[q][1], (double)res[q][1]};
                        for (int i = 0; i < 3; ++i)
                            for (int j = 0; j < 3; ++j)
                                for (int u = 0; u < 3; ++u) {
                                    camera_sample s = {v2(xs[i], ys[j]),
                                                       v2(0.49 * u, 0.999 - 0.3 * u), 0.5, 1};
                                    ray_differential rd;
                                    assert_true(camera_generate_ray_differential(&c, s, &rd));
                                    check_ray_sane(&rd.r);
                                    ray rx = {rd.rx_o, rd.rx_d, 0, -1},
                                        ry = {rd.ry_o, rd.ry_d, 0, -1};
                                    check_ray_sane(&rx);
                                    check_ray_sane(&ry);
                                }
                    }
}

static void expect_invalid(camera_config cfg, const char *param, const char *text)
{
    hz_error err = {0};
    camera c;
    const char *bad = camera_config_check(&cfg, &err);
    if (!bad)
        fail_msg("expected \"%s\" to be rejected", param);
    assert_string_equal(bad, param);
    if (!strstr(err.message, text))
        fail_msg("message \"%s\" lacks \"%s\"", err.message, text);
    assert_int_equal(camera_init(&cfg, &c, &err), HZ_ERROR);
}

static void test_illegal_values_are_rejected(void **state)
{
    (void)state;
    camera_config ok = camera_config_default(CAMERA_PERSPECTIVE, 64, 32);
    hz_error err;
    assert_null(camera_config_check(&ok, &err));
    camera_config c;
    const double bad_fov[] = {0, -5, 180, 200, NAN, INFINITY};
    for (size_t i = 0; i < sizeof bad_fov / sizeof bad_fov[0]; ++i) {
        c = ok;
        c.fov = bad_fov[i];
        expect_invalid(c, "fov", "\"fov\" must be in (0, 180) degrees");
    }
    c = ok;
    c.kind = CAMERA_ORTHOGRAPHIC;
    c.fov = 500; /* fov means nothing to an orthographic camera */
    assert_null(camera_config_check(&c, &err));
    c = ok;
    c.lens_radius = -0.1;
    expect_invalid(c, "lensradius", "\"lensradius\" must be in [0, 1e+16], got -0.1");
    c.lens_radius = NAN;
    expect_invalid(c, "lensradius", "\"lensradius\" must be in [0, 1e+16], got nan");
    /* Beyond what a ray origin can hold (Embree's float range): refused. */
    c.lens_radius = 1e19;
    expect_invalid(c, "lensradius", "\"lensradius\" must be in [0, 1e+16], got 1e+19");
    const double bad_fd[] = {0, -1, INFINITY, NAN};
    for (size_t i = 0; i < sizeof bad_fd / sizeof bad_fd[0]; ++i) {
        c = ok;
        c.focal_distance = bad_fd[i];
        expect_invalid(c, "focaldistance", "\"focaldistance\" must be finite and > 0");
    }
    c = ok;
    c.screen_window[1] = c.screen_window[0];
    expect_invalid(c, "screenwindow", "has an empty extent");
    c = ok;
    c.screen_window[2] = 1;
    c.screen_window[3] = -1;
    expect_invalid(c, "screenwindow", "has an empty extent");
    c = ok;
    c.screen_window[0] = -INFINITY;
    expect_invalid(c, "screenwindow", "must be finite");
    c = ok;
    c.shutter_open = 2;
    c.shutter_close = 1;
    expect_invalid(c, "shutteropen", "\"shutteropen\" 2 is after \"shutterclose\" 1");
    c = ok;
    c.shutter_close = NAN;
    expect_invalid(c, "shutterclose", "must be finite");
    const int bad_blades[] = {1, 2, -3};
    for (size_t i = 0; i < 3; ++i) {
        c = ok;
        c.blades = bad_blades[i];
        expect_invalid(c, "blades", "\"blades\" must be 0 (round aperture) or at least 3");
    }
    c = ok;
    c.xres = 0;
    expect_invalid(c, "", "film resolution 0x32");
    c = ok;
    c.camera_from_world.m.m[0][0] = NAN;
    expect_invalid(c, "", "camera transform");
}

/* Where the film's pixel differentials are smallest (the far corner of the
 * film's diagonal, whose neighbours lie outside it), pbrt-v4's approximate footprint of a point on the plane facing
 * that corner's ray is the exact one: the neighbouring ray meets the plane
 * as far from the point. Elsewhere it is smaller; an orthographic
 * camera's, on its axis, is the pixel step at every distance. */
static double plane_offset(vec3 o, vec3 d, vec3 p, vec3 n)
{
    double t = v3_dot(n, v3_sub(p, o)) / v3_dot(n, d);
    return v3_length(v3_sub(v3_add(o, v3_scale(d, t)), p));
}

static void test_approximate_footprint(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, 64, 48);
    camera c = make_camera(cfg);
    camera_find_min_differentials(&c);
    ray_differential rd;
    assert_true(camera_generate_ray_differential(&c, at(64.0, 48.0), &rd));
    vec3 p = v3_add(rd.r.o, v3_scale(rd.r.d, 5.0)), n = v3_neg(rd.r.d);
    vec3 dpdx, dpdy;
    camera_approximate_dpdxy(&c, p, n, 0.0, 1.0, &dpdx, &dpdy);
    double ex = plane_offset(rd.rx_o, rd.rx_d, p, n), ey = plane_offset(rd.ry_o, rd.ry_d, p, n);
    print_message("corner: approximate %.9f %.9f, exact %.9f %.9f\n", v3_length(dpdx),
                  v3_length(dpdy), ex, ey);
    assert_near(v3_length(dpdx), ex, 1e-9 * ex);
    assert_near(v3_length(dpdy), ey, 1e-9 * ey);
    /* In the tangent plane, and scaled as the camera rays' differentials. */
    assert_near(v3_dot(dpdx, n), 0.0, 1e-12);
    vec3 sx, sy;
    camera_approximate_dpdxy(&c, p, n, 0.0, 0.25, &sx, &sy);
    assert_near(v3_length(sx), 0.25 * ex, 1e-9 * ex);
    /* At the film's centre, the same distance facing the camera gives the
     * same footprint, smaller than the centre pixel's own. */
    assert_true(camera_generate_ray_differential(&c, at(32.0, 24.0), &rd));
    p = v3_add(rd.r.o, v3_scale(rd.r.d, 5.0));
    n = v3_neg(rd.r.d);
    camera_approximate_dpdxy(&c, p, n, 0.0, 1.0, &dpdx, &dpdy);
    double cx = plane_offset(rd.rx_o, rd.rx_d, p, n);
    print_message("centre: approximate %.9f, exact %.9f\n", v3_length(dpdx), cx);
    assert_near(v3_length(dpdx), ex, 1e-9 * ex);
    assert_true(v3_length(dpdx) < cx);

    camera_config oc = camera_config_default(CAMERA_ORTHOGRAPHIC, 200, 100);
    camera o = make_camera(oc);
    camera_find_min_differentials(&o);
    for (double z = 1.0; z < 1000.0; z *= 10.0) {
        camera_approximate_dpdxy(&o, v3(0.0, 0.0, z), v3(0.0, 0.0, -1.0), 0.0, 1.0, &dpdx, &dpdy);
        assert_near(v3_length(dpdx), 0.02, 1e-12);
        assert_near(v3_length(dpdy), 0.02, 1e-12);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_raster_camera_round_trip),
        cmocka_unit_test(test_image_corners_map_to_screen_window_corners),
        cmocka_unit_test(test_fov_spans_shorter_axis_landscape),
        cmocka_unit_test(test_fov_spans_shorter_axis_portrait),
        cmocka_unit_test(test_orthographic_rays),
        cmocka_unit_test(test_approximate_footprint),
        cmocka_unit_test(test_differentials_equal_neighbouring_rays),
        cmocka_unit_test(test_perspective_pinhole_differential_direction),
        cmocka_unit_test(test_lens_radius_zero_is_the_pinhole_bit_for_bit),
        cmocka_unit_test(test_render_space_far_from_origin),
        cmocka_unit_test(test_time_and_imaging_ratio),
        cmocka_unit_test(test_extreme_legal_values_give_finite_normalised_rays),
        cmocka_unit_test(test_illegal_values_are_rejected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
