/* The shadow cache ("float shadowcache" of Integrator "singlescatter" and
 * "volpath"): closed-form transmittance through a uniform box under a tilted
 * distant light, a surface's shadow, convergence against exact shadow rays,
 * volpath's image against its shadow rays, and the scenes it refuses. */
#include "media_test_util.h"

#include "integrator/shadow_cache.h"

/* Density 1 over [-2, 2]^3 (4^3 voxels of 1), sigma_t (0.75, 1, 1.5) or,
 * `grey`, 1, seen through an interface box
 * [-1, 1]^3; a distant light along w ~ (0.1, 1, 0.1); an opaque quad at
 * y = 1.5 over x >= 0.3 shades part of the box. Rendered by `integrator`
 * (its name and parameters; NULL: singlescatter's raymarch) with the cache
 * at `spacing`. */
static char *box_scene_by(const char *integrator, double spacing, bool occluder, bool grey)
{
    char *box = box_mesh(v3(-1, -1, -1), v3(1, 1, 1));
    char *s = sfmt(
        "LookAt 0 0 -6  0 0 0  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 30\n"
        "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
        "Integrator %s \"float shadowcache\" %g\n"
        "WorldBegin\n"
        "LightSource \"distant\" \"point3 from\" [0.1 1 0.1] \"point3 to\" [0 0 0] \"rgb L\" [1 1 1]\n"
        "MakeNamedMedium \"m\" \"string type\" \"uniformgrid\" \"integer nx\" 4 \"integer ny\" 4\n"
        "  \"integer nz\" 4 \"point3 p0\" [-2 -2 -2] \"point3 p1\" [2 2 2]\n"
        "  \"float density\" [1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1\n"
        "                     1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1]\n"
        "  \"rgb sigma_a\" %s \"rgb sigma_s\" [0.5 0.5 0.5]\n"
        "AttributeBegin\n  Material \"interface\"\n  MediumInterface \"m\" \"\"\n  %s\nAttributeEnd\n"
        "%s",
        integrator ? integrator : "\"singlescatter\" \"string transmittance\" \"raymarch\"",
        spacing, grey ? "[0.5 0.5 0.5]" : "[0.25 0.5 1]", box,
        occluder ? "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
                   "  \"point3 P\" [0.3 1.5 -3  3 1.5 -3  3 1.5 3  0.3 1.5 3]\n"
                 : "");
    free(box);
    return s;
}

static char *box_scene(double spacing, bool occluder, bool grey)
{
    return box_scene_by(NULL, spacing, occluder, grey);
}

static vec3 render_point(const render_scene *rs, vec3 world)
{
    transform render_from_world = transform_inverse(render_scene_camera(rs)->world_from_render);
    return transform_point(&render_from_world, world);
}

/* Inside the box, where every node a lookup reads lies on a column that
 * leaves through the top face, the optical depth is linear across the
 * light and along it, which the interpolation reproduces: the cache gives
 * exp(-sigma_t (1 - y) / w_y) to float precision. Under the quad it is 0. */
static void check_closed_form(bool grey)
{
    char *text = box_scene(0.125, true, grey);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    const shadow_cache *c = shadow_caches_get(render_scene_shadow_caches(rs), 0, 0);
    assert_non_null(c);
    vec3 w = v3_normalize(v3(0.1, 1.0, 0.1));
    rgb sigma_t = grey ? rgb_grey(1.0) : rgb_make(0.75, 1.0, 1.5);
    rng r = rng_seeded(7);
    double worst = 0.0;
    for (int k = 0; k < 200; ++k) {
        vec3 p = v3(-0.5 + 0.2 * rng_uniform(&r), -0.5 + rng_uniform(&r),
                    -0.2 + 0.4 * rng_uniform(&r));
        rgb T = shadow_cache_transmittance(c, render_point(rs, p), NULL);
        double d = (1.0 - p.y) / w.y;
        for (int ch = 0; ch < 3; ++ch) {
            double want = exp(-rgb_ch(sigma_t, ch) * d);
            worst = fmax(worst, fabs(rgb_ch(T, ch) / want - 1.0));
        }
        vec3 q = v3(0.6 + 0.1 * rng_uniform(&r), p.y, p.z);
        rgb T0 = shadow_cache_transmittance(c, render_point(rs, q), NULL);
        assert_true(T0.r == 0.0 && T0.g == 0.0 && T0.b == 0.0);
    }
    print_message("closed form: worst relative error %.3g\n", worst);
    assert_true(worst < 1e-5);
    render_memory mem = render_scene_memory(rs);
    assert_true(mem.shadow_caches > 0.0);
    render_scene_destroy(rs);
}

static void test_closed_form(void **state)
{
    (void)state;
    check_closed_form(false);
    check_closed_form(true);
}

/* The fog sphere marched at step 1 voxel, with shadow rays (a quarter voxel)
 * or a cache. */
static char *sphere_scene(double cache) { return fog_sphere_scene("raymarch", 1.0, 0.25, cache); }

/* Against exact shadow rays (marched at a quarter voxel), the whole image's
 * relMSE falls as the spacing shrinks, and is small at half a voxel. */
static void test_converges_to_shadow_rays(void **state)
{
    (void)state;
    char *text = sphere_scene(0.0);
    render_scene *exact = build_scene_or_fail(text, NULL);
    free(text);
    assert_null(render_scene_shadow_caches(exact));
    double prev = INFINITY, mean = 0.0;
    const double spacings[3] = {2.0, 1.0, 0.5};
    for (int k = 0; k < 3; ++k) {
        text = sphere_scene(spacings[k]);
        render_scene *rs = build_scene_or_fail(text, NULL);
        free(text);
        double e = centre_rel_mse(rs, exact, 32, 32, 1, &mean);
        print_message("spacing %g voxels: relMSE %.3g against shadow rays (image mean %.4g)\n",
                      spacings[k], e, mean);
        assert_true(e < prev);
        prev = e;
        render_scene_destroy(rs);
    }
    assert_true(mean > 0.01); /* the image is not black */
    assert_true(prev < 1e-5);
    render_scene_destroy(exact);
}

/* The mean over a w x h image of the difference between scenes a and b,
 * sample by sample (the same pixel, sample index and so random numbers, up
 * to where the two estimators part), and its standard error; *b_mean gets
 * b's mean, per channel. */
static void paired_difference(const render_scene *a, const render_scene *b, int w, int h, int spp,
                              double mean[3], double se[3], double b_mean[3])
{
    sampler sa = *render_scene_sampler(a), sb = *render_scene_sampler(b);
    sampler_set_spp(&sa, spp);
    sampler_set_spp(&sb, spp);
    integrator_counters counters = {0};
    double s[3] = {0}, s2[3] = {0}, sum_b[3] = {0};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            camera_sample cs = {v2(x + 0.5, y + 0.5), v2(0.5, 0.5), 0.5, 1.0};
            ray_differential rd;
            assert_true(camera_generate_ray_differential(render_scene_camera(a), cs, &rd));
            for (int i = 0; i < spp; ++i) {
                sampler_state st;
                double depth;
                sampler_start(&sa, x, y, i, &st);
                rgb la = render_scene_li(a, &rd, &st, &depth, &counters);
                sampler_start(&sb, x, y, i, &st);
                rgb lb = render_scene_li(b, &rd, &st, &depth, &counters);
                for (int c = 0; c < 3; ++c) {
                    double d = rgb_ch(la, c) - rgb_ch(lb, c);
                    s[c] += d;
                    s2[c] += d * d;
                    sum_b[c] += rgb_ch(lb, c);
                }
            }
        }
    double n = (double)w * h * spp;
    for (int c = 0; c < 3; ++c) {
        mean[c] = s[c] / n;
        se[c] = sqrt(fmax(s2[c] / n - mean[c] * mean[c], 0.0) / (n - 1.0));
        b_mean[c] = sum_b[c] / n;
    }
}

/* Under volpath the cache stands in for the shadow rays of scattering
 * vertices in the medium: the image of the lit, partly shaded box is the
 * one of exact shadow rays (ratio tracking) within noise, for single and
 * multiple scattering, grey and chromatic (where the hero channel's MIS
 * weights see a shadow estimate without noise), and the render looks up
 * the density fewer times (no shadow rays through the box). Sample by
 * sample the two estimates share their paths up to the first shadow ray
 * (under maxdepth 1 nothing after it counts), so the difference's noise is
 * the shadow rays' own: a bias of 4% of the image would be 4 standard
 * errors. */
static void check_volpath(int maxdepth, bool grey)
{
    char integ[128];
    snprintf(integ, sizeof integ, "\"volpath\" \"integer maxdepth\" %d", maxdepth);
    render_scene *rs[2];
    uint64_t lookups[2];
    for (int k = 0; k < 2; ++k) {
        char *text = box_scene_by(integ, k == 0 ? 0.0 : 0.125, true, grey);
        rs[k] = build_scene_or_fail(text, NULL);
        free(text);
        assert_true((render_scene_shadow_caches(rs[k]) != NULL) == (k == 1));
        lookups[k] = pixel_stats_raw(rs[k], 8, 6, 256).lookups;
    }
    double d[3], se[3], mean[3];
    paired_difference(rs[1], rs[0], 16, 16, 1024, d, se, mean);
    for (int c = 0; c < 3; ++c) {
        print_message("volpath maxdepth %d%s, channel %d: image mean %.5f, cache - shadow rays "
                      "%+.2e +- %.1e\n",
                      maxdepth, grey ? " grey" : "", c, mean[c], d[c], se[c]);
        assert_true(mean[c] > 1e-3); /* not black */
        assert_true(se[c] < 1e-2 * mean[c]);
        assert_true(fabs(d[c]) < 4.0 * se[c]);
    }
    print_message("density lookups at a pixel: %llu with shadow rays, %llu with the cache\n",
                  (unsigned long long)lookups[0], (unsigned long long)lookups[1]);
    assert_true(lookups[1] < lookups[0]);
    render_scene_destroy(rs[0]);
    render_scene_destroy(rs[1]);
}

static void test_volpath(void **state)
{
    (void)state;
    check_volpath(1, true);
    check_volpath(1, false);
    check_volpath(8, false);
}

static void expect_refused(const char *text, const char *what)
{
    char msg[1024];
    build_scene_expect_error(text, msg, sizeof msg);
    print_message("%s\n", msg);
    assert_non_null(strstr(msg, "test.pbrt:"));
    assert_non_null(strstr(msg, "shadowcache"));
    assert_non_null(strstr(msg, what));
}

/* Refused where it would change nothing, or could not hold, under either
 * integrator (`integrator` as box_scene_by's). */
static void check_refusals(const char *integrator)
{
    char *text = box_scene_by(integrator, -1.0, false, false);
    expect_refused(text, ">= 0");
    free(text);
    text = box_scene_by(integrator, 1.0, false, false);
    char *p = strstr(text, "LightSource \"distant\""), *end = p ? strchr(p, '\n') : NULL;
    assert_non_null(end);
    char *point = sfmt("%.*sLightSource \"point\" \"point3 from\" [0 3 0] \"rgb I\" [1 1 1]%s",
                       (int)(p - text), text, end);
    expect_refused(point, "no distant light");
    free(point);
    char *moving = sfmt("%.*sActiveTransform EndTime\nTranslate 0.5 0 0\nActiveTransform All\n%s",
                        (int)(strstr(text, "MakeNamedMedium") - text), text,
                        strstr(text, "MakeNamedMedium"));
    expect_refused(moving, "static scene");
    free(moving);
    free(text);
}

static void test_refusals(void **state)
{
    (void)state;
    check_refusals(NULL);
    check_refusals("\"volpath\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_form),
        cmocka_unit_test(test_converges_to_shadow_rays),
        cmocka_unit_test(test_volpath),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
