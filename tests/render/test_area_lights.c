/* Diffuse area lights' "power" and "filename", as pbrt-v4 defines them.
 * "power": the radiance is
 * scale * L * power / (A π), A the Area() of one emitter (doubled when
 * two-sided): the analytic shape's in object space (sphere, disk, cylinder),
 * each triangle's (bilinearmesh: quad's) of a mesh. Seen straight on by an
 * orthographic camera, a pixel on the emitter is that radiance exactly. */
#include "render_test_util.h"

#include <unistd.h>

#include "film/exr.h"

static const char *camera_down = "LookAt 0 0 5  0 0 0  0 1 0\n"
                                 "Camera \"orthographic\"\n"
                                 "Film \"rgb\" \"integer xresolution\" 32 "
                                 "\"integer yresolution\" 32\n"
                                 "WorldBegin\n";

/* The radiance seen through pixel (x, y) of a scene of camera_down and
 * `world`; the screen window [-1, 1]^2 spans the 32 pixels. */
static rgb seen_at(const char *world, double x, double y)
{
    char *text = cat(camera_down, world, "");
    render_scene *rs = build_scene_or_fail(text, NULL);
    pixel_eval e = eval_pixel(rs, x, y, 1);
    assert_true(e.hit);
    render_scene_destroy(rs);
    free(text);
    return e.L;
}

/* The pixel over world (wx, wy) sees radiance `want` (relative tolerance). */
static void expect_seen(const char *world, double wx, double wy, rgb want, double rel,
                        const char *what)
{
    /* pbrt-v4's LookAt down -z with y up: camera x is world -x. */
    double x = 16.0 - 16.0 * wx, y = 16.0 - 16.0 * wy;
    expect_rgb_close(seen_at(world, x, y), want, rel, 0.0, what, x, y);
}

static void test_quad_one_and_two_sided(void **state)
{
    (void)state;
    /* Two triangles of area 2 each, facing +z (the camera). */
    const char *quad = "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] "
                       "\"integer indices\" [0 1 2 0 2 3]\n";
    char world[512];
    snprintf(world, sizeof world,
             "AreaLightSource \"diffuse\" \"rgb L\" [0.5 1 2] \"float power\" 8\n%s", quad);
    double k = 8.0 / (2.0 * HZ_PI);
    expect_seen(world, 0.3, -0.4, (rgb){0.5 * k, k, 2 * k, k}, 1e-6,
                     "one-sided quad");
    snprintf(world, sizeof world,
             "AreaLightSource \"diffuse\" \"rgb L\" [0.5 1 2] \"float power\" 8 "
             "\"bool twosided\" true \"float scale\" 3\n%s", quad);
    expect_seen(world, 0.3, -0.4,
                     (rgb){1.5 * k / 2, 3 * k / 2, 6 * k / 2, 3 * k / 2}, 1e-6, "two-sided quad");
    /* A bilinear patch is one emitter of area 4. */
    snprintf(world, sizeof world,
             "AreaLightSource \"diffuse\" \"float power\" 8\n"
             "Shape \"bilinearmesh\" \"point3 P\" [-1 -1 0 1 -1 0 -1 1 0 1 1 0] "
             "\"integer indices\" [0 1 2 3]\n");
    expect_seen(world, -0.5, 0.5, rgb_grey(8.0 / (4.0 * HZ_PI)), 1e-6,
                     "bilinear patch");
}

static void test_analytic_shapes(void **state)
{
    (void)state;
    /* Annulus 0.5 < r < 1: A = π (1 - 0.25). */
    const char *disk = "AreaLightSource \"diffuse\" \"float power\" 3\n"
                       "Shape \"disk\" \"float radius\" 1 \"float innerradius\" 0.5\n";
    expect_seen(disk, 0.75, 0.0, rgb_grey(3.0 / (0.75 * HZ_PI * HZ_PI)),
                     1e-6, "disk");
    /* Sphere of radius 0.5: A = π; scale multiplies. */
    const char *sphere = "AreaLightSource \"diffuse\" \"float power\" 5 \"float scale\" 2\n"
                         "Shape \"sphere\" \"float radius\" 0.5\n";
    expect_seen(sphere, 0.1, 0.1, rgb_grey(10.0 / (HZ_PI * HZ_PI)), 1e-6,
                     "sphere");
    /* A cylinder of radius 0.25 and length 2 along x, seen from the side:
     * A = 2π r h = π; its area counts in object space, as pbrt-v4's. */
    const char *cyl = "AreaLightSource \"diffuse\" \"float power\" 4\n"
                      "Rotate 90 0 1 0\n"
                      "Shape \"cylinder\" \"float radius\" 0.25 \"float zmin\" -1 "
                      "\"float zmax\" 1\n";
    expect_seen(cyl, 0.2, 0.0, rgb_grey(4.0 / (HZ_PI * HZ_PI)), 1e-6,
                     "cylinder");
    /* "power" 0 or less is no power at all (pbrt-v4): L as given. */
    const char *off = "AreaLightSource \"diffuse\" \"float power\" 0 \"rgb L\" [2 2 2]\n"
                      "Shape \"sphere\" \"float radius\" 0.5\n";
    expect_seen(off, 0.1, 0.1, rgb_grey(2.0), 1e-9, "power 0");
}

/* What haze cannot give pbrt-v4's meaning is refused at the parameter. */
static void test_refused(void **state)
{
    (void)state;
    char msg[1024];
    char *text = cat(camera_down,
                     "AreaLightSource \"diffuse\" \"float power\" 8\n"
                     "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 0 0 1] "
                     "\"integer indices\" [0 1 2 0 1 3 0 2 3 1 2 3]\n",
                     "");
    /* Triangles of areas 0.5 and 0.866: each would have its own radiance. */
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:5:"));
    assert_non_null(strstr(msg, "differ in area (0.5 to 0.866"));
    free(text);
    text = cat("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\n"
               "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
               "WorldBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n",
               "AreaLightSource \"diffuse\" \"float power\" 8\n",
               "Shape \"sphere\"\n");
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "moving area light"));
    free(text);
}

/* "filename": the radiance is scale times the image, bilinear at (u, 1 - v)
 * of the emitter's surface. A 4x2 EXR on the quad [-1, 1]^2 (uv = (x + 1,
 * y + 1) / 2): at each texel's centre the pixel sees that texel exactly;
 * halfway between two texels, their mean. With "power", the image's mean
 * luminance takes the place of L's (pbrt-v4's k_e). */
static void test_image_emitter(void **state)
{
    (void)state;
    static const float texels[8][3] = {{4, 0.5, 0.5}, {0.5, 4, 0.5}, {0.5, 0.5, 4}, {2, 2, 2},
                                       {1, 1, 0.2},   {0.2, 1, 1},   {1, 0.2, 1},   {3, 1, 0.5}};
    char path[512];
    snprintf(path, sizeof path, "%s/area_image-%ld.exr", HAZE_TMP, (long)getpid());
    exr_image img;
    hz_error err;
    assert_int_equal(exr_image_alloc(&img, 4, 2, 3, &err), HZ_OK);
    const char *names[3] = {"R", "G", "B"};
    double lum = 0.0;
    for (int c = 0; c < 3; ++c) {
        snprintf(img.channels[c].name, sizeof img.channels[c].name, "%s", names[c]);
        for (int i = 0; i < 8; ++i)
            img.channels[c].pixels[i] = texels[i][c];
    }
    for (int i = 0; i < 8; ++i)
        lum += (0.2126 * texels[i][0] + 0.7152 * texels[i][1] + 0.0722 * texels[i][2]) / 8.0;
    assert_int_equal(exr_write(path, &img, &err), HZ_OK);
    exr_image_free(&img);
    char world[1024];
    const char *quad = "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] "
                       "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n";
    snprintf(world, sizeof world,
             "AreaLightSource \"diffuse\" \"string filename\" \"%s\" \"float scale\" 2\n%s",
             path, quad);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 4; ++i) {
            /* Texel (i, j) centre: (u, 1 - v) = ((i + 0.5) / 4, (j + 0.5) / 2). */
            double u = (i + 0.5) / 4.0, v = 1.0 - (j + 0.5) / 2.0;
            const float *t = texels[j * 4 + i];
            expect_seen(world, 2.0 * u - 1.0, 2.0 * v - 1.0,
                        rgb_make(2.0 * t[0], 2.0 * t[1], 2.0 * t[2]), 1e-5, "texel centre");
        }
    /* Between texels (0, 0) and (1, 0): their mean. */
    expect_seen(world, 2.0 * 0.25 - 1.0, 2.0 * 0.75 - 1.0,
                rgb_make(4.5, 4.5, 1.0), 1e-5, "between texels");
    snprintf(world, sizeof world,
             "AreaLightSource \"diffuse\" \"string filename\" \"%s\" \"float power\" 6\n%s",
             path, quad);
    double k = 6.0 / (2.0 * HZ_PI * lum); /* each triangle: area 2 */
    expect_seen(world, 2.0 * 0.625 - 1.0, 2.0 * 0.75 - 1.0,
                rgb_make(0.5 * k, 0.5 * k, 4.0 * k), 1e-5, "power over the image");
    char msg[1024];
    char *text = cat("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\nWorldBegin\n",
                     "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"string filename\" \"x.exr\"\n",
                     quad);
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "\"L\" and \"filename\" cannot both be given"));
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quad_one_and_two_sided),
        cmocka_unit_test(test_analytic_shapes),
        cmocka_unit_test(test_refused),
        cmocka_unit_test(test_image_emitter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
