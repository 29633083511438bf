/* Moving surfaces (docs/motion.md): shapes, instances and area lights that move
 * with pbrt-v4's AnimatedTransform, intersected through Embree's quaternion
 * motion blur. Pixels are estimated as the renderer does (film position, time
 * and lens from the pixel sampler, box filter) with their standard errors, and
 * compared with analytic values or with each other by z-scores. Set
 * HAZE_MOTION_VERBOSE=1 to print the measured statistics. */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>

#include "cli_util.h"
#include "render_test_util.h"

#include "core/animated_transform.h"
#include "core/rng.h"
#include "geometry/geometry.h"
#include "render/renderer.h"

static bool verbose(void)
{
    const char *v = getenv("HAZE_MOTION_VERBOSE");
    return v && v[0] && v[0] != '0';
}

#define say(...)                                                                                   \
    do {                                                                                           \
        if (verbose())                                                                             \
            fprintf(stderr, __VA_ARGS__);                                                          \
    } while (0)

/* ---- pixel statistics ------------------------------------------------------ */

typedef struct {
    double mean, se; /* green channel: sample mean and its standard error */
} pstat;

/* `spp` samples of pixel (px, py) drawn like the renderer's (film offset,
 * time, lens), weighted by the filter (box: 1). No cmocka calls (threads). */
static pstat pixel_stat(const render_scene *rs, int px, int py, int spp)
{
    const camera *cam = render_scene_camera(rs);
    const filter *flt = render_scene_filter(rs);
    sampler smp = *render_scene_sampler(rs);
    sampler_set_spp(&smp, spp);
    integrator_counters counters = {0};
    double s = 0.0, s2 = 0.0;
    for (int i = 0; i < spp; ++i) {
        sampler_state st;
        sampler_start(&smp, px, py, i, &st);
        camera_sample cs = renderer_camera_sample(flt, &st, px, py);
        ray_differential rd;
        double v = 0.0;
        if (camera_generate_ray_differential(cam, cs, &rd)) {
            double depth;
            v = cs.filter_weight * render_scene_li(rs, &rd, &st, &depth, &counters).g;
        }
        s += v;
        s2 += v * v;
    }
    double mean = s / spp;
    double var = fmax(s2 - spp * mean * mean, 0.0) / (spp - 1);
    return (pstat){mean, sqrt(var / spp)};
}

typedef struct {
    const render_scene *rs;
    int w, spp;
    pstat *out;
} stat_job;

static void stat_pixel(void *ctx, int x, int y)
{
    stat_job *j = ctx;
    j->out[y * j->w + x] = pixel_stat(j->rs, x, y, j->spp);
}

/* Every pixel of a w x h image (row-major), on two threads; checks each is finite. */
static pstat *image_pixel_stats(const char *text, int w, int h, int spp)
{
    render_scene *rs = build_scene_or_fail(text, NULL);
    pstat *out = calloc((size_t)w * h, sizeof *out);
    assert_non_null(out);
    stat_job job = {rs, w, spp, out};
    for_each_pixel_parallel(w, h, stat_pixel, &job);
    for (int i = 0; i < w * h; ++i)
        if (!isfinite(out[i].mean) || !isfinite(out[i].se) || out[i].mean < 0.0) {
            print_error("pixel (%d, %d) is %g\n", i % w, i / w, out[i].mean);
            fail();
        }
    render_scene_destroy(rs);
    return out;
}

typedef struct {
    double zmax, pooled; /* largest |z| of a pixel, z of the summed difference */
    int compared;
} zstats;

/* Pixelwise z-scores of a - b against their combined standard error; pixels
 * with no variance on either side must agree to 1e-9 (relative). */
static zstats compare_images(const pstat *a, const pstat *b, int n, const char *what)
{
    zstats z = {0.0, 0.0, 0};
    double dsum = 0.0, vsum = 0.0;
    for (int i = 0; i < n; ++i) {
        double d = a[i].mean - b[i].mean;
        double se = hypot(a[i].se, b[i].se);
        dsum += d;
        vsum += se * se;
        if (se == 0.0) {
            if (!(fabs(d) <= 1e-9 * fmax(fabs(a[i].mean), 1e-3))) {
                print_error("%s: pixel %d: %.9g vs %.9g with no variance\n", what, i, a[i].mean,
                            b[i].mean);
                fail();
            }
            continue;
        }
        z.zmax = fmax(z.zmax, fabs(d / se));
        z.compared++;
    }
    z.pooled = vsum > 0.0 ? dsum / sqrt(vsum) : 0.0;
    say("%s: %d pixels with variance, max |z| %.2f, pooled z %.2f\n", what, z.compared, z.zmax,
        z.pooled);
    return z;
}

/* ---- 1. a rotating emitter blurs along its arc -------------------------------- */

/* A 0.2 x 0.2 emitter centred at (1, 0), seen along the z axis by an
 * orthographic camera over [-1.5, 1.5]^2 (48^2 pixels of 1/16), turning by 90
 * degrees about the z axis over the shutter when `motion`. */
static const char *rotor_fmt =
    "LookAt 0 0 0  0 0 1  0 1 0\n"
    "Camera \"orthographic\" \"float screenwindow\" [-1.5 1.5 -1.5 1.5]\n"
    "Film \"rgb\" \"integer xresolution\" 48 \"integer yresolution\" 48\n"
    "PixelFilter \"box\"\n"
    "Sampler \"independent\" \"integer pixelsamples\" 256 \"integer seed\" %d\n"
    "WorldBegin\n"
    "AttributeBegin\n%s"
    "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [0.9 -0.1 5  1.1 -0.1 5  1.1 0.1 5  0.9 0.1 5]\n"
    "AttributeEnd\n";

#define ROTOR_RES 48
#define ROTOR_PIXEL (3.0 / ROTOR_RES)

static vec2 rotor_pixel_centre(int i)
{
    return v2(-1.5 + (i % ROTOR_RES + 0.5) * ROTOR_PIXEL,
              1.5 - (i / ROTOR_RES + 0.5) * ROTOR_PIXEL);
}

typedef struct {
    double energy, se;  /* sum of radiance x pixel area, and its standard error */
    double radius;      /* energy-weighted mean distance of pixel centres from the axis */
    double bins[2], bin_var[2]; /* energy at angles [10, 40) and [50, 80) degrees */
} rotor_measure;

static rotor_measure measure_rotor(const pstat *px)
{
    rotor_measure m = {0};
    double a2 = ROTOR_PIXEL * ROTOR_PIXEL, var = 0.0, sr = 0.0;
    for (int i = 0; i < ROTOR_RES * ROTOR_RES; ++i) {
        vec2 c = rotor_pixel_centre(i);
        double e = px[i].mean * a2, v = px[i].se * px[i].se * a2 * a2;
        double r = hypot(c.x, c.y), deg = atan2(c.y, c.x) * 180.0 / HZ_PI;
        m.energy += e;
        var += v;
        sr += e * r;
        for (int b = 0; b < 2; ++b)
            if (deg >= 10.0 + 40.0 * b && deg < 40.0 + 40.0 * b) {
                m.bins[b] += e;
                m.bin_var[b] += v;
            }
    }
    m.se = sqrt(var);
    m.radius = sr / m.energy;
    return m;
}

/* Mean distance from the origin of the square [0.9, 1.1] x [-0.1, 0.1]. */
static double square_mean_radius(void)
{
    const int n = 1000;
    double s = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            s += hypot(0.9 + 0.2 * (i + 0.5) / n, -0.1 + 0.2 * (j + 0.5) / n);
    return s / ((double)n * n);
}

/* pbrt's AnimatedTransform slerps the rotation: every point of the emitter
 * keeps its distance from the axis, so the streak is an arc of radius ~1
 * swept at constant angular speed. A matrix lerp would move the emitter along
 * the chord, through (0.5, 0.5) at mid-shutter. The streak's energy (one
 * emitter visible at every instant) is the still emitter's, 0.04. */
static void test_rotating_emitter_blurs_along_arc(void **state)
{
    (void)state;
    char text[2048];
    snprintf(text, sizeof text, rotor_fmt, 1, "");
    pstat *still = image_pixel_stats(text, ROTOR_RES, ROTOR_RES, 256);
    snprintf(text, sizeof text, rotor_fmt, 2,
             "ActiveTransform EndTime\nRotate 90 0 0 1\nActiveTransform All\n");
    pstat *moving = image_pixel_stats(text, ROTOR_RES, ROTOR_RES, 256);
    rotor_measure s = measure_rotor(still), m = measure_rotor(moving);
    double want_r = square_mean_radius();
    double z_still = (s.energy - 0.04) / s.se, z_moving = (m.energy - 0.04) / m.se;
    double z_pair = (m.energy - s.energy) / hypot(m.se, s.se);
    double z_bins = (m.bins[0] - m.bins[1]) / sqrt(m.bin_var[0] + m.bin_var[1]);
    say("rotor: energy still %.5f (z %.2f), moving %.5f (z %.2f), pair z %.2f\n", s.energy,
        z_still, m.energy, z_moving, z_pair);
    say("rotor: mean radius %.5f still, %.5f moving, want %.5f; bins %.5f %.5f (z %.2f)\n",
        s.radius, m.radius, want_r, m.bins[0], m.bins[1], z_bins);
    assert_true(fabs(z_still) < 4.5 && fabs(z_moving) < 4.5 && fabs(z_pair) < 4.5);
    /* pixel centres stand for their pixels: within 1/6 pixel */
    assert_true(fabs(s.radius - want_r) < 0.01);
    assert_true(fabs(m.radius - want_r) < 0.01);
    /* constant angular speed: the two 30-degree sectors (mirror images about
     * the diagonal, as the pixel grid is) hold the same energy, a third of
     * the 90-degree arc each */
    assert_true(fabs(z_bins) < 4.5);
    assert_true(fabs(m.bins[0] / m.energy - 30.0 / 90.0) < 0.05);
    /* nothing inside radius 0.8 or outside 1.2 (the emitter spans
     * [0.9, 1.105], a pixel reaches 0.045 from its centre): the chord's
     * midpoint (0.5, 0.5) stays dark */
    int dark = 0;
    for (int i = 0; i < ROTOR_RES * ROTOR_RES; ++i) {
        vec2 c = rotor_pixel_centre(i);
        double r = hypot(c.x, c.y);
        if (r < 0.8 || r > 1.2) {
            assert_true(moving[i].mean == 0.0);
            dark++;
        }
    }
    int mid = (int)((1.5 - 0.5) / ROTOR_PIXEL) * ROTOR_RES + (int)((0.5 + 1.5) / ROTOR_PIXEL);
    assert_true(moving[mid].mean == 0.0);
    assert_true(dark > 1500);
    free(still);
    free(moving);
}

/* ---- 2. moving the camera by +d is moving the world by -d -------------------- */

static const char *relative_fmt =
    "LookAt 0 2 -4  0 0.5 0  0 1 0\n"
    "%s"
    "Camera \"perspective\" \"float fov\" 50\n"
    "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
    "PixelFilter \"box\"\n"
    "Sampler \"independent\" \"integer pixelsamples\" 64 \"integer seed\" %d\n"
    "WorldBegin\n"
    "%s"
    "LightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\n"
    "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10]\n"
    "AttributeBegin\nTranslate 0.3 0.6 0.5\nShape \"sphere\" \"float radius\" 0.6\nAttributeEnd\n"
    "AttributeBegin\nTranslate -0.8 2 0\n"
    "AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-0.5 0 -0.5  0.5 0 -0.5  0.5 0 0.5  -0.5 0 0.5]\n"
    "AttributeEnd\n"
    "AttributeBegin\nTranslate 1.2 0.3 -1\n"
    "AreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n"
    "Shape \"sphere\" \"float radius\" 0.2\nAttributeEnd\n";

/* Only the relative motion counts: the camera sliding by d = (0.6, 0, 0.3)
 * over the shutter and the world (shapes, area lights, shadows) sliding by -d
 * under a still camera give the same image. Independent seeds; 384 pixels at
 * 64 spp: every pixel within 5 standard errors, the image sum within 4.5. */
static void test_camera_motion_equals_world_motion(void **state)
{
    (void)state;
    const char *slide = "ActiveTransform EndTime\nTranslate -0.6 0 -0.3\nActiveTransform All\n";
    char text[4096];
    snprintf(text, sizeof text, relative_fmt, slide, 1, "");
    pstat *cam = image_pixel_stats(text, 24, 16, 64);
    snprintf(text, sizeof text, relative_fmt, "", 2, slide);
    pstat *world = image_pixel_stats(text, 24, 16, 64);
    zstats z = compare_images(cam, world, 24 * 16, "camera +d vs world -d");
    assert_true(z.compared > 300);
    assert_true(z.zmax < 5.0);
    assert_true(fabs(z.pooled) < 4.5);
    /* and the slide is visible: the still scene differs */
    snprintf(text, sizeof text, relative_fmt, "", 3, "");
    pstat *still = image_pixel_stats(text, 24, 16, 64);
    zstats zs = compare_images(cam, still, 24 * 16, "camera +d vs still");
    assert_true(zs.zmax > 10.0);
    free(cam);
    free(world);
    free(still);
}

/* ---- 3. equal keyframes are static --------------------------------------------- */

static const char *keyframe_fmt =
    "LookAt 0 2 -4  0 0.5 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 50\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10]\n"
    "ObjectBegin \"ball\"\nShape \"sphere\" \"float radius\" 0.4\nObjectEnd\n"
    "AttributeBegin\nTranslate -0.9 0.4 0.5\n%sObjectInstance \"ball\"\nAttributeEnd\n"
    "AttributeBegin\nTranslate 0.6 0.7 0.3\n%sScale 1 0.5 1\n"
    "Shape \"sphere\" \"float radius\" 0.6\nAttributeEnd\n"
    "AttributeBegin\nTranslate 0 2 0\n%s"
    "AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-0.5 0 -0.5  0.5 0 -0.5  0.5 0 0.5  -0.5 0 0.5]\n"
    "AttributeEnd\n";

static unsigned char *render_bytes(const char *name, const char *a, const char *b, const char *c,
                                   size_t *size)
{
    char text[4096], scene[1024], args[4096], out[4096];
    snprintf(text, sizeof text, keyframe_fmt, a, b, c);
    snprintf(scene, sizeof scene, "%s/%s.pbrt", HAZE_TMP, name);
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' -o '%s/%s.exr' --quiet", scene, HAZE_TMP, name);
    int rc = run_haze(args, out, sizeof out);
    if (rc != 0) {
        print_error("haze exited %d: %s\n", rc, out);
        fail();
    }
    snprintf(scene, sizeof scene, "%s/%s.exr", HAZE_TMP, name);
    unsigned char *bytes = read_exr_pixels(scene, size); /* headers name their scenes */
    assert_non_null(bytes);
    return bytes;
}

/* An instance, a shape and an emitting shape whose start and end transforms
 * are equal (each built by the same operations under StartTime and EndTime)
 * render byte for byte like the static scene; a 1-degree difference does not. */
static void test_equal_keyframes_are_static(void **state)
{
    (void)state;
    const char *still = "Rotate 30 0 1 0\n";
    const char *same = "ActiveTransform StartTime\nRotate 30 0 1 0\n"
                       "ActiveTransform EndTime\nRotate 30 0 1 0\nActiveTransform All\n";
    const char *turn = "ActiveTransform StartTime\nRotate 30 0 1 0\n"
                       "ActiveTransform EndTime\nRotate 31 0 1 0\nActiveTransform All\n";
    size_t n0, n1, n2, n3, n4;
    unsigned char *ref = render_bytes("keys_static", still, still, still, &n0);
    unsigned char *inst = render_bytes("keys_instance", same, still, still, &n1);
    unsigned char *all = render_bytes("keys_all", same, same, same, &n2);
    unsigned char *moved = render_bytes("keys_moved", still, turn, still, &n3);
    unsigned char *lit = render_bytes("keys_light", still, still, turn, &n4);
    assert_int_equal(n0, n1);
    assert_memory_equal(ref, inst, n0);
    assert_int_equal(n0, n2);
    assert_memory_equal(ref, all, n0);
    assert_true(n3 != n0 || memcmp(ref, moved, n0) != 0);
    assert_true(n4 != n0 || memcmp(ref, lit, n0) != 0);
    free(ref);
    free(inst);
    free(all);
    free(moved);
    free(lit);
}

/* ---- 4. a moving area light is the time average of still ones ----------------- */

/* An orthographic view straight down on a diffuse floor (16^2 pixels over
 * [-2, 2]^2) lit only by the emitter block `light`. */
static const char *floor_fmt =
    "LookAt 0 3 0  0 0 0  0 0 1\n"
    "Camera \"orthographic\" \"float screenwindow\" [-2 2 -2 2]\n"
    "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
    "PixelFilter \"box\"\n"
    "Sampler \"independent\" \"integer pixelsamples\" 16 \"integer seed\" %d\n"
    "WorldBegin\n"
    "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-5 0 -5  5 0 -5  5 0 5  -5 0 5]\n"
    "AttributeBegin\n%s"
    "AreaLightSource \"diffuse\" \"rgb L\" [3 3 3]\n%s"
    "AttributeEnd\n";

/* A 1 x 0.4 quad facing down (one-sided) and a sphere of radius 0.3. */
static const char *quad_light = "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
                                "  \"point3 P\" [-0.5 0 -0.2  0.5 0 -0.2  0.5 0 0.2  -0.5 0 0.2]\n";
static const char *ball_light = "Shape \"sphere\" \"float radius\" 0.3\n";

#define AVG_N 16
#define AVG_SPP 64

/* Renders the moving light at AVG_N * AVG_SPP spp and AVG_N still lights at
 * the midpoints of AVG_N equal time slices (AVG_SPP spp each), and compares
 * the moving image with the mean of the still ones. `at(t, buf)` writes the
 * still transform at time t. */
static void compare_with_still_average(const char *what, const char *shape, const char *motion,
                                       void (*at)(double t, char *buf, size_t n))
{
    char text[4096], xf[512];
    snprintf(text, sizeof text, floor_fmt, 1, motion, shape);
    pstat *moving = image_pixel_stats(text, 16, 16, AVG_N * AVG_SPP);
    pstat avg[256];
    memset(avg, 0, sizeof avg);
    for (int k = 0; k < AVG_N; ++k) {
        at((k + 0.5) / AVG_N, xf, sizeof xf);
        snprintf(text, sizeof text, floor_fmt, 100 + k, xf, shape);
        pstat *still = image_pixel_stats(text, 16, 16, AVG_SPP);
        for (int i = 0; i < 256; ++i) {
            avg[i].mean += still[i].mean / AVG_N;
            avg[i].se += still[i].se * still[i].se / (AVG_N * AVG_N); /* variance for now */
        }
        free(still);
    }
    double lit = 0.0;
    for (int i = 0; i < 256; ++i) {
        avg[i].se = sqrt(avg[i].se);
        lit += avg[i].mean > 0.0;
    }
    zstats z = compare_images(moving, avg, 256, what);
    assert_true(lit > 200); /* the light reaches the floor (it faces it) */
    assert_true(z.zmax < 5.0);
    assert_true(fabs(z.pooled) < 4.5);
    free(moving);
}

/* Translation, a 60-degree turn about the vertical and a scale of the quad's
 * x from 1 to 2 (its area doubles: the sample density follows). */
static const char *quad_motion = "ActiveTransform StartTime\nTranslate -1 1 0\n"
                                 "ActiveTransform EndTime\nTranslate 1 1.5 0.5\n"
                                 "Rotate 60 0 1 0\nScale 2 1 1\nActiveTransform All\n";

static void quad_at(double t, char *buf, size_t n)
{
    snprintf(buf, n, "Translate %.17g %.17g %.17g\nRotate %.17g 0 1 0\nScale %.17g 1 1\n",
             hz_lerp(t, -1, 1), hz_lerp(t, 1, 1.5), hz_lerp(t, 0, 0.5), 60 * t, hz_lerp(t, 1, 2));
}

/* Translation and an x scale from 1 to 1.5: a sphere (cone sampling) at the
 * start only, an ellipsoid (area sampling) after. */
static const char *ball_motion = "ActiveTransform StartTime\nTranslate -1 1 0\n"
                                 "ActiveTransform EndTime\nTranslate 1 1.2 0.3\nScale 1.5 1 1\n"
                                 "ActiveTransform All\n";

static void ball_at(double t, char *buf, size_t n)
{
    snprintf(buf, n, "Translate %.17g %.17g %.17g\nScale %.17g 1 1\n", hz_lerp(t, -1, 1),
             hz_lerp(t, 1, 1.2), hz_lerp(t, 0, 0.3), hz_lerp(t, 1, 1.5));
}

/* Light samples are drawn at the ray's time from the light as it is then.
 * The midpoint rule over AVG_N slices errs by ~f''/(24 AVG_N^2) of a pixel's
 * time curve: at 16x these sample counts the quad light's largest pixel z was
 * 22.6 with 4 slices and 4.8 with 8 (second order), so with 16 slices it is
 * about 0.3 standard errors at the counts used here. (Measured here: max |z|
 * 2.7 and 3.5, pooled -2.6 and 0.8; at 16x the samples 2.9 and 2.4, pooled
 * -0.95 and 0.07, so no bias grows with the sample count.) */
static void test_moving_area_light_is_time_average(void **state)
{
    (void)state;
    compare_with_still_average("moving quad light vs still average", quad_light, quad_motion,
                               quad_at);
    compare_with_still_average("moving sphere light vs still average", ball_light, ball_motion,
                               ball_at);
}

/* ---- 5. a moving occluder casts a blurred shadow -------------------------------- */

/* A diffuse floor lit by a distant light from (-1, 1, 0); a plate 0.5 wide
 * (an object instance) at height 3 slides from x = 0 to x = 1 over the
 * shutter, so its shadow, shifted by 3, sweeps [2.75, 4.25]. An orthographic
 * camera looks straight down on x in [2.5, 4.5] (32 x 4 pixels of 1/16), away
 * from the plate itself. */
static const char *shadow_scene =
    "LookAt 3.5 5 0  3.5 0 0  0 0 1\n"
    "Camera \"orthographic\" \"float screenwindow\" [-1 1 -0.125 0.125]\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 4\n"
    "PixelFilter \"box\"\n"
    "Sampler \"independent\" \"integer pixelsamples\" 256 \"integer seed\" 5\n"
    "WorldBegin\n"
    "LightSource \"distant\" \"rgb L\" [2 2 2] \"point3 from\" [-1 1 0] \"point3 to\" [0 0 0]\n"
    "ObjectBegin \"plate\"\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-0.25 0 -10  0.25 0 -10  0.25 0 10  -0.25 0 10]\n"
    "ObjectEnd\n"
    "AttributeBegin\nTranslate 0 3 0\nActiveTransform EndTime\nTranslate 1 0 0\n"
    "ActiveTransform All\nObjectInstance \"plate\"\nAttributeEnd\n"
    "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10]\n";

/* Shadowed fraction of pixel column x (world [x0, x0 + 1/16]) over the
 * shutter: the measure of {(x, t): |x - 3 - t| < 0.25} per unit of x and t. */
static double shadowed_fraction(double x0)
{
    const int n = 4000;
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
        double x = x0 + (i + 0.5) / n / 16.0;
        /* times t in [0, 1] with |x - 3 - t| < 0.25 */
        double lo = fmax(0.0, x - 3.25), hi = fmin(1.0, x - 2.75);
        s += fmax(0.0, hi - lo);
    }
    return s / n;
}

static void test_moving_occluder_shadow(void **state)
{
    (void)state;
    pstat *px = image_pixel_stats(shadow_scene, 32, 4, 256);
    const double lit = 0.5 * HZ_INV_PI * 2.0 * sqrt(0.5);
    double zmax = 0.0, dsum = 0.0, vsum = 0.0, darkest = 1.0;
    for (int i = 0; i < 32 * 4; ++i) {
        double x0 = 2.5 + (i % 32) / 16.0;
        double f = shadowed_fraction(x0), want = lit * (1.0 - f);
        darkest = fmin(darkest, 1.0 - f);
        if (px[i].se == 0.0) {
            /* never shadowed: every sample sees the full light */
            assert_true(f == 0.0);
            assert_true(fabs(px[i].mean - want) <= 1e-9 * want);
            continue;
        }
        double z = (px[i].mean - want) / px[i].se;
        zmax = fmax(zmax, fabs(z));
        dsum += px[i].mean - want;
        vsum += px[i].se * px[i].se;
        if (fabs(z) > 5.0) {
            print_error("shadow pixel %d: %.6g, want %.6g (se %.3g)\n", i, px[i].mean, want,
                        px[i].se);
            fail();
        }
    }
    say("moving shadow: max |z| %.2f, pooled z %.2f, darkest %.3f of the light\n", zmax,
        dsum / sqrt(vsum), darkest);
    assert_true(fabs(dsum / sqrt(vsum)) < 4.5);
    assert_true(darkest < 0.6); /* the plate (0.5 wide, moving 1) covers a point half the time */
    free(px);
}

/* ---- 6. hits lie where Embree found them, on pbrt's moving surface ------------ */

/* A sphere and a box that turn by 120 degrees while scaled along axes that
 * turn with them (pbrt's S is not diagonal: several Embree time steps), the
 * sphere as a shape and as an instance, the box as a mesh. */
static const char *shear_scene =
    "WorldBegin\n"
    "AttributeBegin\nTranslate -1.2 0 4\nActiveTransform EndTime\nRotate 120 1 1 0\n"
    "Scale 2 0.5 1\nRotate 40 0 0 1\nActiveTransform All\n"
    "Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n"
    "AttributeBegin\nTranslate 1.2 0 4\nActiveTransform EndTime\nRotate 120 1 1 0\n"
    "Scale 2 0.5 1\nRotate 40 0 0 1\nActiveTransform All\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1]\n"
    "  \"point3 P\" [-0.5 -0.5 -0.5  0.5 -0.5 -0.5  0.5 0.5 -0.5  -0.5 0.5 -0.5\n"
    "               -0.5 -0.5 0.5  0.5 -0.5 0.5  0.5 0.5 0.5  -0.5 0.5 0.5]\n"
    "AttributeEnd\n"
    "ObjectBegin \"ball\"\nShape \"sphere\" \"float radius\" 0.5\nObjectEnd\n"
    "AttributeBegin\nTranslate 0 1.5 4\nActiveTransform EndTime\nRotate 120 1 1 0\n"
    "Scale 2 0.5 1\nRotate 40 0 0 1\nActiveTransform All\nObjectInstance \"ball\"\n"
    "AttributeEnd\n";

static void test_hits_follow_the_motion(void **state)
{
    (void)state;
    scene_desc sd;
    hz_error err = {0};
    assert_int_equal(scene_parse_string(shear_scene, "shear.pbrt", &sd, &err), HZ_OK);
    material def = material_default();
    geometry *g = NULL;
    if (geometry_create(&sd, transform_identity(), NULL, 0, &def, NULL, false, NULL, &g, &err) != HZ_OK) {
        print_error("%s\n", err.message);
        fail();
    }
    assert_true(geometry_has_motion(g));
    const geom_motion *m = geometry_shape(g, 0)->motion;
    assert_non_null(m);
    assert_true(m->segments > 1 && m->segments <= GEOMETRY_MAX_SEGMENTS);
    /* pbrt's motion of the sphere, to check hits against */
    animated_transform a = animated_transform_make(
        sd.shapes[0].world_from_object, 0.0, sd.shapes[0].world_from_object_end, 1.0);
    uint64_t seed = 9;
    rng r = rng_seeded(seed);
    double worst_t = 0.0, worst_line = 0.0, worst_pbrt = 0.0;
    int hits[3] = {0, 0, 0};
    for (int k = 0; k < 20000; ++k) {
        double time = rng_uniform(&r);
        vec3 target = v3(-3.0 + 6.0 * rng_uniform(&r), -1.5 + 4.5 * rng_uniform(&r), 4.0);
        vec3 d = v3_scale(target, 0.5 + rng_uniform(&r)); /* unnormalised */
        geom_hit h;
        if (!geometry_intersect(g, v3(0, 0, 0), d, 0.0, INFINITY, time, &h))
            continue;
        int which = h.shape == geometry_shape(g, 0) ? 0 : h.shape == geometry_shape(g, 1) ? 1 : 2;
        hits[which]++;
        /* Embree's t and the double hit point agree, and the point lies on the ray */
        double t_mine = v3_dot(h.p, d) / v3_dot(d, d);
        worst_t = fmax(worst_t, fabs(t_mine - h.t) / h.t);
        worst_line = fmax(worst_line, v3_length(v3_sub(h.p, v3_scale(d, t_mine))) / v3_length(h.p));
        if (which == 0) { /* on pbrt's sphere at that time */
            transform x = animated_transform_at(&a, time);
            vec3 po = transform_point(&(transform){x.m_inv, x.m}, h.p);
            worst_pbrt = fmax(worst_pbrt, fabs(v3_length(po) - 0.5) / 0.5);
        }
    }
    say("moving hits: %d sphere, %d box, %d instance; %d segments; worst relative t %.3g, "
        "off the ray %.3g, off pbrt's sphere %.3g\n",
        hits[0], hits[1], hits[2], m->segments, worst_t, worst_line, worst_pbrt);
    assert_true(hits[0] > 500 && hits[1] > 500 && hits[2] > 500);
    assert_true(worst_t < 1e-4);
    assert_true(worst_line < 1e-4);
    assert_true(worst_pbrt < 1e-4);
    geometry_destroy(g);
    scene_desc_free(&sd);
}

/* ---- 7. what stays refused --------------------------------------------------- */

static void test_refused_motion(void **state)
{
    (void)state;
    char msg[1024];
    build_scene_expect_error("WorldBegin\nObjectBegin \"o\"\nActiveTransform EndTime\n"
                             "Translate 1 0 0\nShape \"sphere\"\nObjectEnd\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:5:1"));
    assert_non_null(strstr(msg, "inside ObjectBegin"));
    build_scene_expect_error("WorldBegin\nActiveTransform EndTime\nScale -1 1 1\n"
                             "ActiveTransform All\nShape \"sphere\"\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:5:1"));
    assert_non_null(strstr(msg, "handedness"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rotating_emitter_blurs_along_arc),
        cmocka_unit_test(test_camera_motion_equals_world_motion),
        cmocka_unit_test(test_equal_keyframes_are_static),
        cmocka_unit_test(test_moving_area_light_is_time_average),
        cmocka_unit_test(test_moving_occluder_shadow),
        cmocka_unit_test(test_hits_follow_the_motion),
        cmocka_unit_test(test_refused_motion),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
