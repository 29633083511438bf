/* camera_create: reading a Camera directive's parameters through the param API,
 * pbrt-v4's defaults, haze's physical-lens parameters, and errors that name
 * file:line:column. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera/camera.h"
#include "scene/params.h"
#include "unit/assert_util.h"

static char *dup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    assert_non_null(d);
    memcpy(d, s, n);
    return d;
}

typedef struct {
    camera_entity e;
    char type[32];
} fixture;

static void fixture_init(fixture *f, const char *type)
{
    memset(f, 0, sizeof *f);
    strcpy(f->type, type);
    f->e.entity.type = f->type;
    f->e.entity.loc = (file_loc){"scene.pbrt", 3, 1, NULL};
    params_init(&f->e.entity.params, f->e.entity.loc);
    f->e.camera_from_world = transform_identity();
    f->e.camera_from_world_end = transform_identity();
    f->e.medium = NULL;
}

/* Adds a numeric parameter declared at scene.pbrt:line:column. */
static void add_nums(fixture *f, param_type type, const char *name, int line, int column,
                     size_t count, const double *values)
{
    param p;
    memset(&p, 0, sizeof p);
    p.type = type;
    p.name = dup(name);
    p.loc = (file_loc){"scene.pbrt", line, column, NULL};
    p.count = count;
    p.nums = malloc(count * sizeof *p.nums);
    assert_non_null(p.nums);
    memcpy(p.nums, values, count * sizeof *p.nums);
    hz_error err;
    assert_int_equal(params_add(&f->e.entity.params, p, &err), HZ_OK);
}

static void add_float(fixture *f, const char *name, int line, int column, double v)
{
    add_nums(f, PARAM_FLOAT, name, line, column, 1, &v);
}

static void add_int(fixture *f, const char *name, int line, int column, int v)
{
    double d = v;
    add_nums(f, PARAM_INTEGER, name, line, column, 1, &d);
}

static film_params film_of(int xres, int yres)
{
    film_params fp;
    memset(&fp, 0, sizeof fp);
    fp.xres = xres;
    fp.yres = yres;
    fp.bounds = (pixel_bounds){0, 0, xres, yres};
    fp.iso = 100;
    fp.diagonal = 35.0; /* mm, pbrt-v4's default */
    return fp;
}

static camera create_ok(fixture *f, film_params fp)
{
    camera c;
    hz_error err = {0};
    if (camera_create(&f->e, &fp, &c, &err) != HZ_OK)
        fail_msg("camera_create: %s", err.message);
    params_free(&f->e.entity.params);
    return c;
}

static void expect_error(fixture *f, film_params fp, const char *want)
{
    camera c;
    hz_error err = {0};
    assert_int_equal(camera_create(&f->e, &fp, &c, &err), HZ_ERROR);
    if (strcmp(err.message, want) != 0)
        fail_msg("message\n  \"%s\"\nwanted\n  \"%s\"", err.message, want);
    params_free(&f->e.entity.params);
}

static void test_defaults_are_pbrt_v4s(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "perspective");
    camera c = create_ok(&f, film_of(200, 100));
    assert_int_equal(c.kind, CAMERA_PERSPECTIVE);
    assert_near(c.fov, 90, 0);
    assert_near(c.lens_radius, 0, 0);
    assert_near(c.focal_distance, 1e6, 0);
    assert_near(c.shutter_open, 0, 0);
    assert_near(c.shutter_close, 1, 0);
    assert_int_equal(c.medium, -1);
    assert_int_equal(c.blades, 0);
    const double w[4] = {-2, 2, -1, 1};
    for (int i = 0; i < 4; ++i)
        assert_near(c.screen_window[i], w[i], 0);
    assert_int_equal(c.xres, 200);
    assert_int_equal(c.yres, 100);

    fixture_init(&f, "orthographic");
    c = create_ok(&f, film_of(100, 400));
    assert_int_equal(c.kind, CAMERA_ORTHOGRAPHIC);
    const double wp[4] = {-1, 1, -4, 4};
    for (int i = 0; i < 4; ++i)
        assert_near(c.screen_window[i], wp[i], 0);
}

static void test_every_parameter_is_read(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "perspective");
    add_float(&f, "fov", 4, 5, 30);
    add_float(&f, "lensradius", 5, 5, 0.1);
    add_float(&f, "focaldistance", 6, 5, 4);
    add_float(&f, "shutteropen", 7, 5, 0.2);
    add_float(&f, "shutterclose", 8, 5, 0.7);
    add_nums(&f, PARAM_FLOAT, "screenwindow", 9, 5, 4, (const double[]){-1, 3, -0.5, 0.25});
    add_int(&f, "blades", 10, 5, 5);
    add_float(&f, "bladerotation", 11, 5, 30);
    transform cfw;
    assert_true(transform_look_at(v3(1, 2, 3), v3(1, 2, 4), v3(0, 1, 0), &cfw));
    f.e.camera_from_world = cfw;
    f.e.camera_from_world_end = cfw;
    film_params fp = film_of(64, 64);
    fp.iso = 400;
    camera c = create_ok(&f, fp);
    assert_near(c.fov, 30, 0);
    assert_near(c.lens_radius, 0.1, 0);
    assert_near(c.focal_distance, 4, 0);
    assert_near(c.shutter_open, 0.2, 0);
    assert_near(c.shutter_close, 0.7, 0);
    const double w[4] = {-1, 3, -0.5, 0.25};
    for (int i = 0; i < 4; ++i)
        assert_near(c.screen_window[i], w[i], 0);
    assert_int_equal(c.blades, 5);
    assert_near(c.blade_rotation, HZ_PI / 6, 1e-15);
    assert_near(camera_imaging_ratio(&c, &fp), 0.5 * 4, 1e-15);
    /* Render space: the camera at (1,2,3) is the origin. */
    vec3 o = transform_point(&c.world_from_render, v3(0, 0, 0));
    assert_near(o.x, 1, 0);
    assert_near(o.y, 2, 0);
    assert_near(o.z, 3, 0);
}

static void test_frame_aspect_ratio(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "perspective");
    add_float(&f, "frameaspectratio", 4, 5, 0.5);
    camera c = create_ok(&f, film_of(200, 100));
    const double w[4] = {-1, 1, -2, 2};
    for (int i = 0; i < 4; ++i)
        assert_near(c.screen_window[i], w[i], 0);
}

static void test_physical_lens(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "perspective");
    add_float(&f, "focallength", 4, 5, 50);
    add_float(&f, "fstop", 5, 5, 2);
    camera c = create_ok(&f, film_of(300, 200));
    /* 36 mm along 300 px, so 24 mm along the shorter 200 px. */
    assert_near(c.fov, 2 * atan(12.0 / 50.0) * 180 / HZ_PI, 1e-12);
    assert_near(c.lens_radius, 0.0125, 1e-16);

    fixture_init(&f, "perspective");
    add_float(&f, "focallength", 4, 5, 35);
    add_float(&f, "sensorwidth", 5, 5, 24);
    add_float(&f, "lensradius", 6, 5, 0.01);
    c = create_ok(&f, film_of(100, 200)); /* portrait: 12 mm along x */
    assert_near(c.fov, 2 * atan(6.0 / 35.0) * 180 / HZ_PI, 1e-12);
    assert_near(c.lens_radius, 0.01, 0);

    fixture_init(&f, "perspective");
    add_float(&f, "focallength", 4, 5, 35);
    c = create_ok(&f, film_of(100, 100));
    assert_near(c.lens_radius, 0, 0); /* a pinhole unless told otherwise */
}

static void test_physical_lens_errors(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "perspective");
    add_float(&f, "fov", 4, 5, 40);
    add_float(&f, "focallength", 5, 7, 50);
    expect_error(&f, film_of(10, 10),
                 "scene.pbrt:4:5: give either \"fov\" or \"focallength\" for a perspective "
                 "camera, not both");

    fixture_init(&f, "perspective");
    add_float(&f, "fstop", 6, 2, 2.8);
    expect_error(&f, film_of(10, 10), "scene.pbrt:6:2: \"fstop\" needs \"focallength\"");

    fixture_init(&f, "perspective");
    add_float(&f, "focallength", 5, 7, 50);
    add_float(&f, "fstop", 6, 2, 2.8);
    add_float(&f, "lensradius", 7, 2, 0.1);
    expect_error(&f, film_of(10, 10),
                 "scene.pbrt:6:2: give either \"lensradius\" or \"fstop\", not both");

    fixture_init(&f, "perspective");
    add_float(&f, "focallength", 5, 7, -50);
    expect_error(&f, film_of(10, 10),
                 "scene.pbrt:5:7: \"focallength\" must be finite and > 0 (millimetres), got -50");

    fixture_init(&f, "perspective");
    add_float(&f, "focallength", 5, 7, 50);
    add_float(&f, "fstop", 6, 2, 0);
    expect_error(&f, film_of(10, 10), "scene.pbrt:6:2: \"fstop\" must be finite and > 0, got 0");

    fixture_init(&f, "perspective");
    add_float(&f, "focallength", 5, 7, 50);
    add_float(&f, "sensorwidth", 8, 3, 0);
    expect_error(&f, film_of(10, 10),
                 "scene.pbrt:8:3: \"sensorwidth\" must be finite and > 0 (millimetres), got 0");

    /* sensorwidth means nothing without a focal length. */
    fixture_init(&f, "perspective");
    add_float(&f, "sensorwidth", 8, 3, 24);
    expect_error(
        &f, film_of(10, 10),
        "scene.pbrt:8:3: unused parameter \"float sensorwidth\" for Camera \"perspective\"");
}

static void test_unsupported_type(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "fisheye");
    expect_error(&f, film_of(10, 10),
                 "scene.pbrt:3:1: camera type \"fisheye\" is not supported (haze supports "
                 "\"perspective\", \"orthographic\", \"spherical\" and \"realistic\")");
}

/* The spherical camera's directions (camera space, before the render
 * transform, which is the identity here): pbrt-v4's maps with y and z
 * swapped. */
static void test_spherical_directions(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "spherical"); /* "mapping" "equalarea", the default */
    camera c = create_ok(&f, film_of(64, 32));
    assert_false(c.equirect);
    struct {
        vec2 p;
        vec3 d;
    } equal_area[] = {
        {{32.0, 16.0}, {0.0, 1.0, 0.0}},   /* the square's centre: +z, swapped to up */
        {{0.0, 0.0}, {0.0, -1.0, 0.0}},    /* its corners: down */
        {{64.0, 16.0}, {1.0, 0.0, 0.0}},   /* the middle of its right edge: +x */
        {{32.0, 32.0}, {0.0, 0.0, 1.0}},   /* bottom edge's middle: +y, swapped to +z */
    };
    for (size_t i = 0; i < sizeof equal_area / sizeof equal_area[0]; ++i) {
        ray r;
        camera_sample cs = {equal_area[i].p, v2(0.5, 0.5), 0.0, 1.0};
        assert_true(camera_generate_ray(&c, cs, &r));
        assert_float_equal(r.d.x, equal_area[i].d.x, 1e-12);
        assert_float_equal(r.d.y, equal_area[i].d.y, 1e-12);
        assert_float_equal(r.d.z, equal_area[i].d.z, 1e-12);
        assert_float_equal(v3_length(r.o), 0.0, 0.0);
    }
    /* Equal area: a uniform grid over the film covers the sphere uniformly,
     * so half its directions point up and their mean is the origin. */
    int up = 0, n = 0;
    vec3 mean = v3(0.0, 0.0, 0.0);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) {
            ray r;
            camera_sample cs = {v2(x + 0.5, y + 0.5), v2(0.5, 0.5), 0.0, 1.0};
            assert_true(camera_generate_ray(&c, cs, &r));
            up += r.d.y > 0.0;
            mean = v3_add(mean, r.d);
            ++n;
        }
    assert_int_equal(up, n / 2);
    assert_true(v3_length(mean) / n < 1e-9);

    fixture_init(&f, "spherical");
    const char *equirect = "equirectangular";
    param p = {.type = PARAM_STRING, .name = dup("mapping"), .count = 1,
               .loc = {.file = "scene.pbrt", .line = 4, .column = 5}};
    p.strs = malloc(sizeof *p.strs);
    assert_non_null(p.strs);
    p.strs[0] = dup(equirect);
    hz_error err;
    assert_int_equal(params_add(&f.e.entity.params, p, &err), HZ_OK);
    c = create_ok(&f, film_of(64, 32));
    assert_true(c.equirect);
    struct {
        vec2 p;
        vec3 d;
    } equirect_dirs[] = {
        {{16.0, 16.0}, {0.0, 0.0, 1.0}},  /* longitude 90 degrees on the horizon: ahead */
        {{0.0, 16.0}, {1.0, 0.0, 0.0}},   /* longitude 0: +x */
        {{32.0, 16.0}, {-1.0, 0.0, 0.0}}, /* longitude 180 */
        {{20.0, 0.0}, {0.0, 1.0, 0.0}},   /* the top row: up */
    };
    for (size_t i = 0; i < sizeof equirect_dirs / sizeof equirect_dirs[0]; ++i) {
        ray_differential rd;
        camera_sample cs = {equirect_dirs[i].p, v2(0.5, 0.5), 0.0, 1.0};
        assert_true(camera_generate_ray_differential(&c, cs, &rd));
        assert_float_equal(rd.r.d.x, equirect_dirs[i].d.x, 1e-12);
        assert_float_equal(rd.r.d.y, equirect_dirs[i].d.y, 1e-12);
        assert_float_equal(rd.r.d.z, equirect_dirs[i].d.z, 1e-12);
        assert_true(v3_is_finite(rd.rx_d) && v3_is_finite(rd.ry_d));
    }
    /* On the horizon one pixel turns the ray by 2 pi / 64 about the up axis:
     * the differential direction d + dd/dx (normalised) is that far off d
     * in the tangent's direction. */
    ray_differential rd;
    camera_sample cs = {v2(16.0, 16.0), v2(0.5, 0.5), 0.0, 1.0};
    assert_true(camera_generate_ray_differential(&c, cs, &rd));
    double angle = acos(v3_dot(rd.r.d, rd.rx_d));
    assert_float_equal(tan(angle), 2.0 * HZ_PI / 64.0, 2e-3);
}

/* A spherical camera has no lens and no screen: pbrt-v4 reads and ignores
 * those parameters; haze names them. */
static void test_spherical_refusals(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "spherical");
    add_float(&f, "lensradius", 5, 9, 0.1);
    expect_error(&f, film_of(10, 10),
                 "scene.pbrt:5:9: \"lensradius\" does nothing on a spherical camera (pbrt-v4 "
                 "ignores it): remove it");
    fixture_init(&f, "spherical");
    param p = {.type = PARAM_STRING, .name = dup("mapping"), .count = 1,
               .loc = {.file = "scene.pbrt", .line = 6, .column = 2}};
    p.strs = malloc(sizeof *p.strs);
    assert_non_null(p.strs);
    p.strs[0] = dup("fisheye");
    hz_error err;
    assert_int_equal(params_add(&f.e.entity.params, p, &err), HZ_OK);
    expect_error(&f, film_of(10, 10),
                 "scene.pbrt:6:2: \"mapping\" must be \"equalarea\" or \"equirectangular\", "
                 "got \"fisheye\"");
}

static void test_illegal_values_name_their_place(void **state)
{
    (void)state;
    struct {
        const char *name;
        double value;
        const char *want;
    } cases[] = {
        {"fov", 0, "scene.pbrt:12:9: \"fov\" must be in (0, 180) degrees, got 0"},
        {"fov", 180, "scene.pbrt:12:9: \"fov\" must be in (0, 180) degrees, got 180"},
        {"fov", -3, "scene.pbrt:12:9: \"fov\" must be in (0, 180) degrees, got -3"},
        {"fov", INFINITY, "scene.pbrt:12:9: \"fov\" must be in (0, 180) degrees, got inf"},
        {"lensradius", -0.5, "scene.pbrt:12:9: \"lensradius\" must be in [0, 1e+16], got -0.5"},
        {"focaldistance", 0, "scene.pbrt:12:9: \"focaldistance\" must be finite and > 0, got 0"},
        {"focaldistance", -2, "scene.pbrt:12:9: \"focaldistance\" must be finite and > 0, got -2"},
        {"focaldistance", NAN,
         "scene.pbrt:12:9: \"focaldistance\" must be finite and > 0, got nan"},
        {"frameaspectratio", 0,
         "scene.pbrt:12:9: \"frameaspectratio\" must be finite and > 0, got 0"},
        {"shutteropen", 2, "scene.pbrt:12:9: \"shutteropen\" 2 is after \"shutterclose\" 1"},
        {"bladerotation", NAN, "scene.pbrt:12:9: \"bladerotation\" must be finite, got nan"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        fixture f;
        fixture_init(&f, "perspective");
        add_float(&f, cases[i].name, 12, 9, cases[i].value);
        expect_error(&f, film_of(32, 32), cases[i].want);
    }
    const int bad_blades[] = {1, 2, -1};
    for (size_t i = 0; i < 3; ++i) {
        fixture f;
        fixture_init(&f, "orthographic");
        add_int(&f, "blades", 14, 3, bad_blades[i]);
        char want[200];
        snprintf(want, sizeof want,
                 "scene.pbrt:14:3: \"blades\" must be 0 (round aperture) or at least 3, got %d",
                 bad_blades[i]);
        expect_error(&f, film_of(32, 32), want);
    }
}

static void test_screen_window_errors(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "orthographic");
    add_nums(&f, PARAM_FLOAT, "screenwindow", 9, 5, 3, (const double[]){-1, 1, 0});
    expect_error(&f, film_of(32, 32),
                 "scene.pbrt:9:5: \"screenwindow\" takes four values (xmin xmax ymin ymax), got 3");
    fixture_init(&f, "orthographic");
    add_nums(&f, PARAM_FLOAT, "screenwindow", 9, 5, 4, (const double[]){1, 1, -1, 1});
    expect_error(&f, film_of(32, 32),
                 "scene.pbrt:9:5: \"screenwindow\" [1 1 -1 1] has an empty extent (need xmin < "
                 "xmax and ymin < ymax)");
    fixture_init(&f, "perspective");
    add_nums(&f, PARAM_FLOAT, "screenwindow", 9, 5, 4, (const double[]){-1, 1, 1, -1});
    expect_error(&f, film_of(32, 32),
                 "scene.pbrt:9:5: \"screenwindow\" [-1 1 1 -1] has an empty extent (need xmin < "
                 "xmax and ymin < ymax)");
}

static void test_unknown_and_mistyped_parameters(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "perspective");
    add_float(&f, "fvo", 4, 9, 40);
    expect_error(&f, film_of(32, 32),
                 "scene.pbrt:4:9: unused parameter \"float fvo\" for Camera \"perspective\"");
    /* pbrt-v4 dropped pbrt-v3's "halffov". */
    fixture_init(&f, "perspective");
    add_float(&f, "halffov", 4, 9, 20);
    expect_error(&f, film_of(32, 32),
                 "scene.pbrt:4:9: unused parameter \"float halffov\" for Camera \"perspective\"");
    /* An orthographic camera has no field of view. */
    fixture_init(&f, "orthographic");
    add_float(&f, "fov", 4, 9, 20);
    expect_error(&f, film_of(32, 32),
                 "scene.pbrt:4:9: unused parameter \"float fov\" for Camera \"orthographic\"");
    /* Types are strict, as in pbrt-v4; the message is the param module's. */
    fixture_init(&f, "perspective");
    add_int(&f, "fov", 4, 9, 20);
    camera c;
    hz_error err = {0};
    film_params fp = film_of(32, 32);
    assert_int_equal(camera_create(&f.e, &fp, &c, &err), HZ_ERROR);
    if (!strstr(err.message, "scene.pbrt:4:9: ") || !strstr(err.message, "fov"))
        fail_msg("unexpected message \"%s\"", err.message);
    params_free(&f.e.entity.params);
}

static void test_created_camera_makes_rays(void **state)
{
    (void)state;
    fixture f;
    fixture_init(&f, "perspective");
    add_float(&f, "fov", 4, 5, 60);
    transform cfw;
    assert_true(transform_look_at(v3(5e6, 0, 0), v3(5e6, 0, 10), v3(0, 1, 0), &cfw));
    f.e.camera_from_world = cfw;
    f.e.camera_from_world_end = cfw;
    camera c = create_ok(&f, film_of(100, 50));
    ray r;
    assert_true(camera_generate_ray(&c, (camera_sample){v2(50, 0), v2(0.5, 0.5), 0.5, 1}, &r));
    assert_near(r.o.x, 0, 0);
    assert_near(atan2(r.d.y, r.d.z) * 180 / HZ_PI, 30, 1e-9);
}

/* Through the real parser: the places are those of the scene text. */
static hz_status create_from_text(const char *text, int xres, int yres, camera *c, hz_error *err)
{
    scene_desc sd;
    if (scene_parse_string(text, "t.pbrt", &sd, err) != HZ_OK)
        fail_msg("parse: %s", err->message);
    film_params fp = film_of(xres, yres);
    hz_status st = camera_create(&sd.camera, &fp, c, err);
    scene_desc_free(&sd);
    return st;
}

/* The centre ray of a 10x10 film at shutter sample u (time = lerp(u, open, close)). */
static ray centre_ray_at(const camera *c, double u)
{
    ray r;
    assert_true(camera_generate_ray(c, (camera_sample){v2(5, 5), v2(0.5, 0.5), u, 1}, &r));
    return r;
}

/* pbrt-v4's animated camera: camera_from_world at the start and end of
 * TransformTimes, interpolated (translation lerped, rotation slerped); render
 * space centred on the camera at the middle of the transform times. */
static void test_animated_camera(void **state)
{
    (void)state;
    camera c;
    hz_error err = {0};
    /* camera_from_world_end = Translate(1,0,0): the camera moves from x = 0 to -1. */
    assert_int_equal(create_from_text("ActiveTransform EndTime\nTranslate 1 0 0\n"
                                      "ActiveTransform All\nCamera \"perspective\"\n"
                                      "WorldBegin\n",
                                      10, 10, &c, &err),
                     HZ_OK);
    assert_true(c.motion);
    assert_v3_near(transform_point(&c.world_from_render, v3(0, 0, 0)), v3(-0.5, 0, 0), 1e-15);
    for (int i = 0; i <= 4; ++i) {
        double u = i / 4.0;
        ray r = centre_ray_at(&c, u);
        assert_true(r.time == u);
        /* world x of the origin = -u; render = world + 0.5 */
        assert_v3_near(r.o, v3(0.5 - u, 0, 0), 1e-12);
        assert_v3_near(r.d, v3(0, 0, 1), 1e-12);
    }

    /* A shutter wider than the transform times holds the end transforms. */
    assert_int_equal(create_from_text("TransformTimes 0.25 0.75\n"
                                      "ActiveTransform EndTime\nTranslate 1 0 0\n"
                                      "ActiveTransform All\nCamera \"perspective\"\n"
                                      "WorldBegin\n",
                                      10, 10, &c, &err),
                     HZ_OK);
    assert_v3_near(centre_ray_at(&c, 0.0).o, v3(0.5, 0, 0), 1e-12);
    assert_v3_near(centre_ray_at(&c, 0.1).o, v3(0.5, 0, 0), 1e-12);
    assert_v3_near(centre_ray_at(&c, 0.5).o, v3(0, 0, 0), 1e-12);
    assert_v3_near(centre_ray_at(&c, 0.625).o, v3(-0.25, 0, 0), 1e-12);
    assert_v3_near(centre_ray_at(&c, 0.9).o, v3(-0.5, 0, 0), 1e-12);

    /* A 90 degree turn about y is slerped: 45 degrees at mid-shutter, and the
     * view direction keeps unit length all along (a matrix lerp would not). */
    assert_int_equal(create_from_text("ActiveTransform EndTime\nRotate 90 0 1 0\n"
                                      "ActiveTransform All\nCamera \"perspective\"\n"
                                      "WorldBegin\n",
                                      10, 10, &c, &err),
                     HZ_OK);
    for (int i = 0; i <= 8; ++i) {
        double u = i / 8.0;
        ray r = centre_ray_at(&c, u);
        /* world_from_camera_end = Rotate(-90, y): +z turns to -x. */
        double a = -HZ_PI / 2 * u;
        assert_v3_near(r.d, v3(sin(a), 0, cos(a)), 1e-12);
        assert_v3_near(r.o, v3(0, 0, 0), 1e-12);
    }

    /* Equal keyframes: a static camera, bit for bit the plain one. */
    camera s;
    assert_int_equal(create_from_text("LookAt 1 2 3  0 0 0  0 1 0\nCamera \"perspective\"\n"
                                      "WorldBegin\n",
                                      10, 10, &s, &err),
                     HZ_OK);
    assert_int_equal(create_from_text("LookAt 1 2 3  0 0 0  0 1 0\nActiveTransform EndTime\n"
                                      "ActiveTransform All\nCamera \"perspective\"\n"
                                      "WorldBegin\n",
                                      10, 10, &c, &err),
                     HZ_OK);
    assert_false(c.motion);
    ray ra = centre_ray_at(&s, 0.3), rb = centre_ray_at(&c, 0.3);
    assert_memory_equal(&ra, &rb, sizeof ra);

    /* TransformTimes must increase. */
    scene_desc sd;
    assert_int_equal(scene_parse_string("TransformTimes 1 0\nWorldBegin\n", "t.pbrt", &sd, &err),
                     HZ_ERROR);
    assert_non_null(strstr(err.message, "t.pbrt:1:1: TransformTimes 1 0"));
}

static void test_from_scene_text(void **state)
{
    (void)state;
    camera c;
    hz_error err = {0};
    assert_int_equal(create_from_text("LookAt 0 0 -5  0 0 0  0 1 0\n"
                                      "Camera \"perspective\"\n"
                                      "  \"float fov\" [ 0 ]\n"
                                      "WorldBegin\n",
                                      10, 10, &c, &err),
                     HZ_ERROR);
    assert_string_equal(err.message, "t.pbrt:3:3: \"fov\" must be in (0, 180) degrees, got 0");

    assert_int_equal(create_from_text("Camera \"realistic\" \"string lensfile\" \"x.dat\"\n"
                                      "WorldBegin\n",
                                      10, 10, &c, &err),
                     HZ_ERROR);
    assert_string_equal(err.message,
                        "t.pbrt:1:20: x.dat: cannot read the lens file: No such file or directory");
    /* An aperture that is no built-in shape is an image file, read relative
     * to the scene file; a missing or unsupported one names its place. */
    const char *lens = HAZE_TEST_DATA "/lenses/dgauss.50mm.dat";
    char text[1024];
    snprintf(text, sizeof text,
             "Camera \"realistic\" \"string lensfile\" \"%s\"\n"
             "  \"string aperture\" \"hexagon\"\nWorldBegin\n",
             lens);
    assert_int_equal(create_from_text(text, 10, 10, &c, &err), HZ_ERROR);
    assert_string_equal(err.message,
                        "t.pbrt:2:3: \"aperture\" \"hexagon\" is not a built-in shape "
                        "(\"gaussian\", \"square\", \"pentagon\", \"star\") nor a .png or "
                        ".exr image");
    snprintf(text, sizeof text,
             "Camera \"realistic\" \"string lensfile\" \"%s\"\n"
             "  \"string aperture\" \"no-such-aperture.png\"\nWorldBegin\n",
             lens);
    assert_int_equal(create_from_text(text, 10, 10, &c, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "t.pbrt:2:3: cannot read PNG"));
    snprintf(text, sizeof text,
             "Camera \"realistic\" \"string lensfile\" \"%s\"\n"
             "  \"string aperture\" \"star\" \"float aperturediameter\" 8\nWorldBegin\n",
             lens);
    if (create_from_text(text, 10, 10, &c, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(c.realistic.shape, APERTURE_STAR);
    camera_free(&c);

    assert_int_equal(create_from_text("Camera \"orthographic\" \"float lensradius\" 0.5\n"
                                      "    \"float focaldistance\" -1\nWorldBegin\n",
                                      10, 10, &c, &err),
                     HZ_ERROR);
    assert_string_equal(err.message,
                        "t.pbrt:2:5: \"focaldistance\" must be finite and > 0, got -1");


    /* A LookAt camera far from the origin, with a physical lens. */
    assert_int_equal(create_from_text("LookAt 1e7 0 0  1e7 0 1  0 1 0\n"
                                      "Camera \"perspective\" \"float focallength\" 50\n"
                                      "  \"float fstop\" 4 \"integer blades\" 6\n"
                                      "WorldBegin\n",
                                      300, 200, &c, &err),
                     HZ_OK);
    assert_near(c.fov, 2 * atan(12.0 / 50.0) * 180 / HZ_PI, 1e-12);
    assert_near(c.lens_radius, 0.00625, 1e-16);
    assert_int_equal(c.blades, 6);
    assert_near(transform_point(&c.world_from_render, v3(0, 0, 0)).x, 1e7, 0);
    ray r;
    camera_generate_ray(&c, (camera_sample){v2(150, 100), v2(0.5, 0.5), 0.5, 1}, &r);
    /* Through the image centre: the lens ray starts on the hexagon and aims at
     * the optical axis at the default focal distance 1e6. */
    assert_true(hypot(r.o.x, r.o.y) <= 0.00625 * (1 + 1e-12));
    assert_near(r.o.z, 0, 1e-12);
    vec3 focus = ray_at(&r, (1e6 - r.o.z) / r.d.z);
    assert_near(focus.x, 0, 1e-6);
    assert_near(focus.y, 0, 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_are_pbrt_v4s),
        cmocka_unit_test(test_every_parameter_is_read),
        cmocka_unit_test(test_frame_aspect_ratio),
        cmocka_unit_test(test_physical_lens),
        cmocka_unit_test(test_physical_lens_errors),
        cmocka_unit_test(test_unsupported_type),
        cmocka_unit_test(test_spherical_directions),
        cmocka_unit_test(test_spherical_refusals),
        cmocka_unit_test(test_illegal_values_name_their_place),
        cmocka_unit_test(test_screen_window_errors),
        cmocka_unit_test(test_unknown_and_mistyped_parameters),
        cmocka_unit_test(test_created_camera_makes_rays),
        cmocka_unit_test(test_from_scene_text),
        cmocka_unit_test(test_animated_camera),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
