/* volpath's light samplers: the BVH sampler's probabilities (light_bvh.h)
 * sum to one, agree with what it samples, and follow pbrt-v4's split between
 * unbounded (distant) lights and the tree, also in a tree as deep as the
 * lights' bit trails allow; power and uniform samplers. */
#include "media_test_util.h"
#include "core/rng.h"
#include "lights/light_sampler.h"

static const char *many_lights =
    "LookAt 0 1 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
    "LightSource \"point\" \"rgb I\" [1 2 3] \"point3 from\" [1 1 1]\n"
    "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [-3 0.5 2]\n"
    "LightSource \"spot\" \"rgb I\" [30 30 30] \"point3 from\" [0 4 0] \"point3 to\" [0 0 0] "
    "\"float coneangle\" 10\n"
    "LightSource \"spot\" \"rgb I\" [8 8 8] \"point3 from\" [2 1 -2] \"point3 to\" [3 0 -2] "
    "\"float coneangle\" 40 \"float conedeltaangle\" 10\n"
    "LightSource \"distant\" \"rgb L\" [1 1 1] \"point3 from\" [0 1 0] \"point3 to\" [0 0 0]\n"
    "LightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\n"
    "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nTranslate 0 2 3\n"
    "Shape \"sphere\" \"float radius\" 0.3\nAttributeEnd\n"
    "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2] \"bool twosided\" true\n"
    "Shape \"trianglemesh\" \"point3 P\" [-1 3 -1  1 3 -1  1 3 1] \"integer indices\" [0 1 2]\n"
    "AttributeEnd\n"
    "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 1 1]\n"
    "Shape \"trianglemesh\" \"point3 P\" [4 0 0  4 1 0  4 0 1] \"integer indices\" [0 1 2]\n"
    "AttributeEnd\n";

static void test_bvh_probabilities(void **state)
{
    (void)state;
    render_scene *rs = build(many_lights);
    const light *lights = render_scene_lights(rs);
    size_t n = render_scene_light_count(rs);
    assert_int_equal(n, 9);
    light_sampler ls;
    hz_error err = {0};
    assert_int_equal(light_sampler_create(LIGHT_SAMPLER_BVH, lights, n, 10.0, &ls, &err), HZ_OK);
    /* One distant light, one tree: each has probability 1/2. */
    assert_int_equal(ls.bvh.unbounded_count, 1);
    rng r = rng_seeded(42);
    int checked = 0;
    for (int k = 0; k < 60; ++k) {
        vec3 p = v3(8.0 * rng_uniform(&r) - 4.0, 5.0 * rng_uniform(&r) - 1.0,
                    8.0 * rng_uniform(&r) - 4.0);
        vec3 nrm = k % 2 ? v3_normalize(v3(rng_uniform(&r) - 0.5, 1.0, rng_uniform(&r) - 0.5))
                         : v3(0.0, 0.0, 0.0);
        double sum = 0.0, pmf[9];
        for (size_t i = 0; i < n; ++i) {
            pmf[i] = light_sampler_pmf(&ls, p, nrm, i);
            assert_true(pmf[i] >= 0.0);
            sum += pmf[i];
        }
        assert_float_equal(pmf[4], 0.5, 1e-15);                  /* the distant light */
        assert_float_equal(light_sampler_pmf(&ls, p, nrm, 5), 0.0, 0.0); /* the sky */
        if (sum > 0.5 + 1e-12)
            assert_float_equal(sum, 1.0, 1e-12);
        /* Sampling frequencies follow the pmf; each sample reports its pmf. */
        enum { N = 20000 };
        int count[9] = {0};
        for (int j = 0; j < N; ++j) {
            size_t li;
            double p_li;
            if (!light_sampler_sample(&ls, p, nrm, (j + 0.5) / N, &li, &p_li))
                continue;
            assert_float_equal(p_li, pmf[li], 1e-12 * (1.0 + pmf[li]));
            count[li]++;
        }
        for (size_t i = 0; i < n; ++i)
            assert_true(fabs(count[i] / (double)N - pmf[i]) < 2.0 / N + 1e-9 * N);
        checked++;
    }
    assert_int_equal(checked, 60);
    light_sampler_free(&ls);
    render_scene_destroy(rs);
}

/* The probability of reaching each leaf from node i (probability `prob`),
 * by the tree's own links (not the lights' bit trails): into ref. */
static void leaf_probabilities(const light_bvh *b, size_t i, vec3 p, vec3 n, double prob,
                               double *ref)
{
    const light_bvh_node *nd = &b->nodes[i];
    if (nd->leaf) {
        ref[nd->index] = prob;
        return;
    }
    double c0 = light_bounds_importance(&b->nodes[i + 1].b, p, n);
    double c1 = light_bounds_importance(&b->nodes[nd->index].b, p, n);
    leaf_probabilities(b, i + 1, p, n, prob * c0 / (c0 + c1), ref);
    leaf_probabilities(b, nd->index, p, n, prob * c1 / (c0 + c1), ref);
}

static int tree_depth(const light_bvh *b, size_t i)
{
    const light_bvh_node *nd = &b->nodes[i];
    if (nd->leaf)
        return 0;
    int d0 = tree_depth(b, i + 1), d1 = tree_depth(b, nd->index);
    return 1 + (d0 > d1 ? d0 : d1);
}

/* 80 sphere lights at x = 2^-k, each 1/8 of its distance from 0 in radius:
 * the bucketed split peels one light per level, a chain deeper than the 64
 * bits of a light's trail. The tree must stop at 64 levels (deeper, the trail
 * shifted 1 << 64: undefined) and every light's pmf must follow its path. */
static void test_bvh_deep_chain(void **state)
{
    (void)state;
    enum { LIGHTS = 80 };
    size_t cap = 1 << 16, len = 0;
    char *text = malloc(cap);
    assert_non_null(text);
    len += (size_t)snprintf(text, cap, "Film \"rgb\" \"integer xresolution\" 4 "
                                       "\"integer yresolution\" 4\nWorldBegin\n");
    for (int k = 0; k < LIGHTS; ++k)
        len += (size_t)snprintf(text + len, cap - len,
                                "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
                                "Translate %.17g 0 0\nShape \"sphere\" \"float radius\" %.17g\n"
                                "AttributeEnd\n",
                                ldexp(1.0, -k), ldexp(1.0, -k - 3));
    assert_true(len < cap);
    render_scene *rs = build(text);
    free(text);
    size_t n = render_scene_light_count(rs);
    assert_int_equal(n, LIGHTS);
    light_sampler ls;
    hz_error err = {0};
    assert_int_equal(light_sampler_create(LIGHT_SAMPLER_BVH, render_scene_lights(rs), n, 10.0,
                                          &ls, &err),
                     HZ_OK);
    int depth = tree_depth(&ls.bvh, 0);
    assert_true(depth >= 60 && depth <= 64);
    const vec3 points[] = {v3(0.3, 1.0, 0.0), v3(1e-9, 0.5, 0.2), v3(2.0, -1.0, 1.0),
                           v3(-0.5, 0.0, 0.001)};
    for (size_t k = 0; k < sizeof points / sizeof points[0]; ++k) {
        double ref[LIGHTS] = {0}, sum = 0.0;
        leaf_probabilities(&ls.bvh, 0, points[k], v3(0, 0, 0), 1.0, ref);
        for (size_t i = 0; i < n; ++i) {
            double pmf = light_sampler_pmf(&ls, points[k], v3(0, 0, 0), i);
            if (!(ref[i] > 0.0) || fabs(pmf - ref[i]) > 1e-12 * ref[i])
                fail_msg("point %zu, light %zu: pmf %g, its path's probability %g", k, i, pmf,
                         ref[i]);
            sum += pmf;
        }
        assert_float_equal(sum, 1.0, 1e-12);
    }
    light_sampler_free(&ls);
    render_scene_destroy(rs);
}

/* Importance: zero outside a spot light's cone (beyond its falloff), falling
 * as 1/d² with distance, and cut by a surface facing away. */
static void test_bounds_importance(void **state)
{
    (void)state;
    light_bounds spot = {v3(0, 0, 0), v3(0, 0, 0), 10.0, v3(0, 0, 1), cos(0.2), cos(0.1), false};
    assert_true(light_bounds_importance(&spot, v3(0, 0, 5), v3(0, 0, 0)) > 0.0);
    assert_float_equal(light_bounds_importance(&spot, v3(5, 0, 0.1), v3(0, 0, 0)), 0.0, 0.0);
    light_bounds point = {v3(0, 0, 0), v3(0, 0, 0), 10.0, v3(0, 0, 1), -1.0, 0.0, false};
    double a = light_bounds_importance(&point, v3(0, 2, 0), v3(0, 0, 0));
    double b = light_bounds_importance(&point, v3(0, 4, 0), v3(0, 0, 0));
    assert_float_equal(a / b, 4.0, 1e-12);
    assert_float_equal(light_bounds_importance(&point, v3(0, 2, 0), v3(1, 0, 0)), 0.0, 1e-15);
}

/* Power: probabilities in proportion to RGB-averaged phi; uniform: equal. */
static void test_power_and_uniform(void **state)
{
    (void)state;
    render_scene *rs = build(many_lights);
    const light *lights = render_scene_lights(rs);
    size_t n = render_scene_light_count(rs);
    light_sampler ls;
    hz_error err = {0};
    assert_int_equal(light_sampler_create(LIGHT_SAMPLER_POWER, lights, n, 10.0, &ls, &err), HZ_OK);
    double phi0 = 4.0 * HZ_PI * 2.0, phi1 = 4.0 * HZ_PI * 5.0; /* the two point lights */
    vec3 o = v3(0, 0, 0);
    assert_float_equal(light_sampler_pmf(&ls, o, o, 0) / light_sampler_pmf(&ls, o, o, 1),
                       phi0 / phi1, 1e-12);
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i)
        sum += light_sampler_pmf(&ls, o, o, i);
    assert_float_equal(sum, 1.0, 1e-12);
    light_sampler_free(&ls);
    assert_int_equal(light_sampler_create(LIGHT_SAMPLER_UNIFORM, lights, n, 10.0, &ls, &err),
                     HZ_OK);
    assert_float_equal(light_sampler_pmf(&ls, o, o, 0), 1.0 / 8.0, 1e-15);
    assert_float_equal(light_sampler_pmf(&ls, o, o, 5), 0.0, 0.0);
    light_sampler_free(&ls);
    render_scene_destroy(rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bvh_probabilities),
        cmocka_unit_test(test_bvh_deep_chain),
        cmocka_unit_test(test_bounds_importance),
        cmocka_unit_test(test_power_and_uniform),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
