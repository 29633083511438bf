/* Analytic checks of geometry handling: spherical emitters, transformed
 * spheres, interface surfaces and object instances. */
#include "render_test_util.h"

#define RES 32

static const char *camera_down =
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 60\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n";

/* A sphere of radius R and radiance L entirely above a point's horizon gives
 * E = π L (R/D)² cosθ (D: distance to its centre, θ: angle of the centre from
 * the normal). Radius 0.5 scaled by 2 checks the area-measure Jacobian. */
static void test_sphere_emitter(void **state)
{
    (void)state;
    char *text = cat(camera_down,
                     "Sampler \"zsobol\" \"integer pixelsamples\" 4096\n"
                     "WorldBegin\nAttributeBegin\nTranslate 0 0 3\nScale 2 2 2\n"
                     "AreaLightSource \"diffuse\" \"rgb L\" [1.5 1.5 1.5]\n"
                     "Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n"
                     "Material \"diffuse\" \"rgb reflectance\" [0.6 0.6 0.6]\n"
                     "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0]\n"
                     "  \"integer indices\" [0 1 2 0 2 3]\n",
                     "");
    render_scene *rs = build_scene_or_fail(text, NULL);
    vec3 c = v3(0, 0, 3);
    int on_plane = 0, on_sphere = 0;
    for (int y = 1; y < RES; y += 5)
        for (int x = 1; x < RES; x += 5) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 4096);
            assert_true(e.hit);
            if (e.p_world.z > 1.0) {
                /* The emitter itself: L (a convex emitter does not light itself). */
                assert_true(fabs(v3_length(v3_sub(e.p_world, c)) - 1.0) < 1e-5);
                expect_close(e.L.r, 1.5, 1e-9, 0, "emitter seen directly", x, y);
                ++on_sphere;
                continue;
            }
            vec3 d = v3_sub(c, e.p_world);
            double D2 = v3_length_sq(d);
            double E = HZ_PI * 1.5 * (1.0 / D2) * (d.z / sqrt(D2));
            expect_close(e.L.r, 0.6 * HZ_INV_PI * E, 0.005, 0, "lit by sphere", x, y);
            ++on_plane;
        }
    assert_true(on_plane > 10 && on_sphere > 0);
    render_scene_destroy(rs);
    free(text);
}

/* An ellipsoid (a non-uniformly scaled sphere) under a distant light: hits
 * lie on the ellipsoid and shade with its true normal. */
static void test_ellipsoid(void **state)
{
    (void)state;
    char *text = cat(camera_down,
                     "WorldBegin\nLightSource \"distant\" \"rgb L\" [1 1 1] "
                     "\"point3 from\" [3 -1 0.7] \"point3 to\" [0 0 0]\n"
                     "AttributeBegin\nTranslate 0 0 1\nRotate 30 0 0 1\nScale 2 1 0.5\n"
                     "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
                     "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
                     "");
    render_scene *rs = build_scene_or_fail(text, NULL);
    transform from_obj = transform_compose(
        transform_compose(transform_translate(v3(0, 0, 1)), transform_rotate(30, v3(0, 0, 1))),
        transform_scale(v3(2, 1, 0.5)));
    transform to_obj = transform_inverse(from_obj);
    vec3 w = v3_normalize(v3(3, -1, 0.7));
    int hits = 0, dark = 0;
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            if (!e.hit) {
                assert_true(e.L.r == 0.0);
                continue;
            }
            vec3 po = transform_point(&to_obj, e.p_world);
            expect_close(v3_length(po), 1.0, 1e-6, 0, "on the ellipsoid", x, y);
            vec3 n = v3_normalize(transform_normal(&from_obj, po)); /* by (M^-1)^T */
            double cos_theta = fmax(0.0, v3_dot(n, w));
            expect_close(e.L.r, 0.5 * HZ_INV_PI * cos_theta, 1e-5, 1e-12, "ellipsoid shading", x,
                         y);
            ++hits;
            dark += cos_theta == 0.0;
        }
    assert_true(hits > 50 && dark > 5 && hits - dark > 5);
    render_scene_destroy(rs);
    free(text);
}

/* Interface surfaces are not surfaces: camera and shadow rays pass them, and
 * depth is the distance to the first real surface. */
static void test_interface_is_invisible(void **state)
{
    (void)state;
    const char *light = "LightSource \"point\" \"rgb I\" [1 1 1] \"point3 from\" [0.3 -0.2 2]\n";
    const char *plane =
        "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
        "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0]\n"
        "  \"integer indices\" [0 1 2 0 2 3]\n";
    const char *interfaces =
        "AttributeBegin\nMaterial \"interface\"\n"
        "Shape \"trianglemesh\" \"point3 P\" [-20 -20 1  20 -20 1  20 20 1  -20 20 1]\n"
        "  \"integer indices\" [0 1 2 0 2 3]\n"
        "Shape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n";
    char *a_text = cat(camera_down, "WorldBegin\n", light);
    char *a_full = cat(a_text, plane, "");
    char *b_full = cat(a_text, interfaces, plane);
    render_scene *a = build_scene_or_fail(a_full, NULL);
    render_scene *b = build_scene_or_fail(b_full, NULL);
    for (int y = 0; y < RES; y += 3)
        for (int x = 0; x < RES; x += 3) {
            pixel_eval ea = eval_pixel(a, x + 0.5, y + 0.5, 1);
            pixel_eval eb = eval_pixel(b, x + 0.5, y + 0.5, 1);
            assert_true(ea.L.r > 0.0);
            expect_rgb_close(eb.L, ea.L, 1e-6, 0, "through interfaces", x, y);
            expect_close(eb.depth, ea.depth, 1e-6, 0, "depth through interfaces", x, y);
        }
    render_scene_destroy(a);
    render_scene_destroy(b);
    free(a_text);
    free(a_full);
    free(b_full);
}

/* Two instances of one object (a unit quad and a small sphere) at different
 * places and heights, lit by a distant light from +z. */
static void test_instances(void **state)
{
    (void)state;
    char *text = cat(camera_down,
                     "WorldBegin\nLightSource \"distant\" \"rgb L\" [2 2 2] "
                     "\"point3 from\" [0 0 1] \"point3 to\" [0 0 0]\n"
                     "ObjectBegin \"thing\"\n"
                     "Material \"diffuse\" \"rgb reflectance\" [0.25 0.5 0.75]\n"
                     "Shape \"trianglemesh\" \"point3 P\" [-0.5 -0.5 0  0.5 -0.5 0  0.5 0.5 0  "
                     "-0.5 0.5 0]\n  \"integer indices\" [0 1 2 0 2 3]\n"
                     "ObjectEnd\n"
                     "AttributeBegin\nTranslate -1 0 0\nObjectInstance \"thing\"\nAttributeEnd\n"
                     "AttributeBegin\nTranslate 1 0.5 0.5\nRotate 180 1 0 0\n"
                     "ObjectInstance \"thing\"\nAttributeEnd\n",
                     "");
    render_scene *rs = build_scene_or_fail(text, NULL);
    rgb want = rgb_scale(rgb_make(0.25, 0.5, 0.75), 2.0 * HZ_INV_PI);
    int first = 0, second = 0, missed = 0;
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            if (!e.hit) {
                assert_true(e.L.r == 0.0);
                ++missed;
                continue;
            }
            vec3 p = e.p_world;
            if (fabs(p.z) < 1e-5) {
                assert_true(fabs(p.x + 1.0) <= 0.5 + 1e-5 && fabs(p.y) <= 0.5 + 1e-5);
                ++first;
            } else {
                assert_true(fabs(p.z - 0.5) < 1e-5);
                assert_true(fabs(p.x - 1.0) <= 0.5 + 1e-5 && fabs(p.y - 0.5) <= 0.5 + 1e-5);
                ++second;
            }
            expect_rgb_close(e.L, want, 1e-9, 0, "instance", x, y);
        }
    assert_true(first > 10 && second > 10 && missed > 10);
    render_scene_destroy(rs);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_emitter),
        cmocka_unit_test(test_ellipsoid),
        cmocka_unit_test(test_interface_is_invisible),
        cmocka_unit_test(test_instances),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
