/* The extremes suite: scenes at the limits of the camera and film parameters,
 * each with an assertion on the image, not just "it ran". Every image must be
 * finite everywhere (the film counts non-finite samples; none are allowed).
 *
 * Most cases use one of two invariants with exact answers:
 *   SKY     no shapes, an infinite light L: every ray escapes, every pixel is L;
 *   INSIDE  the camera inside a two-sided emitting sphere of radius 1e4: every
 *           ray hits it, every pixel is L;
 * whatever the camera does to its rays. Far-from-origin cases compare a room
 * scene translated by 1e7 and 1e12 units with the same scene at the origin. */
#define _POSIX_C_SOURCE 200809L
#include "render/render_test_util.h"

#include "render/renderer.h"

#define L_R 0.25
#define L_G 0.5
#define L_B 1.0

static const char film_8x6[] =
    "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 6\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 4\n";
static const char world_sky[] = "WorldBegin\nLightSource \"infinite\" \"rgb L\" [0.25 0.5 1]\n";
static const char world_inside[] =
    "WorldBegin\n"
    "AreaLightSource \"diffuse\" \"rgb L\" [0.25 0.5 1] \"bool twosided\" true\n"
    "Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n" /* no light reflected inside */
    "Shape \"sphere\" \"float radius\" 1e4\n";

typedef struct {
    render_scene *rs;
    int w, h;
    double ratio;
} rendered;

static rendered render_text(const char *text)
{
    rendered r;
    r.rs = build_scene_or_fail(text, NULL);
    render_expect_finite(r.rs);
    film *f = render_scene_film(r.rs);
    const film_params *fp = film_get_params(f);
    r.w = fp->bounds.x1 - fp->bounds.x0;
    r.h = fp->bounds.y1 - fp->bounds.y0;
    r.ratio = camera_imaging_ratio(render_scene_camera(r.rs), fp);
    return r;
}

static rgb pixel(const rendered *r, int x, int y)
{
    film *f = render_scene_film(r->rs);
    const film_params *fp = film_get_params(f);
    return film_get_pixel(f, fp->bounds.x0 + x, fp->bounds.y0 + y, r->ratio);
}

/* Every pixel equals `want` within `rel`. */
static void expect_uniform(const char *name, const rendered *r, rgb want, double rel)
{
    for (int y = 0; y < r->h; ++y)
        for (int x = 0; x < r->w; ++x) {
            rgb v = pixel(r, x, y);
            if (!(isfinite(v.r) && isfinite(v.g) && isfinite(v.b)))
                fail_msg("%s: pixel (%d, %d) is not finite", name, x, y);
            expect_rgb_close(v, want, rel, 1e-300, name, x, y);
        }
}

typedef struct {
    const char *name;
    const char *camera; /* Camera directive (and anything before it) */
    const char *film;   /* NULL: 8x6, 4 spp */
    int world_inside;   /* INSIDE instead of SKY */
    double exposure;    /* expected imaging ratio */
} uniform_case;

static const uniform_case uniform_cases[] = {
    {"fov 1e-4", "Camera \"perspective\" \"float fov\" 1e-4\n", NULL, 1, 1.0},
    {"fov 179.99", "Camera \"perspective\" \"float fov\" 179.99\n", NULL, 1, 1.0},
    {"fov 179.99 sky", "Camera \"perspective\" \"float fov\" 179.99\n", NULL, 0, 1.0},
    {"lens radius 0", "Camera \"perspective\" \"float lensradius\" 0 \"float focaldistance\" 3\n",
     NULL, 1, 1.0},
    {"lens radius 1e-12",
     "Camera \"perspective\" \"float lensradius\" 1e-12 \"float focaldistance\" 3\n", NULL, 1,
     1.0},
    {"lens radius 1e3",
     "Camera \"perspective\" \"float lensradius\" 1e3 \"float focaldistance\" 10\n", NULL, 1, 1.0},
    {"lens radius 1e3 sky",
     "Camera \"perspective\" \"float lensradius\" 1e3 \"float focaldistance\" 10\n", NULL, 0, 1.0},
    {"focal distance 1e-6",
     "Camera \"perspective\" \"float lensradius\" 0.1 \"float focaldistance\" 1e-6\n", NULL, 1,
     1.0},
    {"focal distance 1e12",
     "Camera \"perspective\" \"float lensradius\" 0.1 \"float focaldistance\" 1e12\n", NULL, 1,
     1.0},
    {"orthographic tiny window",
     "Camera \"orthographic\" \"float screenwindow\" [-1e-9 1e-9 -1e-9 1e-9]\n", NULL, 1, 1.0},
    {"orthographic wide window",
     "Camera \"orthographic\" \"float screenwindow\" [-1e3 1e3 -1e3 1e3]\n", NULL, 1, 1.0},
    {"orthographic thin lens 1e3",
     "Camera \"orthographic\" \"float lensradius\" 1e3 \"float focaldistance\" 1e-6\n", NULL, 1,
     1.0},
    {"film 1x1", "Camera \"perspective\"\n",
     "Film \"rgb\" \"integer xresolution\" 1 \"integer yresolution\" 1\n", 1, 1.0},
    {"film 16384x1", "Camera \"perspective\"\n",
     "Film \"rgb\" \"integer xresolution\" 16384 \"integer yresolution\" 1\n"
     "Sampler \"zsobol\" \"integer pixelsamples\" 1\n",
     0, 1.0},
    {"film 1x16384 orthographic", "Camera \"orthographic\"\n",
     "Film \"rgb\" \"integer xresolution\" 1 \"integer yresolution\" 16384\n"
     "Sampler \"zsobol\" \"integer pixelsamples\" 1\n",
     0, 1.0}, /* its screen window reaches y = +-16384, outside the sphere */
    {"shutter 1e9 long", "Camera \"perspective\" \"float shutterclose\" 1e9\n", NULL, 1, 1e9},
    {"shutter 1e9 long, moving camera",
     "TransformTimes 0 1e9\nActiveTransform EndTime\nTranslate 1e3 0 0\nActiveTransform All\n"
     "Camera \"perspective\" \"float shutterclose\" 1e9\n",
     NULL, 1, 1e9},
    {"zero-length shutter",
     "Camera \"perspective\" \"float shutteropen\" 0.5 \"float shutterclose\" 0.5\n", NULL, 1,
     0.0},
};

static void test_uniform_invariants(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof uniform_cases / sizeof uniform_cases[0]; ++i) {
        const uniform_case *c = &uniform_cases[i];
        char *head = cat(c->camera, c->film ? c->film : film_8x6, "");
        char *text = cat(head, c->world_inside ? world_inside : world_sky, "");
        rendered r = render_text(text);
        rgb want = rgb_scale(rgb_make(L_R, L_G, L_B), c->exposure);
        /* Emission and the sky are exact; the only error is float rounding. */
        expect_uniform(c->name, &r, want, 1e-6);
        print_message("%-34s %dx%d pixels = (%g, %g, %g)\n", c->name, r.w, r.h, want.r, want.g,
                      want.b);
        render_scene_destroy(r.rs);
        free(text);
        free(head);
    }
}

/* A lit room with the camera in it, the whole scene (camera included)
 * translated by `offset` along every axis. */
static char *room_at(double offset)
{
    char buf[4096];
    snprintf(buf, sizeof buf,
             "LookAt 0 1.5 -4  0 1 0  0 1 0\n"
             "Translate %.17g %.17g %.17g\n"
             "Camera \"perspective\" \"float fov\" 50\n"
             "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
             "WorldBegin\n"
             "Translate %.17g %.17g %.17g\n"
             "LightSource \"point\" \"point3 from\" [1 2.5 -1] \"rgb I\" [6 6 6]\n"
             "AttributeBegin\n"
             "  AreaLightSource \"diffuse\" \"rgb L\" [4 3 2]\n"
             "  Translate -1 2 1\n"
             "  Shape \"sphere\" \"float radius\" 0.3\n"
             "AttributeEnd\n"
             "Material \"diffuse\" \"rgb reflectance\" [0.6 0.6 0.6]\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "  \"point3 P\" [-5 0 -5  5 0 -5  5 0 5  -5 0 5]\n"
             "AttributeBegin\n"
             "  Translate 0.5 0.7 0.5\n"
             "  Shape \"sphere\" \"float radius\" 0.7\n"
             "AttributeEnd\n",
             -offset, -offset, -offset, offset, offset, offset);
    return strdup(buf);
}

/* Mean and largest |a - b| over all pixels and channels, and the mean of a. */
static void compare_images(const rendered *a, const rendered *b, double *mean_abs,
                           double *max_abs, double *mean_a)
{
    assert_int_equal(a->w, b->w);
    assert_int_equal(a->h, b->h);
    double sum = 0.0, mx = 0.0, sa = 0.0;
    for (int y = 0; y < a->h; ++y)
        for (int x = 0; x < a->w; ++x) {
            rgb u = pixel(a, x, y), v = pixel(b, x, y);
            double d[3] = {fabs(u.r - v.r), fabs(u.g - v.g), fabs(u.b - v.b)};
            for (int k = 0; k < 3; ++k) {
                sum += d[k];
                mx = fmax(mx, d[k]);
            }
            sa += u.r + u.g + u.b;
        }
    double n = 3.0 * a->w * a->h;
    *mean_abs = sum / n;
    *max_abs = mx;
    *mean_a = sa / n;
}

/* Rendering happens in camera-centred space, so a scene far from the origin
 * keeps its precision up to what double world coordinates hold: at 1e7 the
 * positions round by 1e7 * 2^-53 ~ 1e-9 (the images agree to float rounding);
 * at 1e12 by ~1e-4 units, which moves silhouettes by a fraction of a pixel
 * in a few pixels. */
static void test_far_from_origin(void **state)
{
    (void)state;
    char *t0 = room_at(0.0);
    rendered r0 = render_text(t0);
    static const struct {
        double offset, mean_rel, max_abs;
    } cases[] = {{1e7, 1e-8, 1e-6}, {1e12, 1e-4, 1e-3}};
    for (size_t i = 0; i < 2; ++i) {
        char *t = room_at(cases[i].offset);
        rendered r = render_text(t);
        double mean_abs, max_abs, mean0;
        compare_images(&r, &r0, &mean_abs, &max_abs, &mean0);
        print_message("offset %.0e: mean |diff| %.3g (relative %.3g), max |diff| %.3g\n",
                      cases[i].offset, mean_abs, mean_abs / mean0, max_abs);
        assert_true(mean_abs / mean0 <= cases[i].mean_rel);
        assert_true(max_abs <= cases[i].max_abs);
        render_scene_destroy(r.rs);
        free(t);
    }
    render_scene_destroy(r0.rs);
    free(t0);
}

/* An emitter almost touching the lens, and rays grazing a plane that contains
 * the camera: finite, and the exact values where they are known. */
static void test_near_and_grazing(void **state)
{
    (void)state;
    /* Sphere of radius 1 whose surface is 1e-6 in front of the pinhole. */
    rendered r = render_text("Camera \"perspective\" \"float fov\" 30\n"
                             "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                             "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
                             "WorldBegin\n"
                             "AreaLightSource \"diffuse\" \"rgb L\" [0.25 0.5 1]\n"
                             "Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
                             "Translate 0 0 1.000001\n"
                             "Shape \"sphere\" \"float radius\" 1\n");
    /* Every ray of a 30-degree cone meets the sphere's near side. */
    expect_uniform("emitter 1e-6 from the lens", &r, rgb_make(L_R, L_G, L_B), 1e-6);
    render_scene_destroy(r.rs);

    /* The camera sits 1e-3 above the plane y = 0 (a millionth of its size)
     * and looks along it: the rays near the horizon graze it. The floor is
     * black and the sky uniform, so away from the horizon row (the filter
     * spreads samples 1.5 pixels) the values are exact. */
    rendered g = render_text("LookAt 0 1e-3 0  0 1e-3 1  0 1 0\n"
                             "Camera \"perspective\" \"float fov\" 60\n"
                             "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                             "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
                             "WorldBegin\n"
                             "LightSource \"infinite\" \"rgb L\" [0.25 0.5 1]\n"
                             "Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
                             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
                             "  \"point3 P\" [-1e3 0 -1e3  1e3 0 -1e3  1e3 0 1e3  -1e3 0 1e3]\n");
    /* A black floor: rows below the horizon are 0, rows above are the sky. */
    for (int y = 0; y < g.h; ++y)
        for (int x = 0; x < g.w; ++x) {
            rgb v = pixel(&g, x, y);
            assert_true(isfinite(v.r) && isfinite(v.g) && isfinite(v.b));
            if (y < g.h / 2 - 2)
                expect_rgb_close(v, rgb_make(L_R, L_G, L_B), 1e-6, 0.0, "sky above", x, y);
            else if (y > g.h / 2 + 1)
                expect_rgb_close(v, rgb_grey(0.0), 0.0, 0.0, "black floor", x, y);
        }
    render_scene_destroy(g.rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_uniform_invariants),
        cmocka_unit_test(test_far_from_origin),
        cmocka_unit_test(test_near_and_grazing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
