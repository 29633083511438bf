/* Tiles whose camera rays hit nothing skip the integrator
 * (render_scene_black_outside, camera_raster_bounds): outside the raster
 * rectangle it gives, no camera ray meets a shape, for perspective and
 * orthographic cameras; the rectangle holds the image of the box it bounds;
 * and it is refused wherever a ray that hits nothing could bring light or
 * the box has no bounded image. */
#include "media_test_util.h"

#include "core/rng.h"

/* Camera rays through random raster points over twice the image: none
 * outside the rectangle hits a shape, and some inside it do. */
static void check_rays_outside_miss(const char *text, int xres, int yres)
{
    render_scene *rs = build(text);
    double b[4];
    assert_true(render_scene_black_outside(rs, b));
    assert_true(b[0] <= b[1] && b[2] <= b[3]);
    const camera *cam = render_scene_camera(rs);
    const geometry *g = render_scene_geometry(rs);
    rng r = rng_seeded(3);
    int outside = 0, hits_inside = 0;
    for (int i = 0; i < 40000; ++i) {
        camera_sample cs = {.p_film = v2((2.0 * rng_uniform(&r) - 0.5) * xres,
                                         (2.0 * rng_uniform(&r) - 0.5) * yres),
                            .p_lens = v2(0.5, 0.5),
                            .time = 0.5,
                            .filter_weight = 1.0};
        ray ry;
        if (!camera_generate_ray(cam, cs, &ry))
            continue;
        geom_hit h;
        bool hit = geometry_intersect(g, ry.o, ry.d, 0.0, INFINITY, 0.0, &h);
        bool out = cs.p_film.x < b[0] || cs.p_film.x > b[1] || cs.p_film.y < b[2] ||
                   cs.p_film.y > b[3];
        if (out && hit)
            fail_msg("ray through %g %g, outside [%g %g] x [%g %g], hits", cs.p_film.x,
                     cs.p_film.y, b[0], b[1], b[2], b[3]);
        outside += out;
        hits_inside += !out && hit;
    }
    assert_true(outside > 10000);
    assert_true(hits_inside > 1000);
    render_scene_destroy(rs);
}

static const char *const shapes =
    "WorldBegin\n"
    "LightSource \"distant\" \"point3 from\" [0 4 1] \"point3 to\" [0 0 0]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-1 -1 0.5  1.2 -1 0.7  1 0.8 0.4  -1 1 0.5]\n"
    "AttributeBegin\nTranslate 0.6 0.3 -0.2\nShape \"sphere\" \"float radius\" 0.4\n"
    "AttributeEnd\n";

static void test_perspective_rays_outside_miss(void **state)
{
    (void)state;
    char *text = sfmt("LookAt 0.4 0.9 -4  0.1 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
                      "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 48\n%s",
                      shapes);
    check_rays_outside_miss(text, 64, 48);
    free(text);
}

static void test_orthographic_rays_outside_miss(void **state)
{
    (void)state;
    char *text = sfmt("LookAt -0.5 0.9 -4  0.1 0 0  0 1 0\nCamera \"orthographic\" "
                      "\"float screenwindow\" [-3 3 -2 2]\n"
                      "Film \"rgb\" \"integer xresolution\" 60 \"integer yresolution\" 40\n%s",
                      shapes);
    check_rays_outside_miss(text, 60, 40);
    free(text);
}

/* The rectangle holds the image of the box's centre, and a scene without
 * shapes is black everywhere (an empty rectangle). */
static void test_rectangle_and_empty_scene(void **state)
{
    (void)state;
    render_scene *rs = build("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n"
                             "Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 100\n"
                             "WorldBegin\nShape \"sphere\" \"float radius\" 0.5\n");
    double b[4];
    assert_true(render_scene_black_outside(rs, b));
    /* The sphere at the image's centre: the rectangle straddles pixel 50. */
    assert_true(b[0] < 50.0 && b[1] > 50.0 && b[2] < 50.0 && b[3] > 50.0);
    assert_true(b[1] - b[0] < 60.0);
    render_scene_destroy(rs);
    rs = build("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
               "LightSource \"distant\" \"point3 from\" [0 4 1] \"point3 to\" [0 0 0]\n");
    assert_true(render_scene_black_outside(rs, b));
    assert_true(b[0] > b[1] && b[2] > b[3]);
    render_scene_destroy(rs);
}

/* Whether the camera ray through raster point (x, y) hits a shape. */
static bool ray_hits(const camera *cam, const geometry *g, double x, double y)
{
    camera_sample cs = {.p_film = v2(x, y), .p_lens = v2(0.5, 0.5), .time = 0.5,
                        .filter_weight = 1.0};
    ray ry;
    geom_hit h;
    return camera_generate_ray(cam, cs, &ry) &&
           geometry_intersect(g, ry.o, ry.d, 0.0, INFINITY, 0.0, &h);
}

/* The rectangle is tight around an axis-aligned box mesh seen in perspective: its
 * corners project onto the rectangle's sides, so along each side rays a
 * quarter pixel inside hit it somewhere, and rays a quarter pixel outside
 * never do (scanned every 0.01 pixel). A rectangle 2 pixels too small or
 * too large fails. */
static void test_rectangle_tight(void **state)
{
    (void)state;
    render_scene *rs =
        build("LookAt 0.7 1.1 -4  0.2 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
              "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 48\n"
              "WorldBegin\nTranslate 0.3 -0.2 0.4\n"
              "Shape \"trianglemesh\" \"integer indices\" [0 6 2  0 4 6  1 3 7  1 7 5  0 1 5  "
              "0 5 4  2 7 3  2 6 7  0 3 1  0 2 3  4 5 7  4 7 6]\n"
              "  \"point3 P\" [-0.6 -0.4 -0.5  0.6 -0.4 -0.5  -0.6 0.4 -0.5  0.6 0.4 -0.5  "
              "-0.6 -0.4 0.5  0.6 -0.4 0.5  -0.6 0.4 0.5  0.6 0.4 0.5]\n");
    double b[4];
    assert_true(render_scene_black_outside(rs, b));
    const camera *cam = render_scene_camera(rs);
    const geometry *g = render_scene_geometry(rs);
    assert_true(b[0] > 1.0 && b[1] < 63.0 && b[2] > 1.0 && b[3] < 47.0);
    for (int side = 0; side < 4; ++side) {
        bool vertical = side < 2; /* x = b[side], scanning y */
        double at = b[side], dir = side % 2 ? -1.0 : 1.0; /* inward */
        double lo = vertical ? b[2] : b[0], hi = vertical ? b[3] : b[1];
        int inside = 0;
        for (double u = lo; u <= hi; u += 0.01) {
            double xi = vertical ? at + 0.25 * dir : u, yi = vertical ? u : at + 0.25 * dir;
            double xo = vertical ? at - 0.25 * dir : u, yo = vertical ? u : at - 0.25 * dir;
            inside += ray_hits(cam, g, xi, yi);
            if (ray_hits(cam, g, xo, yo))
                fail_msg("side %d: the ray through %g %g, outside [%g %g] x [%g %g], hits", side,
                         xo, yo, b[0], b[1], b[2], b[3]);
        }
        if (inside == 0)
            fail_msg("side %d: no ray a quarter pixel inside [%g %g] x [%g %g] hits", side, b[0],
                     b[1], b[2], b[3]);
    }
    render_scene_destroy(rs);
}

/* Refused: light from the sky, a camera inside a medium, a lens, a shape
 * around the camera (part of it behind the eye) and a moving shape. */
static void test_refused(void **state)
{
    (void)state;
    const char *const scenes[] = {
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
        "LightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\nShape \"sphere\"\n",
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\nMediumInterface \"\" \"fog\"\n"
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nShape \"sphere\"\n",
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float lensradius\" 0.1\n"
        "WorldBegin\nShape \"sphere\"\n",
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
        "  \"point3 P\" [-20 -1 -20  20 -1 -20  20 -1 20  -20 -1 20]\n",
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
        "ActiveTransform EndTime\nTranslate 0.5 0 0\nActiveTransform All\nShape \"sphere\"\n",
    };
    for (size_t i = 0; i < sizeof scenes / sizeof *scenes; ++i) {
        render_scene *rs = build(scenes[i]);
        double b[4];
        if (render_scene_black_outside(rs, b))
            fail_msg("scene %zu: accepted", i);
        render_scene_destroy(rs);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_perspective_rays_outside_miss),
        cmocka_unit_test(test_orthographic_rays_outside_miss),
        cmocka_unit_test(test_rectangle_and_empty_scene),
        cmocka_unit_test(test_rectangle_tight),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
