/* Moving grid media: a grid under an animated transform and a grid moved by a
 * velocity grid (Eulerian motion blur) against closed forms and against each
 * other, static equivalence bit for bit, and bad input.
 *
 * The volumes (volumes/generate.cpp): box.vdb is density 1 on index voxels
 * [0,31]^3 with voxel size 1/32, so its trilinear field along an axis is the
 * trapezoid f(u) = clamp(min(u + 1, 32 - u), 0, 1) of the index coordinate u;
 * box_velocity.vdb holds the same density, "v" = (1, 0.25, 0) world units per
 * unit time and "v0" = 0 on voxels [-3,50] x [-3,38] x [-3,34]. Both motions
 * below move the box by (0.25, 0.0625, 0) t over the shutter t in [0, 1]:
 * Translate at TransformTimes' end, or v with "velocityscale" 0.25.
 * The measured statistics are printed (ctest -V shows them). */
#include <stdarg.h>

#include "render_test_util.h"

#include "render/renderer.h"

#define VOLUMES HAZE_SCENES "/../volumes"

/* The two ways of moving the box by (0.25, 0.0625, 0) t. */
static const char *moved_by_transform = "ActiveTransform EndTime\n"
                                        "Translate 0.25 0.0625 0\n"
                                        "ActiveTransform All\n"
                                        "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                                        "\"string filename\" \"" VOLUMES "/box.vdb\" ";
static const char *moved_by_velocity =
    "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
    "\"string filename\" \"" VOLUMES "/box_velocity.vdb\" "
    "\"string velocityname\" \"v\" \"float velocityscale\" 0.25 ";

/* A static interface box around everything the moving box sweeps, "box"
 * inside, vacuum outside (counter-clockwise seen from outside). */
static const char *container =
    "AttributeBegin\n"
    "Material \"interface\"\n"
    "MediumInterface \"box\" \"\"\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 6 2  0 4 6  1 3 7  1 7 5  0 1 5  0 5 4 "
    "2 7 3  2 6 7  0 3 1  0 2 3  4 5 7  4 7 6]\n"
    "  \"point3 P\" [-0.2 -0.2 -0.2  1.5 -0.2 -0.2  -0.2 1.3 -0.2  1.5 1.3 -0.2 "
    "-0.2 -0.2 1.2  1.5 -0.2 1.2  -0.2 1.3 1.2  1.5 1.3 1.2]\n"
    "AttributeEnd\n";

/* head + medium + medium_params + "\n" + container + tail, as a new string. */
static char *scene_text(const char *head, const char *medium, const char *medium_params,
                        const char *tail)
{
    size_t n = strlen(head) + strlen(medium) + strlen(medium_params) + strlen(container) +
               strlen(tail) + 64;
    char *s = malloc(n);
    assert_non_null(s);
    snprintf(s, n, "%sWorldBegin\nAttributeBegin\n%s%s\nAttributeEnd\n%s%s", head, medium,
             medium_params, container, tail);
    return s;
}

/* The camera ray through the centre of pixel (px, py) at shutter fraction u. */
static ray_differential pixel_ray(const render_scene *rs, int px, int py, double u)
{
    camera_sample cs = {v2(px + 0.5, py + 0.5), v2(0.5, 0.5), u, 1.0};
    ray_differential rd;
    assert_true(camera_generate_ray_differential(render_scene_camera(rs), cs, &rd));
    return rd;
}

static rgb li(const render_scene *rs, const ray_differential *rd, int px, int py, int i,
              int spp)
{
    sampler smp = *render_scene_sampler(rs);
    sampler_set_spp(&smp, spp);
    sampler_state st;
    sampler_start(&smp, px, py, i, &st);
    integrator_counters counters = {0};
    double depth;
    return render_scene_li(rs, rd, &st, &depth, &counters);
}

static double ch(rgb c, int i) { return i == 0 ? c.r : i == 1 ? c.g : c.b; }

/* ---- 1. An absorbing box sliding across orthographic rays: closed form ---- */

/* Looking down -z at the box; 16 x 16 pixels of 1/8 world unit; the sky (1)
 * behind; no scattering, so every pixel is the transmittance along z,
 * exp(-sigma_a f(X) f(Y)) with X, Y the ray's index coordinates in the moved
 * box (the field integrates to 32 voxels = 1 world unit along z). */
static const char *slide_head =
    "LookAt 0.5 0.5 5  0.5 0.5 0  0 1 0\n"
    "Camera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"
    "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
    "Sampler \"independent\" \"integer pixelsamples\" 1\n"
    "Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" \"float stepsize\" 0.125\n";
static const char *slide_params = "\"rgb sigma_a\" [0.25 0.5 1] \"rgb sigma_s\" [0 0 0]";
static const char *slide_tail = "LightSource \"infinite\" \"rgb L\" [1 1 1]\n";
static const rgb slide_sigma = {0.25, 0.5, 1.0, 0.5};
#define SLIDE_STEP 0.125 /* voxels, as in slide_head */

static double trapezoid(double u) { return fmax(0.0, fmin(1.0, fmin(u + 1.0, 32.0 - u))); }

/* The box's optical depth per unit sigma through world (x, y) at time t. */
static double slide_depth(double x, double y, double t)
{
    return trapezoid(32.0 * (x - 0.25 * t)) * trapezoid(32.0 * (y - 0.0625 * t));
}

/* The midpoint rule along z is exact except in the strata holding one of the
 * trapezoid's four kinks, each off by at most h^2/8 voxels (slope change 1):
 * a bound on the raymarched optical depth's error, per unit sigma, in world
 * units (32 voxels each), scaled by the profile's height. */
static double march_bound(double depth)
{
    return depth * 4.0 * SLIDE_STEP * SLIDE_STEP / 8.0 / 32.0;
}

/* ∫_0^1 exp(-sigma f(32 (x - 0.25 t))) dt in closed form: f is linear between
 * the times the ray crosses the kinks, and so is the exponent. */
static double slide_time_average(double x, double sigma)
{
    double cuts[6] = {0.0, 1.0};
    int n = 2;
    const double kinks[4] = {-1.0, 0.0, 31.0, 32.0};
    for (int k = 0; k < 4; ++k) {
        double t = (32.0 * x - kinks[k]) / 8.0; /* X(t) = 32 x - 8 t */
        if (t > 0.0 && t < 1.0)
            cuts[n++] = t;
    }
    for (int i = 1; i < n; ++i) /* insertion sort */
        for (int j = i; j > 0 && cuts[j] < cuts[j - 1]; --j) {
            double c = cuts[j];
            cuts[j] = cuts[j - 1];
            cuts[j - 1] = c;
        }
    double sum = 0.0;
    for (int i = 0; i + 1 < n; ++i) {
        double a = cuts[i], b = cuts[i + 1];
        double fa = trapezoid(32.0 * x - 8.0 * a), fb = trapezoid(32.0 * x - 8.0 * b);
        if (fa == fb)
            sum += (b - a) * exp(-sigma * fa);
        else
            sum += (b - a) * (exp(-sigma * fa) - exp(-sigma * fb)) / (sigma * (fb - fa));
    }
    return sum;
}

static void check_slide(const char *medium, const char *what)
{
    char *text = scene_text(slide_head, medium, slide_params, slide_tail);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    const camera *cam = render_scene_camera(rs);
    double worst = 0.0, worst_avg = 0.0;
    int averaged = 0;
    for (int py = 0; py < 16; ++py)
        for (int px = 0; px < 16; ++px) {
            /* Per ray, at nine times: the closed form within the marching bound. */
            for (int k = 0; k <= 8; ++k) {
                double u = k / 8.0 * 0.999999;
                ray_differential rd = pixel_ray(rs, px, py, u);
                vec3 o = transform_point(&cam->world_from_render, rd.r.o);
                double depth = slide_depth(o.x, o.y, rd.r.time);
                rgb L = li(rs, &rd, px, py, 0, 1);
                for (int c = 0; c < 3; ++c) {
                    double s = ch(slide_sigma, c), want = exp(-s * depth);
                    double tol = want * s * march_bound(depth) * 1.01 + 1e-12;
                    double err = fabs(ch(L, c) - want);
                    if (!(err <= tol))
                        fail_msg("%s: pixel (%d, %d) at time %g channel %d: %.12g, want %.12g "
                                 "(tolerance %.3g)",
                                 what, px, py, rd.r.time, c, ch(L, c), want, tol);
                    worst = fmax(worst, err);
                }
            }
            /* The time average over the shutter (K stratified times) where the
             * box covers the ray's y for the whole shutter (f(Y) = 1). */
            ray_differential rd0 = pixel_ray(rs, px, py, 0.5);
            vec3 o0 = transform_point(&cam->world_from_render, rd0.r.o);
            if (!(o0.y >= 0.0625 + 1e-9 && o0.y <= 31.0 / 32 - 1e-9) || (px % 2))
                continue;
            enum { K = 256 };
            rgb sum = rgb_grey(0.0);
            for (int k = 0; k < K; ++k) {
                ray_differential rd = pixel_ray(rs, px, py, (k + 0.5) / K);
                sum = rgb_add(sum, li(rs, &rd, px, py, 0, 1));
            }
            for (int c = 0; c < 3; ++c) {
                double s = ch(slide_sigma, c), want = slide_time_average(o0.x, s);
                /* Midpoint rule in time: (1/24) h^2 max|g''| with g'' <= (8 s)^2,
                 * plus up to four kinks where g' jumps by <= 8 s, each
                 * (jump) h^2 / 8; and the marching bound. */
                double h = 1.0 / K;
                double tol = (64.0 * s * s / 24.0 + 4.0 * s) * h * h + s * march_bound(1.0);
                double err = fabs(ch(sum, c) / K - want);
                if (!(err <= tol))
                    fail_msg("%s: pixel (%d, %d) time average channel %d: %.9g, want %.9g "
                             "(tolerance %.3g)",
                             what, px, py, c, ch(sum, c) / K, want, tol);
                worst_avg = fmax(worst_avg, err);
            }
            ++averaged;
        }
    assert_true(averaged >= 40);
    print_message("%s: worst per-ray error %.3g; worst time-average error %.3g over %d pixels\n",
                  what, worst, worst_avg, averaged);
    render_scene_destroy(rs);
}

static void test_sliding_box_closed_form(void **state)
{
    (void)state;
    check_slide(moved_by_transform, "animated transform");
    check_slide(moved_by_velocity, "velocity grid");
}

/* ---- 2. Animated transform = constant velocity grid, within noise ---- */

/* The box lit by a point light beside it, over a floor that catches its
 * shadow: camera rays and shadow rays (from the box and from the floor) cross
 * the moving box. */
static const char *lit_head =
    "LookAt 0.7 0.9 -2.2  0.65 0.45 0.5  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 48\n"
    "Film \"rgb\" \"integer xresolution\" 10 \"integer yresolution\" 10\n";
static const char *lit_params =
    "\"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [1 2 3] \"float g\" 0.3";
static const char *lit_tail =
    "LightSource \"point\" \"point3 from\" [-1.2 2.2 0.3] \"rgb I\" [5 5 5]\n"
    "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-5 -0.3 -5  5 -0.3 -5  5 -0.3 5  -5 -0.3 5]\n";

#define LIT_RES 10

/* Every sample of the centre ray of every pixel: sample i at shutter fraction
 * (i + 0.5) / spp, the same times for every scene; the estimators' random
 * numbers come from the seed. Returns [pixel * spp + i]. */
static rgb *lit_samples(const char *medium, const char *integrator, uint64_t seed, int spp)
{
    char head[1024];
    snprintf(head, sizeof head, "%s%sSampler \"independent\"\n", lit_head, integrator);
    char *text = scene_text(head, medium, lit_params, lit_tail);
    render_options opt = {.seed = seed};
    render_scene *rs = build_scene_or_fail(text, &opt);
    free(text);
    rgb *out = calloc((size_t)LIT_RES * LIT_RES * spp, sizeof *out);
    assert_non_null(out);
    for (int p = 0; p < LIT_RES * LIT_RES; ++p)
        for (int i = 0; i < spp; ++i) {
            ray_differential rd = pixel_ray(rs, p % LIT_RES, p / LIT_RES, (i + 0.5) / spp);
            rgb L = li(rs, &rd, p % LIT_RES, p / LIT_RES, i, spp);
            assert_true(isfinite(L.r) && isfinite(L.g) && isfinite(L.b));
            out[p * spp + i] = L;
        }
    render_scene_destroy(rs);
    return out;
}

/* Paired per-pixel z-scores: d_i = a_i - b_i pairs samples at the same time
 * from independent random streams, so when both scenes are the same medium at
 * every time the d_i have mean 0 and the time variation cancels; z = mean(d) /
 * (sd(d) / sqrt(spp)). Returns the largest |z| over pixels and channels; sets
 * the z-score of the image means' difference (all pixel channels pooled) and
 * that difference relative to a's mean. */
static double max_z(const rgb *a, const rgb *b, int spp, double *z_mean, double *mean_rel)
{
    double zmax = 0.0, ma = 0.0, mb = 0.0, var_sum = 0.0;
    for (int p = 0; p < LIT_RES * LIT_RES; ++p) {
        /* The channels of a sample are correlated: the pooled statistic takes
         * their sum per sample. */
        double s[4] = {0, 0, 0, 0}, s2[4] = {0, 0, 0, 0};
        for (int i = 0; i < spp; ++i) {
            rgb x = a[p * spp + i], y = b[p * spp + i];
            double d[4] = {x.r - y.r, x.g - y.g, x.b - y.b, 0.0};
            d[3] = d[0] + d[1] + d[2];
            for (int c = 0; c < 4; ++c) {
                s[c] += d[c];
                s2[c] += d[c] * d[c];
            }
            ma += x.r + x.g + x.b;
            mb += y.r + y.g + y.b;
        }
        for (int c = 0; c < 4; ++c) {
            double mean = s[c] / spp, var = fmax(s2[c] - spp * mean * mean, 0.0) / (spp - 1);
            double se = sqrt(var / spp);
            if (c == 3)
                var_sum += var / spp;
            else
                zmax = fmax(zmax, se > 0.0 ? fabs(mean) / se : (mean == 0.0 ? 0.0 : INFINITY));
        }
    }
    *z_mean = (mb - ma) / spp / sqrt(var_sum);
    *mean_rel = (mb - ma) / ma;
    return zmax;
}

static void check_lit(const char *integrator, const char *what, int spp)
{
    rgb *t = lit_samples(moved_by_transform, integrator, 1, spp);
    rgb *v = lit_samples(moved_by_velocity, integrator, 2, spp);
    double rel, z_mean, z = max_z(t, v, spp, &z_mean, &rel);
    print_message("%s: transform vs velocity: max |z| %.2f over %d pixel channels (%d samples "
                  "each); image means differ by %.3g%% (z %.2f)\n",
                  what, z, LIT_RES * LIT_RES * 3, spp, 100 * rel, z_mean);
    /* 300 z-scores: |z| > 4.5 has probability about 0.002 under the null. */
    if (!(z < 4.5 && fabs(z_mean) < 4.0))
        fail_msg("%s: the animated box and the velocity box differ: max |z| %.2f, image mean z "
                 "%.2f",
                 what, z, z_mean);
    /* The comparison has power: a velocity box moving 0.6 times as far is told
     * apart. */
    rgb *slow = lit_samples("MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                            "\"string filename\" \"" VOLUMES "/box_velocity.vdb\" "
                            "\"string velocityname\" \"v\" \"float velocityscale\" 0.15 ",
                            integrator, 3, spp);
    double z_slow = max_z(t, slow, spp, &z_mean, &rel);
    print_message("%s: transform vs a 0.6 times slower velocity: max |z| %.2f\n", what, z_slow);
    assert_true(z_slow > 6.0);
    free(t);
    free(v);
    free(slow);
}

static void test_transform_equals_velocity(void **state)
{
    (void)state;
    check_lit("Integrator \"singlescatter\" \"string transmittance\" \"jittered\"\n", "jittered",
              64);
    check_lit("Integrator \"singlescatter\" \"string transmittance\" \"ratio\"\n", "ratio", 64);
}

/* ---- 3. No motion: bit for bit the static medium ---- */

typedef struct {
    rgb *px;
    uint64_t lookups;
} image;

static image render_image(const char *text, int threads)
{
    render_scene *rs = build_scene_or_fail(text, NULL);
    renderer_options opt = {.threads = threads, .progress = NULL};
    render_stats stats;
    hz_error err = {0};
    if (renderer_run(rs, &opt, &stats, &err) != HZ_OK)
        fail_msg("render: %s", err.message);
    film *f = render_scene_film(rs);
    const film_params *fp = film_get_params(f);
    int w = fp->bounds.x1 - fp->bounds.x0, h = fp->bounds.y1 - fp->bounds.y0;
    image im = {calloc((size_t)w * h, sizeof(rgb)), stats.density_lookups};
    assert_non_null(im.px);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            im.px[y * w + x] = film_get_pixel(f, fp->bounds.x0 + x, fp->bounds.y0 + y, 1.0);
    render_scene_destroy(rs);
    return im;
}

static image render_lit(const char *medium, const char *integrator, int threads)
{
    char head[1024];
    snprintf(head, sizeof head, "%s%sSampler \"independent\" \"integer pixelsamples\" 4\n",
             lit_head, integrator);
    char *text = scene_text(head, medium, lit_params, lit_tail);
    image im = render_image(text, threads);
    free(text);
    return im;
}

static void expect_identical(image a, image b, const char *what)
{
    if (memcmp(a.px, b.px, LIT_RES * LIT_RES * sizeof(rgb)) != 0)
        fail_msg("%s: the images differ", what);
}

static void test_no_motion_is_static(void **state)
{
    (void)state;
    static const char *integrators[] = {
        "Integrator \"singlescatter\" \"string transmittance\" \"jittered\"\n",
        "Integrator \"singlescatter\" \"string transmittance\" \"ratio\"\n",
        "Integrator \"singlescatter\" \"string transmittance\" \"raymarch\"\n",
    };
    const char *box = "Translate 0.25 0 0\nMakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                      "\"string filename\" \"" VOLUMES "/box.vdb\" ";
    const char *equal_keys =
        "ActiveTransform StartTime\nTranslate 0.25 0 0\nActiveTransform EndTime\n"
        "Translate 0.25 0 0\nActiveTransform All\nMakeNamedMedium \"box\" \"string type\" "
        "\"nanovdb\" \"string filename\" \"" VOLUMES "/box.vdb\" ";
    const char *zero_v = "Translate 0.25 0 0\nMakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                         "\"string filename\" \"" VOLUMES "/box_velocity.vdb\" "
                         "\"string velocityname\" \"v0\" ";
    const char *zero_scale = "Translate 0.25 0 0\nMakeNamedMedium \"box\" \"string type\" "
                             "\"nanovdb\" \"string filename\" \"" VOLUMES "/box_velocity.vdb\" "
                             "\"string velocityname\" \"v\" \"float velocityscale\" 0 ";
    for (size_t i = 0; i < sizeof integrators / sizeof integrators[0]; ++i) {
        image still = render_lit(box, integrators[i], 2);
        image keys = render_lit(equal_keys, integrators[i], 2);
        image zero = render_lit(zero_v, integrators[i], 2);
        image scale0 = render_lit(zero_scale, integrators[i], 2);
        expect_identical(still, keys, "equal keyframes");
        expect_identical(still, zero, "a zero velocity grid");
        expect_identical(still, scale0, "velocityscale 0");
        assert_true(still.lookups > 1000);
        assert_int_equal(keys.lookups, still.lookups);
        /* The zero grid is looked up (one velocity lookup per density lookup)
         * and changes nothing; a zero scale skips the velocity altogether. */
        assert_int_equal(zero.lookups, 2 * still.lookups);
        assert_int_equal(scale0.lookups, still.lookups);
        print_message("no motion, %s", integrators[i]);
        print_message("  %llu lookups static, %llu with the zero velocity grid\n",
                      (unsigned long long)still.lookups, (unsigned long long)zero.lookups);
        free(still.px);
        free(keys.px);
        free(zero.px);
        free(scale0.px);
    }
}

/* A moving grid does not depend on the thread count either. */
static void test_moving_threads_identical(void **state)
{
    (void)state;
    const char *integrator = "Integrator \"singlescatter\"\n";
    image a = render_lit(moved_by_velocity, integrator, 1);
    image b = render_lit(moved_by_velocity, integrator, 2);
    expect_identical(a, b, "velocity grid, 1 and 2 threads");
    image c = render_lit(moved_by_transform, integrator, 1);
    image d = render_lit(moved_by_transform, integrator, 2);
    expect_identical(c, d, "animated transform, 1 and 2 threads");
    free(a.px);
    free(b.px);
    free(c.px);
    free(d.px);
}

/* ---- 4. Bad input and the example scene ---- */

static void expect_error(const char *medium, const char *want)
{
    char *text = scene_text(lit_head, medium, "", lit_tail);
    /* The error names a place on the MakeNamedMedium line. */
    int line = 1;
    for (const char *c = text; c < strstr(text, "MakeNamedMedium"); ++c)
        line += *c == '\n';
    char place[64], msg[1024];
    snprintf(place, sizeof place, "test.pbrt:%d:", line);
    build_scene_expect_error(text, msg, sizeof msg);
    free(text);
    if (!strstr(msg, place) || !strstr(msg, want) || strchr(msg, '\n'))
        fail_msg("got \"%s\", want one line naming %s and \"%s\"", msg, place, want);
}

/* ---- 4. Moves of many majorant cells, and a shutter past TransformTimes ---- */

/* The sliding box's image (raymarched, deterministic) moved by `medium`, with
 * `camera_extra` on the Camera line; pixels scaled by `scale`. */
static image slide_image(const char *medium, const char *camera_extra)
{
    char head[1024];
    snprintf(head, sizeof head,
             "LookAt 0.5 0.5 5  0.5 0.5 0  0 1 0\n"
             "Camera \"orthographic\" \"float screenwindow\" [-1 1 -1 1] %s\n"
             "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
             "Sampler \"independent\" \"integer pixelsamples\" 16\n"
             "Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" "
             "\"float stepsize\" 0.25\n",
             camera_extra, LIT_RES, LIT_RES);
    char *text = scene_text(head, medium, slide_params, slide_tail);
    image im = render_image(text, 2);
    free(text);
    return im;
}

static void expect_close_images(image a, image b, double b_scale, const char *what)
{
    for (int p = 0; p < LIT_RES * LIT_RES; ++p)
        for (int c = 0; c < 3; ++c) {
            double x = ch(a.px[p], c), y = b_scale * ch(b.px[p], c);
            if (!(fabs(x - y) <= 1e-4 * fmax(fabs(y), 1e-3)))
                fail_msg("%s: pixel %d channel %d: %.9g vs %.9g", what, p, c, x, y);
        }
}

/* A velocity carrying the box 16 voxels (two majorant cells) renders as the
 * same move by ActiveTransform: the majorant grid covers where the density
 * is carried, not only where it starts (it used to lose 1.6% here). And rays
 * at shutter times past TransformTimes (shutterclose 2) see the density as
 * far as it is carried then: velocityscale 0.25 over [0, 2] is velocityscale
 * 0.5 over [0, 1] (the film before its exposure scaling). */
static void test_many_cell_moves(void **state)
{
    (void)state;
    const char *by_transform = "ActiveTransform EndTime\nTranslate 0.5 0.125 0\n"
                               "ActiveTransform All\nMakeNamedMedium \"box\" \"string type\" "
                               "\"nanovdb\" \"string filename\" \"" VOLUMES "/box.vdb\" ";
    const char *by_velocity = "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                              "\"string filename\" \"" VOLUMES "/box_velocity.vdb\" "
                              "\"string velocityname\" \"v\" \"float velocityscale\" 0.5 ";
    const char *slower = "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                         "\"string filename\" \"" VOLUMES "/box_velocity.vdb\" "
                         "\"string velocityname\" \"v\" \"float velocityscale\" 0.25 ";
    image a = slide_image(by_transform, ""), b = slide_image(by_velocity, "");
    image c = slide_image(slower, "\"float shutterclose\" 2");
    expect_close_images(b, a, 1.0, "16-voxel move: velocity vs transform");
    expect_close_images(c, b, 1.0, "shutter [0, 2] at half the velocity");
    free(a.px);
    free(b.px);
    free(c.px);
}

static void test_bad_input(void **state)
{
    (void)state;
    const char *file = "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" \"string filename\" "
                       "\"" VOLUMES "/box_velocity.vdb\" ";
    char m[1024];
    snprintf(m, sizeof m, "%s\"string velocityname\" \"w\"", file);
    expect_error(m, "no grid named \"w\"");
    snprintf(m, sizeof m, "%s\"string velocityname\" \"density\"", file);
    expect_error(m, "grid \"density\" is float, expected vec3s");
    snprintf(m, sizeof m, "%s\"string velocityname\" \"v\" \"float velocityscale\" -0.5", file);
    expect_error(m, "\"velocityscale\" must be finite and non-negative");
    snprintf(m, sizeof m, "%s\"string velocityname\" \"v\" \"float velocityscale\" nan", file);
    expect_error(m, "not a number");
}

static void test_example_scene_builds(void **state)
{
    (void)state;
    scene_desc sd;
    hz_error err = {0};
    if (scene_parse_file(HAZE_SCENES "/moving-smoke.pbrt", &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    render_options opt = {.spp = 1};
    render_scene *rs = NULL;
    hz_status st = render_scene_create(&sd, &opt, NULL, &rs, &err);
    scene_desc_free(&sd);
    if (st != HZ_OK)
        fail_msg("%s", err.message);
    render_scene_destroy(rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sliding_box_closed_form),
        cmocka_unit_test(test_transform_equals_velocity),
        cmocka_unit_test(test_no_motion_is_static),
        cmocka_unit_test(test_moving_threads_identical),
        cmocka_unit_test(test_many_cell_moves),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_example_scene_builds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
