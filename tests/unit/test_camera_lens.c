/* camera: the thin lens (focus, circle of confusion), polygonal apertures and
 * haze's physical-lens parameters. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "camera/camera.h"
#include "camera/lens.h"
#include "core/sampling.h"
#include "unit/assert_util.h"
#include "unit/camera_util.h"

/* Where a render-space ray meets camera-space plane z = depth, in camera space. */
static vec3 hit_camera_plane(const camera *c, const ray *r, double depth)
{
    transform camera_from_render = transform_inverse(c->render_from_camera);
    vec3 o = transform_point(&camera_from_render, r->o);
    vec3 d = transform_vector(&camera_from_render, r->d);
    return v3_add(o, v3_scale(d, (depth - o.z) / d.z));
}

static void check_lens_rays_meet_on_focal_plane(camera_config cfg)
{
    camera c = make_camera(cfg);
    transform camera_from_render = transform_inverse(c.render_from_camera);
    uint64_t rng = 7;
    const vec2 pixels[] = {{0.5, 0.5}, {37.25, 81.5}, {199.9, 0.1}, {100, 50}};
    for (size_t i = 0; i < sizeof pixels / sizeof pixels[0]; ++i) {
        camera_sample s = {pixels[i], v2(0.5, 0.5), 0.5, 1};
        vec3 p_camera = transform_point(&c.camera_from_raster, v3(pixels[i].x, pixels[i].y, 0));
        vec3 focus = cfg.kind == CAMERA_PERSPECTIVE
                         ? v3_scale(p_camera, cfg.focal_distance / p_camera.z)
                         : v3(p_camera.x, p_camera.y, cfg.focal_distance);
        double spread = 0;
        for (int k = 0; k < 200; ++k) {
            s.p_lens = v2(rng_next(&rng), rng_next(&rng));
            ray r;
            assert_true(camera_generate_ray(&c, s, &r));
            vec3 o_cam = transform_point(&camera_from_render, r.o);
            spread =
                fmax(spread, hypot(o_cam.x - (cfg.kind == CAMERA_PERSPECTIVE ? 0 : p_camera.x),
                                   o_cam.y - (cfg.kind == CAMERA_PERSPECTIVE ? 0 : p_camera.y)));
            assert_near(o_cam.z, 0, 1e-12);
            assert_v3_near(hit_camera_plane(&c, &r, cfg.focal_distance), focus,
                           1e-11 * fmax(1.0, v3_length(focus)));
        }
        /* ... from points spread over the whole aperture. */
        assert_true(spread > 0.9 * cfg.lens_radius);
        assert_true(spread <= cfg.lens_radius * (1 + 1e-12));
    }
}

static void test_lens_rays_meet_on_focal_plane(void **state)
{
    (void)state;
    transform cfw;
    assert_true(transform_look_at(v3(1, 2, -4), v3(0, 0.5, 1), v3(0, 1, 0.1), &cfw));
    for (int k = 0; k < 2; ++k)
        for (int blades = 0; blades <= 7; blades += 7) {
            camera_config cfg =
                camera_config_default(k ? CAMERA_ORTHOGRAPHIC : CAMERA_PERSPECTIVE, 200, 100);
            cfg.camera_from_world = cfw;
            cfg.fov = 45;
            cfg.lens_radius = 0.3;
            cfg.focal_distance = 7.5;
            cfg.blades = blades;
            cfg.blade_rotation = 10;
            check_lens_rays_meet_on_focal_plane(cfg);
        }
}

/* Distance from point p to the line of ray r. */
static double distance_to_ray(const ray *r, vec3 p)
{
    vec3 op = v3_sub(p, r->o);
    return v3_length(v3_sub(op, v3_scale(r->d, v3_dot(op, r->d))));
}

static void test_circle_of_confusion(void **state)
{
    (void)state;
    const int xres = 300, yres = 200; /* N_short = 200 */
    const double fov = 40, R = 0.1, zf = 5;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, xres, yres);
    cfg.fov = fov;
    cfg.lens_radius = R;
    cfg.focal_distance = zf;
    camera c = make_camera(cfg);
    const double depths[] = {1.5, 3, 4.9, 8, 50, 1e4};
    for (size_t i = 0; i < sizeof depths / sizeof depths[0]; ++i) {
        double z = depths[i];
        vec3 p = v3(0, 0, z);
        /* Lens samples on the boundary of the unit square land on the rim. */
        enum { RIM = 64 };
        vec2 raster[RIM];
        for (int k = 0; k < RIM; ++k) {
            double t = (k % (RIM / 4)) / (double)(RIM / 4);
            vec2 u = k < RIM / 4       ? v2(1, t)
                     : k < RIM / 2     ? v2(1 - t, 1)
                     : k < 3 * RIM / 4 ? v2(0, 1 - t)
                                       : v2(t, 0);
            vec2 l = lens_sample_aperture(R, 0, 0, u);
            assert_near(hypot(l.x, l.y), R, 1e-15);
            /* The ray from l through p meets the focal plane at q; the film
             * position whose lens rays aim at q is q's projection. */
            vec3 lp = v3(l.x, l.y, 0);
            vec3 q = v3_add(lp, v3_scale(v3_sub(p, lp), zf / z));
            vec3 pr = transform_point(&c.raster_from_camera, q);
            raster[k] = v2(pr.x, pr.y);
            ray r;
            camera_generate_ray(&c, (camera_sample){raster[k], u, 0.5, 1}, &r);
            assert_near(distance_to_ray(&r, p), 0, 1e-9 * z);
        }
        double diameter = 0;
        for (int a = 0; a < RIM; ++a)
            for (int b = a + 1; b < RIM; ++b)
                diameter =
                    fmax(diameter, hypot(raster[a].x - raster[b].x, raster[a].y - raster[b].y));
        double want = 2 * R * fabs(1 / zf - 1 / z) * (yres / 2.0) / tan(hz_radians(fov) / 2);
        assert_near(diameter / want, 1.0, 0.02);
        /* A disc around the pixel on the optical axis: every rim image sits on its edge. */
        for (int k = 0; k < RIM; ++k)
            assert_near(hypot(raster[k].x - xres / 2.0, raster[k].y - yres / 2.0), want / 2,
                        1e-9 * want + 1e-9);
    }
}

static void test_aperture_polygon_containment(void **state)
{
    (void)state;
    camera_config cfg = camera_config_default(CAMERA_PERSPECTIVE, 64, 64);
    cfg.lens_radius = 0.5;
    cfg.focal_distance = 2;
    cfg.blades = 6;
    cfg.blade_rotation = 15;
    camera c = make_camera(cfg);
    assert_near(c.blade_rotation, hz_radians(15), 1e-15);
    uint64_t rng = 11;
    double best_vertex = 1e9;
    for (int i = 0; i < 20000; ++i) {
        camera_sample s = {v2(32, 32), v2(rng_next(&rng), rng_next(&rng)), 0.5, 1};
        ray r;
        camera_generate_ray(&c, s, &r);
        vec2 lp = v2(r.o.x / 0.5, r.o.y / 0.5); /* identity camera: lens point = origin */
        assert_true(regular_polygon_contains(6, hz_radians(15), lp, 1e-12));
        best_vertex =
            fmin(best_vertex, hypot(lp.x - cos(hz_radians(15)), lp.y - sin(hz_radians(15))));
    }
    /* The polygon's corners are reached (circumradius = lens radius), and the
     * hexagon is really rotated: the unrotated corner (1, 0) lies outside it. */
    assert_true(best_vertex < 0.05);
    assert_false(regular_polygon_contains(6, hz_radians(15), v2(0.999, 0), 0));
}

static void test_aperture_polygon_is_uniform(void **state)
{
    (void)state;
    const int blades[] = {3, 5, 8};
    for (size_t b = 0; b < 3; ++b) {
        int n = blades[b];
        double rot = 0.3, area = sample_regular_polygon_area(n);
        /* Test squares fully inside the polygon (convex: corners inside). */
        enum { SQ = 12 };
        double side = 0.15, sx[SQ], sy[SQ];
        int count[SQ] = {0}, squares = 0, fan[8] = {0};
        for (int i = 0; i < 9 && squares < SQ; ++i)
            for (int j = 0; j < 9 && squares < SQ; ++j) {
                double x0 = -0.8 + 0.18 * i, y0 = -0.8 + 0.18 * j;
                if (regular_polygon_contains(n, rot, v2(x0, y0), 0) &&
                    regular_polygon_contains(n, rot, v2(x0 + side, y0), 0) &&
                    regular_polygon_contains(n, rot, v2(x0, y0 + side), 0) &&
                    regular_polygon_contains(n, rot, v2(x0 + side, y0 + side), 0)) {
                    sx[squares] = x0;
                    sy[squares++] = y0;
                }
            }
        assert_true(squares >= 6);
        uint64_t rng = 1234 + (uint64_t)n;
        const int N = 400000;
        for (int k = 0; k < N; ++k) {
            vec2 p = lens_sample_aperture(1.0, n, rot, v2(rng_next(&rng), rng_next(&rng)));
            assert_true(regular_polygon_contains(n, rot, p, 1e-12));
            for (int q = 0; q < squares; ++q)
                if (p.x >= sx[q] && p.x < sx[q] + side && p.y >= sy[q] && p.y < sy[q] + side)
                    ++count[q];
            double a = atan2(p.y, p.x) - rot;
            a -= 2 * HZ_PI * floor(a / (2 * HZ_PI));
            ++fan[(int)(a / (2 * HZ_PI / n)) % n];
        }
        for (int q = 0; q < squares; ++q) {
            double want = N * side * side / area; /* ~ 4000-8000, sigma ~ 1-1.5% */
            assert_near(count[q] / want, 1.0, 0.06);
        }
        for (int f = 0; f < n; ++f)
            assert_near(fan[f] / (double)N, 1.0 / n, 0.01);
    }
}

static void test_concentric_disk_matches_pbrt(void **state)
{
    (void)state;
    /* Values of pbrt-v4's SampleUniformDiskConcentric worked by hand. */
    vec2 p = sample_uniform_disk_concentric(v2(0.5, 0.5));
    assert_true(p.x == 0 && p.y == 0);
    p = sample_uniform_disk_concentric(v2(0.75, 0.5));
    assert_near(p.x, 0.5, 1e-15);
    assert_near(p.y, 0.0, 1e-15);
    p = sample_uniform_disk_concentric(v2(1, 1));
    assert_near(p.x, sqrt(0.5), 1e-15);
    assert_near(p.y, sqrt(0.5), 1e-15);
    p = sample_uniform_disk_concentric(v2(0.5, 0));
    assert_near(p.x, 0, 1e-15);
    assert_near(p.y, -1, 1e-15);
    p = sample_uniform_disk_concentric(v2(1, 0.75)); /* r = 1, theta = pi/8 */
    assert_near(p.x, cos(HZ_PI / 8), 1e-15);
    assert_near(p.y, sin(HZ_PI / 8), 1e-15);
    /* A round aperture is exactly radius * concentric. */
    vec2 l = lens_sample_aperture(0.25, 0, 1.0, v2(0.1, 0.7));
    vec2 d = sample_uniform_disk_concentric(v2(0.1, 0.7));
    assert_true(l.x == 0.25 * d.x && l.y == 0.25 * d.y);
}

static void test_physical_lens_formulas(void **state)
{
    (void)state;
    /* 50 mm on a 36 mm wide 3:2 sensor: the short side is 24 mm. */
    double want = 2 * atan(12.0 / 50.0) * 180 / HZ_PI; /* 26.99 degrees */
    assert_near(lens_fov_from_focal_length(50, 36, 1.5), want, 1e-12);
    assert_near(lens_fov_from_focal_length(50, 36, 1 / 1.5), want, 1e-12);
    assert_near(lens_fov_from_focal_length(18, 36, 1.0), 2 * atan(1.0) * 180 / HZ_PI, 1e-12);
    assert_near(lens_radius_from_fstop(50, 2), 0.0125, 1e-16);
    assert_near(lens_radius_from_fstop(85, 1.4), 0.085 / 2.8, 1e-16);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lens_rays_meet_on_focal_plane),
        cmocka_unit_test(test_circle_of_confusion),
        cmocka_unit_test(test_aperture_polygon_containment),
        cmocka_unit_test(test_aperture_polygon_is_uniform),
        cmocka_unit_test(test_concentric_disk_matches_pbrt),
        cmocka_unit_test(test_physical_lens_formulas),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
