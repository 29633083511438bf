/* Spherical emitters sampled by solid angle (pbrt-v4's cone sampling) when
 * their transform is a uniform scale, by area otherwise and from inside:
 * convergence against the analytic irradiance E = π L (R/D)² cosθ of a sphere
 * entirely above the horizon, tiny far spheres, the geometry of the samples,
 * one-sided emission and the uniform-scale detection. */
#include "render_test_util.h"

#include <float.h>

#include "lights/lights.h"

#define RES 32

static const char *camera_down =
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 60\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n";

static const char *plane = "Material \"diffuse\" \"rgb reflectance\" [0.6 0.6 0.6]\n"
                           "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  "
                           "-20 20 0]\n  \"integer indices\" [0 1 2 0 2 3]\n";

/* Irradiance on the z = 0 plane (normal +z) at `p` from a sphere of radius R
 * and radiance L centred at `c`, entirely above the horizon. */
static double sphere_irradiance(vec3 p, vec3 c, double R, double L)
{
    vec3 d = v3_sub(c, p);
    double D2 = v3_length_sq(d);
    return HZ_PI * L * (R * R / D2) * (d.z / sqrt(D2));
}

typedef struct {
    double rms, max; /* relative errors over the plane pixels */
    int pixels;
} error_stats;

/* Renders a grid of plane pixels at `spp` and compares ρ/π E with the sphere
 * formula (the sphere pixels themselves are skipped). */
static error_stats plane_errors(const char *sphere_block, vec3 c, double R, double L, int spp)
{
    char text[2048];
    snprintf(text, sizeof text,
             "%sSampler \"zsobol\" \"integer pixelsamples\" %d\nWorldBegin\n%s%s", camera_down,
             spp, sphere_block, plane);
    render_scene *rs = build_scene_or_fail(text, NULL);
    error_stats st = {0.0, 0.0, 0};
    for (int y = 1; y < RES; y += 3)
        for (int x = 1; x < RES; x += 3) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, spp);
            assert_true(e.hit);
            if (fabs(e.p_world.z) > 1e-6)
                continue; /* the emitter */
            assert_true(isfinite(e.L.r));
            double want = 0.6 * HZ_INV_PI * sphere_irradiance(e.p_world, c, R, L);
            double rel = (e.L.r - want) / want;
            st.rms += rel * rel;
            st.max = fmax(st.max, fabs(rel));
            st.pixels++;
        }
    st.rms = sqrt(st.rms / st.pixels);
    render_scene_destroy(rs);
    return st;
}

/* An emitter of radius 0.5 (0.25, scaled and rotated) 1.5 above the plane:
 * at 64 spp every pixel is within 1% with cone sampling. The same sphere
 * with its z scale off by 1e-3 (an ellipsoid, so sampled by area; its
 * irradiance differs from the sphere's by less than 1e-3) is far noisier. */
static void test_cone_sampling_converges(void **state)
{
    (void)state;
    const char *sphere = "AttributeBegin\nTranslate 0 0 1.5\nRotate 37 1 1 0\nScale 2 2 2\n"
                         "AreaLightSource \"diffuse\" \"rgb L\" [1.5 1.5 1.5]\n"
                         "Shape \"sphere\" \"float radius\" 0.25\nAttributeEnd\n";
    const char *ellipsoid = "AttributeBegin\nTranslate 0 0 1.5\nRotate 37 1 1 0\nScale 2 2 2.002\n"
                            "AreaLightSource \"diffuse\" \"rgb L\" [1.5 1.5 1.5]\n"
                            "Shape \"sphere\" \"float radius\" 0.25\nAttributeEnd\n";
    vec3 c = v3(0, 0, 1.5);
    error_stats cone = plane_errors(sphere, c, 0.5, 1.5, 64);
    error_stats area = plane_errors(ellipsoid, c, 0.5, 1.5, 64);
    print_message("64 spp, %d pixels: cone rms %.3e max %.3e; area rms %.3e max %.3e\n",
                  cone.pixels, cone.rms, cone.max, area.rms, area.max);
    assert_true(cone.pixels > 50 && area.pixels == cone.pixels);
    assert_true(cone.max < 0.01);
    assert_true(cone.rms * 10.0 < area.rms);
}

/* Tiny far spheres (sin²θmax = 1e-12 and 4e-12, where the general pbrt-v4
 * formulas cancel to nothing in float): the analytic E within 1%, no NaN. */
static void test_tiny_far_sphere(void **state)
{
    (void)state;
    const struct {
        double R, D;
    } cases[] = {{1e-3, 1e3}, {0.02, 1e4}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        double R = cases[i].R, D = cases[i].D;
        double L = 1.0 / ((R / D) * (R / D)); /* E ~ π cosθ */
        vec3 c = v3(0.6 * D, 0.0, 0.8 * D);
        char sphere[512];
        snprintf(sphere, sizeof sphere,
                 "AttributeBegin\nTranslate %.17g 0 %.17g\n"
                 "AreaLightSource \"diffuse\" \"rgb L\" [%.17g %.17g %.17g]\n"
                 "Shape \"sphere\" \"float radius\" %.17g\nAttributeEnd\n",
                 c.x, c.z, L, L, L, R);
        error_stats e = plane_errors(sphere, c, R, L, 16);
        print_message("R %g at D %g, 16 spp: rms %.3e max %.3e\n", R, D, e.rms, e.max);
        assert_int_equal(e.pixels, 121);
        assert_true(e.max < 0.01);
    }
}

/* ---- the light sampler itself ---- */

typedef struct {
    scene_desc sd;
    geom_shape shape;
    light l;
} sphere_light;

static void make_sphere_light(sphere_light *s, transform space_from_object, double radius,
                              bool flip, const char *params)
{
    char text[512];
    snprintf(text, sizeof text,
             "WorldBegin\nAreaLightSource \"diffuse\" %s\nShape \"sphere\" \"float radius\" 1\n",
             params);
    hz_error err = {0};
    if (scene_parse_string(text, "test.pbrt", &s->sd, &err) != HZ_OK) {
        print_error("parse: %s\n", err.message);
        fail();
    }
    assert_true(s->sd.shape_count == 1 && s->sd.shapes[0].has_area_light);
    memset(&s->shape, 0, sizeof s->shape);
    s->shape.kind = GEOMETRY_SPHERE;
    s->shape.radius = radius;
    s->shape.space_from_object = space_from_object;
    s->shape.flip_normal = flip;
    s->shape.area_light = -1;
    if (light_area_from_entity(&s->sd.shapes[0].area_light, &s->shape, &s->l, NULL, &err) !=
        HZ_OK) {
        print_error("light: %s\n", err.message);
        fail();
    }
}

static void free_sphere_light(sphere_light *s)
{
    light_free(&s->l);
    scene_desc_free(&s->sd);
}

/* Every sample lies on the sphere, inside the cone, on the side facing the
 * point, at the angle its u asks for, with pdf 1 / (2π (1 - cosθmax)); for
 * moderate and tiny cones, u on a grid that includes the edges. */
static void test_cone_samples(void **state)
{
    (void)state;
    const struct {
        double R, D;
    } cases[] = {{1.0, 1.5}, {1.0, 1.0 + 1e-7}, {0.3, 40.0}, {1e-3, 1e3}, {1e-9, 1e6}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        double R = cases[k].R, D = cases[k].D;
        vec3 c = v3(3.0, -2.0, 1.0);
        /* Radius 2R scaled by 0.5 (and rotated): the render-space radius is R. */
        transform m = transform_compose(
            transform_compose(transform_translate(c), transform_rotate(70, v3(1, 2, 3))),
            transform_scale(v3(0.5, 0.5, 0.5)));
        sphere_light s;
        make_sphere_light(&s, m, 2.0 * R, false, "\"rgb L\" [2 2 2]");
        assert_true(s.l.area.sphere_cone);
        expect_close(s.l.area.sphere_radius, R, 1e-14, 0, "render radius", 0, 0);
        vec3 axis = v3_normalize(v3(1, 1, -2));
        vec3 p = v3_sub(c, v3_scale(axis, D)); /* the point, D from the centre */
        double s2max = (R / D) * (R / D);
        double omc_max = s2max / (1.0 + sqrt(1.0 - s2max));
        double us[] = {0.0, 1e-9, 0.1, 0.25, 0.5, 0.75, 0.999, 0x1.fffffffffffffp-1};
        int n_us = (int)(sizeof us / sizeof us[0]);
        for (int i = 0; i < n_us; ++i)
            for (int j = 0; j < n_us; ++j) {
                light_sample ls;
                if (!light_sample_li(&s.l, p, axis, 0.0, v2(us[i], us[j]), &ls)) {
                    assert_true(us[i] > 0.99); /* only the rim may face away by rounding */
                    continue;
                }
                assert_true(isfinite(ls.pdf) && isfinite(ls.dist) && v3_is_finite(ls.wi));
                expect_close(ls.pdf, 1.0 / (2.0 * HZ_PI * omc_max), 1e-12, 0, "cone pdf", i, j);
                expect_close(ls.L.r, 2.0, 0, 0, "radiance", i, j);
                /* Coordinates near c carry ~1e-16 absolute rounding. */
                vec3 pc = v3_sub(ls.p_light, c);
                expect_close(v3_length(pc), R, 1e-12, 1e-14, "on the sphere", i, j);
                expect_close(v3_length(v3_sub(ls.p_light, p)), ls.dist, 1e-12, 0, "dist", i, j);
                /* Outward unit normal facing the point. */
                expect_close(v3_length(v3_sub(ls.n_light, v3_scale(pc, 1.0 / R))), 0.0, 0,
                             1e-6, "normal", i, j);
                assert_true(v3_dot(ls.n_light, ls.wi) <= 1e-6);
                /* sin²θ of wi from the axis, against u (1 + cosθ)/(1 + cosθmax)
                 * of sin²θmax: the sample is at the requested angle. */
                vec3 cr = v3_cross(ls.wi, axis);
                double s2 = v3_length_sq(cr);
                double omc = us[i] * omc_max;
                double want = us[i] * (2.0 - omc) / (2.0 - omc_max);
                /* p_light - p rounds at the ulp of the coordinates, which
                 * bounds what the direction can resolve (the point is at
                 * least D - R away and spans R across). */
                double res = 8.0 * DBL_EPSILON * (D + v3_length(c)) / fmin(R, D - R);
                expect_close(s2 / s2max, want, 1e-9, 1e-9 + 4.0 * res, "sin2 theta", i, j);
            }
        free_sphere_light(&s);
    }
}

/* Monte Carlo irradiance at `p` (normal `n`) over an n×n grid of u. */
static double grid_irradiance(const light *l, vec3 p, vec3 n, int grid)
{
    double sum = 0.0;
    for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j) {
            light_sample ls;
            vec2 u = v2((i + 0.5) / grid, (j + 0.5) / grid);
            if (!light_sample_li(l, p, n, 0.0, u, &ls))
                continue;
            double cos_t = v3_dot(n, ls.wi);
            if (cos_t > 0.0)
                sum += ls.L.r * cos_t / ls.pdf;
        }
    return sum / ((double)grid * grid);
}

/* Reverse orientation makes the sphere emit inward only: nothing reaches an
 * outside point unless it is two-sided, while a point inside (area sampling,
 * as pbrt-v4) sees the whole cavity: E = π L. */
static void test_one_sided_and_inside(void **state)
{
    (void)state;
    transform m = transform_compose(transform_translate(v3(1, 2, 3)),
                                    transform_scale(v3(-2, 2, 2))); /* a mirror: still a sphere */
    vec3 c = v3(1, 2, 3), n = v3(0, 0, 1);
    vec3 outside = v3(1, 2, -5); /* D = 8 below, R = 2: the sphere is above the horizon */
    double E_out = sphere_irradiance(outside, c, 2.0, 3.0);

    sphere_light out_only; /* flip_normal: ReverseOrientation (XOR the mirror) */
    make_sphere_light(&out_only, m, 1.0, true, "\"rgb L\" [3 3 3]");
    assert_true(out_only.l.area.sphere_cone);
    expect_close(out_only.l.area.sphere_radius, 2.0, 1e-15, 0, "radius", 0, 0);
    light_sample ls;
    for (int i = 0; i < 16; ++i)
        assert_false(light_sample_li(&out_only.l, outside, n, 0.0, v2(i / 16.0, 0.3), &ls));
    /* Inside, from the centre: area sampling (the cone pdf would be wrong). */
    expect_close(grid_irradiance(&out_only.l, c, n, 64), HZ_PI * 3.0, 1e-3, 0, "inside", 0, 0);
    expect_close(grid_irradiance(&out_only.l, v3(1.5, 2.7, 3.9), n, 256), HZ_PI * 3.0, 0.02, 0,
                 "inside, off centre", 0, 0);
    free_sphere_light(&out_only);

    sphere_light two;
    make_sphere_light(&two, m, 1.0, true, "\"rgb L\" [3 3 3] \"bool twosided\" true");
    expect_close(grid_irradiance(&two.l, outside, n, 16), E_out, 1e-3, 0, "two-sided", 0, 0);
    free_sphere_light(&two);

    sphere_light normal;
    make_sphere_light(&normal, m, 1.0, false, "\"rgb L\" [3 3 3]");
    expect_close(grid_irradiance(&normal.l, outside, n, 16), E_out, 1e-3, 0, "one-sided", 0, 0);
    /* Inside a sphere emitting outward only: nothing. */
    assert_true(grid_irradiance(&normal.l, c, n, 16) == 0.0);
    free_sphere_light(&normal);
}

/* Uniform scale detection: rotations, reflections, translations and float-
 * precision matrices pass; anisotropic scales and shears (even by 1e-4) and
 * projective matrices fall back to area sampling. */
static void test_uniform_scale_detection(void **state)
{
    (void)state;
    transform r = transform_compose(transform_rotate(33, v3(1, -2, 0.5)),
                                    transform_translate(v3(1e3, -7, 2)));
    transform t = transform_compose(r, transform_scale(v3(0.25, 0.25, 0.25)));
    expect_close(light_uniform_scale(&t), 0.25, 1e-14, 0, "rotated scale", 0, 0);
    t = transform_compose(r, transform_scale(v3(-3, 3, -3)));
    expect_close(light_uniform_scale(&t), 3.0, 1e-14, 0, "mirrored scale", 0, 0);
    /* The same matrix rounded to float, as exporters write it. */
    transform f = t;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            f.m.m[i][j] = (float)t.m.m[i][j];
    expect_close(light_uniform_scale(&f), 3.0, 1e-6, 0, "float matrix", 0, 0);
    /* Tiny and huge scales are uniform too: the tolerance is relative. */
    t = transform_compose(r, transform_scale(v3(1e-8, 1e-8, 1e-8)));
    expect_close(light_uniform_scale(&t), 1e-8, 1e-13, 0, "tiny scale", 0, 0);
    t = transform_compose(r, transform_scale(v3(1e9, 1e9, 1e9)));
    expect_close(light_uniform_scale(&t), 1e9, 1e-13, 0, "huge scale", 0, 0);

    t = transform_compose(r, transform_scale(v3(1, 1, 1.0001)));
    assert_true(light_uniform_scale(&t) == 0.0);
    t = transform_compose(r, transform_scale(v3(2, 1, 0.5)));
    assert_true(light_uniform_scale(&t) == 0.0);
    transform shear = transform_scale(v3(1, 1, 1));
    shear.m.m[0][1] = 1e-4;
    t = transform_compose(r, shear);
    assert_true(light_uniform_scale(&t) == 0.0);
    transform proj = transform_scale(v3(1, 1, 1));
    proj.m.m[3][2] = 0.5;
    assert_true(light_uniform_scale(&proj) == 0.0);
    transform zero = transform_scale(v3(1, 1, 1));
    zero.m.m[0][0] = zero.m.m[1][1] = zero.m.m[2][2] = 0.0;
    assert_true(light_uniform_scale(&zero) == 0.0);

    /* And the light follows: an ellipsoid emitter is sampled by area. */
    sphere_light s;
    make_sphere_light(&s, transform_scale(v3(2, 1, 0.5)), 1.0, false, "\"rgb L\" [1 1 1]");
    assert_false(s.l.area.sphere_cone);
    free_sphere_light(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cone_sampling_converges),
        cmocka_unit_test(test_tiny_far_sphere),
        cmocka_unit_test(test_cone_samples),
        cmocka_unit_test(test_one_sided_and_inside),
        cmocka_unit_test(test_uniform_scale_detection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
