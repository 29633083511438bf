#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "film/filter.h"
#include "scene/params.h"
#include "unit/filter_util.h"

static double gauss(double x, double s) { return exp(-x * x / (2 * s * s)) / sqrt(2 * HZ_PI * s * s); }

static void test_defaults_and_values(void **state)
{
    (void)state;
    filter *f = make_filter("box");
    assert_int_equal(filter_get_kind(f), FILTER_BOX);
    assert_true(filter_radius(f).x == 0.5 && filter_radius(f).y == 0.5);
    assert_true(filter_evaluate(f, v2(0.3, -0.4)) == 1.0);
    assert_true(filter_evaluate(f, v2(0.6, 0.0)) == 0.0);
    assert_true(filter_integral(f) == 1.0);
    filter_destroy(f);

    f = make_filter("triangle");
    assert_true(filter_radius(f).x == 2.0 && filter_radius(f).y == 2.0);
    assert_float_equal(filter_evaluate(f, v2(0.5, -1.0)), 1.5 * 1.0, 1e-15);
    assert_true(filter_evaluate(f, v2(2.5, 0.0)) == 0.0);
    assert_float_equal(filter_integral(f), 16.0, 1e-12);
    filter_destroy(f);

    f = make_filter("gaussian");
    assert_true(filter_radius(f).x == 1.5 && filter_radius(f).y == 1.5);
    double want = (gauss(0.3, 0.5) - gauss(1.5, 0.5)) * (gauss(0.2, 0.5) - gauss(1.5, 0.5));
    assert_float_equal(filter_evaluate(f, v2(0.3, 0.2)), want, 1e-14);
    assert_true(filter_evaluate(f, v2(1.6, 0.0)) == 0.0);
    filter_destroy(f);

    f = make_filter("mitchell");
    assert_true(filter_radius(f).x == 2.0 && filter_radius(f).y == 2.0);
    /* B = C = 1/3: Mitchell1D(0.5) = (7/8 - 3 + 16/3)/6, Mitchell1D(0) = 8/9,
     * Mitchell1D(1.5) = (-7/3*3.375 + 27 - 30 + 32/3)/6 (negative lobe). */
    double m05 = (0.875 - 3.0 + 16.0 / 3.0) / 6.0, m0 = 8.0 / 9.0;
    double m15 = (-7.0 / 3.0 * 3.375 + 27.0 - 30.0 + 32.0 / 3.0) / 6.0;
    assert_float_equal(filter_evaluate(f, v2(0.5, 0.0)), m05 * m0, 1e-14); /* pbrt: Mitchell1D(2x/r) */
    /* y = 1 -> Mitchell1D(1) = (7 - 12 + 16/3)/6 = 1/18. */
    assert_float_equal(filter_evaluate(f, v2(1.5, 1.0)), m15 / 18.0, 1e-14);
    assert_true(m15 < 0.0);
    assert_float_equal(filter_integral(f), 1.0, 1e-15);
    filter_destroy(f);

    f = make_filter("sinc");
    assert_int_equal(filter_get_kind(f), FILTER_LANCZOS);
    assert_true(filter_radius(f).x == 4.0);
    double s = sin(HZ_PI * 0.5) / (HZ_PI * 0.5) * sin(HZ_PI * 0.5 / 3) / (HZ_PI * 0.5 / 3);
    assert_float_equal(filter_evaluate(f, v2(0.5, 0.0)), s, 1e-12);
    filter_destroy(f);
}

typedef struct {
    double w, wg, wabs; /* means of weight, weight*g, |weight| */
    int negative;
} sample_stats;

static double next_u(uint64_t *x)
{
    *x ^= *x << 13; /* xorshift64: deterministic jitter for the test */
    *x ^= *x >> 7;
    *x ^= *x << 17;
    return (double)(*x >> 11) * 0x1p-53;
}

/* Mean over a 1024x1024 jittered grid of u: unbiased and low variance. (A
 * regular grid is not enough for signed weights: it quantises the few
 * samples landing in the small negative lobes.) */
static sample_stats sample_moments(const filter *f)
{
    sample_stats s = {0};
    const int n = 1024;
    uint64_t rng = 0x853c49e6748fea9bull;
    vec2 r = filter_radius(f);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double ux = (i + next_u(&rng)) / n, uy = (j + next_u(&rng)) / n;
            filter_sample fs = filter_sample_offset(f, v2(ux, uy));
            assert_true(fabs(fs.p.x) <= r.x && fabs(fs.p.y) <= r.y);
            assert_true(isfinite(fs.weight));
            s.w += fs.weight;
            s.wg += fs.weight * fs.p.x * fs.p.x;
            s.wabs += fabs(fs.weight);
            s.negative += fs.weight < 0.0;
        }
    s.w /= (double)n * n;
    s.wg /= (double)n * n;
    s.wabs /= (double)n * n;
    return s;
}

/* ∫ f(x,y) x² / ∫ f by midpoint quadrature in x (f is separable). */
static double quadrature_x2(const filter *f)
{
    const int n = 200000;
    double r = filter_radius(f).x, num = 0.0, den = 0.0;
    for (int i = 0; i < n; i++) {
        double x = -r + 2 * r * (i + 0.5) / n;
        double v = filter_evaluate(f, v2(x, 0.0));
        num += v * x * x;
        den += v;
    }
    return num / den;
}

static void test_box_triangle_sampling(void **state)
{
    (void)state;
    filter *f = make_filter("box");
    sample_stats s = sample_moments(f);
    assert_true(s.w == 1.0 && s.negative == 0);
    assert_float_equal(s.wg, 0.25 / 3.0, 1e-4); /* E[x²] of uniform on [-r, r] = r²/3 */
    filter_destroy(f);

    f = make_filter("triangle");
    s = sample_moments(f);
    assert_true(s.w == 1.0);
    assert_float_equal(s.wg, 4.0 / 6.0, 2e-3); /* tent: E[x²] = r²/6 */
    filter_destroy(f);
}

static void check_tabulated(const char *type, double integral)
{
    filter *f = make_filter(type);
    sample_stats s = sample_moments(f);
    /* E[weight] estimates the filter's integral: normalisation is exact. */
    assert_float_equal(s.w, integral, 0.01 * fabs(integral));
    double want = quadrature_x2(f);
    double got = s.wg / s.w;
    if (fabs(got - want) > 0.01 * fabs(want))
        fail_msg("%s: E[w x^2]/E[w] = %g, quadrature %g", type, got, want);
    filter_destroy(f);
}

static void test_tabulated_sampling(void **state)
{
    (void)state;
    double g = erf(1.5 / (0.5 * sqrt(2.0))) - 3.0 * gauss(1.5, 0.5);
    check_tabulated("gaussian", g * g);
    check_tabulated("mitchell", 1.0);
    /* Mitchell has negative lobes: some weights must be negative. */
    filter *f = make_filter("mitchell");
    sample_stats s = sample_moments(f);
    assert_true(s.negative > 0);
    assert_true(s.wabs > s.w);
    filter_destroy(f);
    /* Gaussian weights are all the same positive constant (f/pdf). */
    f = make_filter("gaussian");
    filter_sample a = filter_sample_offset(f, v2(0.1, 0.7)), b = filter_sample_offset(f, v2(0.9, 0.3));
    assert_true(a.weight > 0.0 && a.weight == b.weight);
    filter_destroy(f);
}

static void test_parameters(void **state)
{
    (void)state;
    scene_entity e;
    entity_init(&e, "gaussian");
    add_float(&e, "xradius", 2.0);
    add_float(&e, "yradius", 1.0);
    add_float(&e, "sigma", 0.7);
    hz_error err = {0};
    filter *f = filter_create(&e, &err);
    assert_non_null(f);
    assert_true(filter_radius(f).x == 2.0 && filter_radius(f).y == 1.0);
    double want = (gauss(0.5, 0.7) - gauss(2.0, 0.7)) * (gauss(0.5, 0.7) - gauss(1.0, 0.7));
    assert_float_equal(filter_evaluate(f, v2(0.5, 0.5)), want, 1e-14);
    filter_destroy(f);
    entity_free(&e);

    entity_init(&e, "mitchell");
    add_float(&e, "B", 0.0);
    add_float(&e, "C", 0.5);
    f = filter_create(&e, &err);
    assert_non_null(f); /* Catmull-Rom */
    assert_float_equal(filter_evaluate(f, v2(0.0, 0.0)), 1.0, 1e-15);
    filter_destroy(f);
    entity_free(&e);
}

static void expect_error(scene_entity *e, const char *needle)
{
    hz_error err = {0};
    filter *f = filter_create(e, &err);
    assert_null(f);
    if (!strstr(err.message, needle))
        fail_msg("error \"%s\" does not mention \"%s\"", err.message, needle);
    assert_non_null(strstr(err.message, "test.pbrt:3:"));
    entity_free(e);
}

static void test_errors(void **state)
{
    (void)state;
    scene_entity e;
    entity_init(&e, "lanczo");
    expect_error(&e, "\"mitchell\"");
    entity_init(&e, "box");
    add_float(&e, "radius", 1.0); /* pbrt-v4 names are xradius/yradius */
    expect_error(&e, "radius");
    entity_init(&e, "triangle");
    add_float(&e, "xradius", -1.0);
    expect_error(&e, "xradius");
    entity_init(&e, "gaussian");
    add_float(&e, "sigma", 0.0);
    expect_error(&e, "sigma");
    entity_init(&e, "gaussian");
    add_float(&e, "xradius", 1e9);
    expect_error(&e, "xradius");
    entity_init(&e, "gaussian");
    add_int(&e, "xradius", 2); /* wrong type */
    expect_error(&e, "xradius");
    entity_init(&e, "mitchell");
    add_float(&e, "B", NAN);
    expect_error(&e, "B");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_and_values),
        cmocka_unit_test(test_box_triangle_sampling),
        cmocka_unit_test(test_tabulated_sampling),
        cmocka_unit_test(test_parameters),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
