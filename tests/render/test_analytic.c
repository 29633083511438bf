/* Analytic checks of the surface integrator: scenes whose radiance has a closed
 * form, evaluated through render_scene_li for camera rays at many pixels. */
#include "render_test_util.h"

#define RES 32

/* A 40x40 diffuse plane at z = 0 (world), seen from above. */
static const char *camera_down =
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 60\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
    "Sampler \"independent\" \"integer pixelsamples\" 1\n";

static const char *plane =
    "Material \"diffuse\" \"rgb reflectance\" [0.2 0.5 0.8]\n"
    "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0]\n"
    "  \"integer indices\" [0 1 2 0 2 3]\n";

static const rgb rho = {0.2, 0.5, 0.8, 0.5};

/* ρ/π · I · cosθ / d² for a plane z = 0 with normal +z. */
static rgb point_on_plane(vec3 p, vec3 light, rgb I)
{
    vec3 d = v3_sub(light, p);
    double d2 = v3_length_sq(d);
    double cos_theta = d.z / sqrt(d2);
    return rgb_scale(rgb_mul(rho, I), HZ_INV_PI * cos_theta / d2);
}

static void check_point_light(const char *light_text, vec3 light, rgb I)
{
    char *text = cat(camera_down, "WorldBegin\n", "");
    char *full = cat(text, light_text, plane);
    render_scene *rs = build_scene_or_fail(full, NULL);
    int checked = 0;
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            assert_true(e.hit);
            assert_true(fabs(e.p_world.z) < 1e-5);
            expect_rgb_close(e.L, point_on_plane(e.p_world, light, I), 1e-4, 1e-12, "point light",
                             x, y);
            ++checked;
        }
    assert_int_equal(checked, RES * RES);
    render_scene_destroy(rs);
    free(text);
    free(full);
}

static void test_point_light(void **state)
{
    (void)state;
    check_point_light("LightSource \"point\" \"rgb I\" [1 2 3] \"float scale\" 1.5 "
                      "\"point3 from\" [0.3 -0.2 2]\n",
                      v3(0.3, -0.2, 2.0), rgb_make(1.5, 3.0, 4.5));
    /* The CTM applies to the light: Translate moves `from`. */
    check_point_light("AttributeBegin\nTranslate 1 0 0.5\n"
                      "LightSource \"point\" \"rgb I\" [2 2 2] \"point3 from\" [0 1 1]\n"
                      "AttributeEnd\n",
                      v3(1.0, 1.0, 1.5), rgb_grey(2.0));
}

/* pbrt-v4: scale /= SpectrumToPhotometric(I) (only the colour space's
 * illuminant counts for an RGB value) then scale *= power / (4π), so in RGB
 * I = rgb * scale * power / (4π). */
static void test_point_light_power(void **state)
{
    (void)state;
    check_point_light("LightSource \"point\" \"float power\" 100 \"point3 from\" [0 0 3]\n",
                      v3(0, 0, 3), rgb_grey(100.0 / (4.0 * HZ_PI)));
    check_point_light("LightSource \"point\" \"rgb I\" [1 0.5 0.25] \"float power\" 50 "
                      "\"float scale\" 2 \"point3 from\" [0 0 3]\n",
                      v3(0, 0, 3), rgb_scale(rgb_make(1, 0.5, 0.25), 2 * 50.0 / (4.0 * HZ_PI)));
}

static void test_distant_light(void **state)
{
    (void)state;
    char *text = cat(camera_down,
                     "WorldBegin\nLightSource \"distant\" \"rgb L\" [2 1 0.5] "
                     "\"point3 from\" [1 0.5 3] \"point3 to\" [0 0 0]\n",
                     plane);
    render_scene *rs = build_scene_or_fail(text, NULL);
    double cos_theta = 3.0 / sqrt(1.0 + 0.25 + 9.0);
    rgb want = rgb_scale(rgb_mul(rho, rgb_make(2, 1, 0.5)), HZ_INV_PI * cos_theta);
    for (int y = 0; y < RES; y += 3)
        for (int x = 0; x < RES; x += 3) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            expect_rgb_close(e.L, want, 1e-6, 0, "distant light", x, y);
        }
    render_scene_destroy(rs);
    free(text);
}

/* pbrt-v4's photometric parameters in RGB: a distant light's "illuminance" E
 * multiplies L (E on a patch facing it); a uniform sky's "illuminance" E
 * gives L = E / π (E on an upward patch). */
static void test_light_illuminance(void **state)
{
    (void)state;
    char *text = cat(camera_down,
                     "WorldBegin\nLightSource \"distant\" \"float illuminance\" 3 "
                     "\"point3 from\" [0 0 1] \"point3 to\" [0 0 0]\n",
                     plane);
    render_scene *rs = build_scene_or_fail(text, NULL);
    pixel_eval e = eval_pixel(rs, 7.5, 20.5, 1);
    expect_rgb_close(e.L, rgb_scale(rho, 3.0 * HZ_INV_PI), 1e-9, 0, "distant illuminance", 7, 20);
    render_scene_destroy(rs);
    free(text);

    text = cat(camera_down, "WorldBegin\nLightSource \"infinite\" \"float illuminance\" 2\n",
               plane);
    rs = build_scene_or_fail(text, NULL);
    e = eval_pixel(rs, 7.5, 20.5, 1);
    expect_rgb_close(e.L, rgb_scale(rho, 2.0 * HZ_INV_PI), 1e-9, 0, "sky illuminance", 7, 20);
    render_scene_destroy(rs);
    free(text);
}

static double smooth_step(double x, double a, double b)
{
    double t = fmin(fmax((x - a) / (b - a), 0.0), 1.0);
    return t * t * (3.0 - 2.0 * t);
}

static void check_spot(vec3 from, vec3 to)
{
    /* Cone 30° with a 10° falloff; the camera sees ±2.9 units of the plane,
     * so pixels fall inside the cone, in the falloff and outside. */
    char light[512];
    snprintf(light, sizeof light,
             "WorldBegin\nLightSource \"spot\" \"rgb I\" [3 3 3] \"point3 from\" [%g %g %g] "
             "\"point3 to\" [%g %g %g] \"float coneangle\" 30 \"float conedeltaangle\" 10\n",
             from.x, from.y, from.z, to.x, to.y, to.z);
    char *text = cat(camera_down, light, plane);
    render_scene *rs = build_scene_or_fail(text, NULL);
    vec3 axis = v3_normalize(v3_sub(to, from));
    double cos_end = cos(30.0 * HZ_PI / 180.0), cos_start = cos(20.0 * HZ_PI / 180.0);
    int inside = 0, falloff = 0, outside = 0;
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            double c = v3_dot(v3_normalize(v3_sub(e.p_world, from)), axis);
            double s = smooth_step(c, cos_end, cos_start);
            rgb want = rgb_scale(point_on_plane(e.p_world, from, rgb_grey(3.0)), s);
            expect_rgb_close(e.L, want, 1e-4, 1e-12, "spot light", x, y);
            if (c >= cos_start)
                ++inside;
            else if (c <= cos_end) {
                ++outside;
                assert_true(e.L.r == 0.0);
            } else
                ++falloff;
        }
    assert_true(inside > 10 && falloff > 10 && outside > 10);
    render_scene_destroy(rs);
    free(text);
}

static void test_spot_light(void **state)
{
    (void)state;
    check_spot(v3(0.2, 0, 2), v3(0.2, 0, 0));
    check_spot(v3(1, -0.5, 2), v3(-0.3, 0.4, 0)); /* oblique axis */
}

/* Distance from c to the segment [a, b]. */
static double segment_distance(vec3 c, vec3 a, vec3 b)
{
    vec3 ab = v3_sub(b, a);
    double t = hz_clamp(v3_dot(v3_sub(c, a), ab) / v3_dot(ab, ab), 0.0, 1.0);
    return v3_length(v3_sub(c, v3_add(a, v3_scale(ab, t))));
}

static void test_sphere_shadow(void **state)
{
    (void)state;
    /* Sphere (radius 0.6 at (0.3, 0, 1)) between a point light and the plane;
     * the sphere is diffuse too and lit on its upper half. */
    char *text = cat(camera_down,
                     "WorldBegin\nLightSource \"point\" \"rgb I\" [4 4 4] \"point3 from\" [0 0 3]\n"
                     "AttributeBegin\nTranslate 0.3 0 1\nMaterial \"diffuse\" \"rgb reflectance\" "
                     "[0.2 0.5 0.8]\nShape \"sphere\" \"float radius\" 0.6\nAttributeEnd\n",
                     plane);
    render_scene *rs = build_scene_or_fail(text, NULL);
    vec3 light = v3(0, 0, 3), c = v3(0.3, 0, 1);
    int umbra = 0, lit = 0, on_sphere = 0;
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            assert_true(e.hit);
            if (fabs(e.p_world.z) > 1e-4) { /* on the sphere */
                assert_true(fabs(v3_length(v3_sub(e.p_world, c)) - 0.6) < 1e-4);
                vec3 n = v3_normalize(v3_sub(e.p_world, c));
                vec3 d = v3_sub(light, e.p_world);
                double cos_theta = v3_dot(n, d) / v3_length(d);
                rgb want = cos_theta > 0 ? rgb_scale(rho, 4.0 * HZ_INV_PI * cos_theta /
                                                              v3_length_sq(d))
                                         : rgb_grey(0.0);
                expect_rgb_close(e.L, want, 1e-4, 1e-9, "sphere", x, y);
                ++on_sphere;
                continue;
            }
            double dist = segment_distance(c, e.p_world, light);
            if (fabs(dist - 0.6) < 1e-3)
                continue; /* the shadow's edge: either answer is right */
            if (dist < 0.6) {
                assert_true(e.L.r == 0.0 && e.L.g == 0.0 && e.L.b == 0.0);
                ++umbra;
            } else {
                expect_rgb_close(e.L, point_on_plane(e.p_world, light, rgb_grey(4.0)), 1e-4,
                                 1e-12, "lit plane", x, y);
                ++lit;
            }
        }
    assert_true(umbra > 10 && lit > 10 && on_sphere > 10);
    render_scene_destroy(rs);
    free(text);
}

/* Camera, plane and light moved together far from the origin: render space
 * keeps the values those at the origin have. */
static void test_far_from_origin(void **state)
{
    (void)state;
    const char *near =
        "LookAt 0.5 0.25 5  0 0 0  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 60\n"
        "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
        "Sampler \"independent\" \"integer pixelsamples\" 1\n"
        "WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1] \"point3 from\" [0.3 -0.2 2]\n"
        "Material \"diffuse\" \"rgb reflectance\" [0.2 0.5 0.8]\n"
        "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0]\n"
        "  \"integer indices\" [0 1 2 0 2 3]\n";
    const char *far =
        "LookAt 10000000.5 -29999999.75 20000005  10000000 -30000000 20000000  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 60\n"
        "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
        "Sampler \"independent\" \"integer pixelsamples\" 1\n"
        "WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1] "
        "\"point3 from\" [10000000.3 -30000000.2 20000002]\n"
        "Material \"diffuse\" \"rgb reflectance\" [0.2 0.5 0.8]\n"
        "Shape \"trianglemesh\" \"point3 P\" [9999980 -30000020 20000000  10000020 -30000020 "
        "20000000  10000020 -29999980 20000000  9999980 -29999980 20000000]\n"
        "  \"integer indices\" [0 1 2 0 2 3]\n";
    render_scene *a = build_scene_or_fail(near, NULL);
    render_scene *b = build_scene_or_fail(far, NULL);
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            pixel_eval ea = eval_pixel(a, x + 0.5, y + 0.5, 1);
            pixel_eval eb = eval_pixel(b, x + 0.5, y + 0.5, 1);
            assert_true(ea.L.r > 0.0);
            expect_rgb_close(eb.L, ea.L, 1e-4, 0, "far scene vs origin", x, y);
            expect_close(eb.depth, ea.depth, 1e-5, 0, "depth", x, y);
        }
    render_scene_destroy(a);
    render_scene_destroy(b);
}

/* A tilted plane lit at grazing incidence (cosθ = 0.002): every pixel must be
 * lit with the analytic value, i.e. no shadow ray hits its own surface. */
static void test_grazing_no_acne(void **state)
{
    (void)state;
    double cos_theta = 0.002, sin_theta = sqrt(1.0 - cos_theta * cos_theta);
    /* Plane normal after Rotate 33 about (1 1 0.3). */
    char light[256];
    transform r = transform_rotate(33.0, v3(1, 1, 0.3));
    vec3 n = v3_normalize(transform_normal(&r, v3(0, 0, 1)));
    vec3 t1, t2;
    v3_basis(n, &t1, &t2);
    vec3 to_light = v3_add(v3_scale(n, cos_theta), v3_scale(t1, sin_theta));
    snprintf(light, sizeof light,
             "LightSource \"distant\" \"rgb L\" [1 1 1] \"point3 from\" [%.17g %.17g %.17g] "
             "\"point3 to\" [0 0 0]\n",
             to_light.x, to_light.y, to_light.z);
    char *scene = cat(camera_down, "WorldBegin\n", light);
    char *full = cat(scene,
                     "Material \"diffuse\" \"rgb reflectance\" [0.2 0.5 0.8]\n"
                     "Rotate 33 1 1 0.3\n"
                     "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0]\n"
                     "  \"integer indices\" [0 1 2 0 2 3]\n",
                     "");
    render_scene *rs = build_scene_or_fail(full, NULL);
    rgb want = rgb_scale(rho, HZ_INV_PI * cos_theta);
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            expect_rgb_close(e.L, want, 1e-4, 0, "grazing", x, y);
        }
    render_scene_destroy(rs);
    free(scene);
    free(full);
}

/* Irradiance per unit radiance at a point at height h below a corner of an
 * a x b rectangle parallel to it: (1/2)[X/√(1+X²) atan(Y/√(1+X²)) + ...],
 * X = a/h, Y = b/h (π times the form factor). */
static double rect_corner_irradiance(double a, double b, double h)
{
    double X = a / h, Y = b / h;
    double sx = sqrt(1 + X * X), sy = sqrt(1 + Y * Y);
    return 0.5 * (X / sx * atan(Y / sx) + Y / sy * atan(X / sy));
}

static void test_area_light_rectangle(void **state)
{
    (void)state;
    /* 2x2 emitter facing down at height 1 (indices reversed so its normal is
     * -z); the camera sits between it and the plane, looking down, so every
     * pixel sees a plane point under the emitter. Each pixel averages 4096
     * zsobol samples: measured error below 1e-4 (independent samples need
     * ~65536 for 0.5%); the tolerance is 0.5%. */
    const char *text =
        "LookAt 0 0 0.5  0 0 0  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 60\n"
        "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
        "Sampler \"zsobol\" \"integer pixelsamples\" 4096\n"
        "WorldBegin\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n"
        "Shape \"trianglemesh\" \"point3 P\" [-1 -1 1  1 -1 1  1 1 1  -1 1 1]\n"
        "  \"integer indices\" [0 2 1 0 3 2]\nAttributeEnd\n"
        "Material \"diffuse\" \"rgb reflectance\" [0.2 0.5 0.8]\n"
        "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0]\n"
        "  \"integer indices\" [0 1 2 0 2 3]\n";
    render_scene *rs = build_scene_or_fail(text, NULL);
    for (int y = 2; y < RES; y += 9)
        for (int x = 2; x < RES; x += 9) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 4096);
            vec3 p = e.p_world;
            assert_true(fabs(p.z) < 1e-6);
            double E = 0;
            for (int sx = -1; sx <= 1; sx += 2)
                for (int sy = -1; sy <= 1; sy += 2)
                    E += rect_corner_irradiance(1.0 + sx * p.x, 1.0 + sy * p.y, 1.0);
            E *= 2.0; /* L */
            rgb want = rgb_scale(rho, HZ_INV_PI * E);
            expect_rgb_close(e.L, want, 0.005, 0, "rectangle area light", x, y);
        }
    render_scene_destroy(rs);
}

/* One-sided emitters are seen from the front only; twosided from both. */
static void test_area_light_seen_directly(void **state)
{
    (void)state;
    const char *fmt =
        "LookAt 0 0 5  0 0 0  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 30\n"
        "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
        "WorldBegin\n%s"
        "AreaLightSource \"diffuse\" \"rgb L\" [0.5 1 2] %s\n"
        "Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
        "Shape \"trianglemesh\" \"point3 P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0]\n"
        "  \"integer indices\" [0 1 2 0 2 3]\n";
    struct {
        const char *pre, *params;
        double want;
    } cases[] = {
        {"", "", 1.0},
        {"ReverseOrientation\n", "", 0.0},
        {"ReverseOrientation\n", "\"bool twosided\" true", 1.0},
        {"Scale 1 1 -1\n", "", 0.0},           /* handedness swap flips the normal */
        {"Scale 1 1 -1\nReverseOrientation\n", "", 1.0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char text[2048];
        snprintf(text, sizeof text, fmt, cases[i].pre, cases[i].params);
        render_scene *rs = build_scene_or_fail(text, NULL);
        pixel_eval e = eval_pixel(rs, 4.5, 3.5, 1);
        expect_rgb_close(e.L, rgb_scale(rgb_make(0.5, 1, 2), cases[i].want), 1e-12, 0,
                         "direct emitter", (double)i, 0);
        render_scene_destroy(rs);
    }
}

static void test_infinite_light(void **state)
{
    (void)state;
    /* A constant sky of radiance L over an unoccluded plane: E = πL, so the
     * plane shows ρL; cosine sampling makes every sample exact. Rays that
     * miss (looking up at the horizon) see L. */
    char *text = cat(camera_down, "WorldBegin\nLightSource \"infinite\" \"rgb L\" [0.5 1 1.5]\n",
                     plane);
    render_scene *rs = build_scene_or_fail(text, NULL);
    for (int y = 0; y < RES; y += 5)
        for (int x = 0; x < RES; x += 5) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            expect_rgb_close(e.L, rgb_mul(rho, rgb_make(0.5, 1, 1.5)), 1e-9, 0, "sky on plane",
                             x, y);
        }
    render_scene_destroy(rs);
    free(text);

    const char *up = "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\n"
                     "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                     "WorldBegin\nLightSource \"infinite\" \"rgb L\" [0.5 1 1.5] \"float scale\" 2\n";
    rs = build_scene_or_fail(up, NULL);
    pixel_eval e = eval_pixel(rs, 3.5, 3.5, 1);
    assert_false(e.hit);
    expect_rgb_close(e.L, rgb_make(1, 2, 3), 1e-12, 0, "sky seen directly", 3, 3);
    render_scene_destroy(rs);
}

static void test_errors(void **state)
{
    (void)state;
    char msg[1024];
    build_scene_expect_error("WorldBegin\nMaterial \"subsurface\"\n"
                             "Shape \"sphere\"\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:2:"));
    assert_non_null(strstr(msg, "diffuse"));
    build_scene_expect_error("Integrator \"ambientocclusion\"\nWorldBegin\n", msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:1:"));
    assert_non_null(strstr(msg, "volpath"));
    build_scene_expect_error("WorldBegin\nLightSource \"goniometric\"\n", msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:2:"));
    build_scene_expect_error("WorldBegin\nLightSource \"point\" \"float scael\" 2\n", msg,
                             sizeof msg);
    assert_non_null(strstr(msg, "scael"));
    build_scene_expect_error("WorldBegin\nLightSource \"infinite\" \"string filename\" \"a.exr\"\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:2:"));
    /* Media names resolve after the whole file: an undefined one is an error
     * at the directive that used it. */
    build_scene_expect_error("MediumInterface \"\" \"fgo\"\nCamera \"perspective\"\nWorldBegin\n"
                             "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:2:"));
    assert_non_null(strstr(msg, "\"fgo\""));
    build_scene_expect_error("WorldBegin\nMediumInterface \"fog\" \"\"\nShape \"sphere\"\n", msg,
                             sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:3:"));
    build_scene_expect_error("Integrator \"singlescatter\" \"string transmittance\" \"exact\"\n"
                             "WorldBegin\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "exact"));
    build_scene_expect_error("Integrator \"singlescatter\" \"float stepsize\" 0\nWorldBegin\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "stepsize"));
}

/* The camera's medium is named before it is defined: names resolve after the
 * whole file is read, so declaration order does not matter. */
static void test_camera_medium_resolved_late(void **state)
{
    (void)state;
    render_scene *rs = build_scene_or_fail(
        "MediumInterface \"\" \"thick\"\nCamera \"perspective\"\nWorldBegin\n"
        "MakeNamedMedium \"thin\" \"string type\" \"homogeneous\"\n"
        "MakeNamedMedium \"thick\" \"string type\" \"homogeneous\"\n",
        NULL);
    assert_int_equal(render_scene_camera(rs)->medium, 1);
    render_scene_destroy(rs);
    rs = build_scene_or_fail("Camera \"perspective\"\nWorldBegin\n"
                             "MakeNamedMedium \"thin\" \"string type\" \"homogeneous\"\n",
                             NULL);
    assert_int_equal(render_scene_camera(rs)->medium, -1);
    render_scene_destroy(rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_light),
        cmocka_unit_test(test_camera_medium_resolved_late),
        cmocka_unit_test(test_point_light_power),
        cmocka_unit_test(test_distant_light),
        cmocka_unit_test(test_light_illuminance),
        cmocka_unit_test(test_spot_light),
        cmocka_unit_test(test_sphere_shadow),
        cmocka_unit_test(test_far_from_origin),
        cmocka_unit_test(test_grazing_no_acne),
        cmocka_unit_test(test_area_light_rectangle),
        cmocka_unit_test(test_area_light_seen_directly),
        cmocka_unit_test(test_infinite_light),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
