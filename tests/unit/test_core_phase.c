/* media/phase: the Henyey–Greenstein phase function (normalisation, mean cosine,
 * pbrt-v4's direction convention) and its sampling (density, pdf, unit vectors,
 * extreme g). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include "sampler/sampler_math.h"
#include "core/rng.h"
#include "core/phase.h"
#include "unit/assert_util.h"

#define QUAD_N 200000

/* ∫_{-1}^{1} 2π p(μ) f(μ) dμ by the midpoint rule in x after μ = -1 + 2 w(x) with
 * w the quintic smoothstep (w' = 30 x² (1 - x)²): the nodes crowd at both poles,
 * where HG with |g| near 1 has its narrow peak. moment 0: f = 1; moment 1: f = -μ. */
static double hg_moment(double g, int moment)
{
    double sum = 0.0;
    for (int i = 0; i < QUAD_N; ++i) {
        double x = (i + 0.5) / QUAD_N;
        double w = x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
        double dw = 30.0 * x * x * (1.0 - x) * (1.0 - x);
        double mu = -1.0 + 2.0 * w;
        double f = moment == 0 ? 1.0 : -mu;
        sum += 2.0 * HZ_PI * hg_phase(mu, g) * f * 2.0 * dw;
    }
    return sum / QUAD_N;
}

static const double gs[] = {0.0, 0.3, -0.7, 0.9, 0.99, -0.99, 1e-4, -5e-4};

static void phase_integrates_to_one(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof gs / sizeof gs[0]; ++i)
        assert_near(hg_moment(gs[i], 0), 1.0, 1e-6);
}

/* pbrt-v4 convention: wo points back toward the viewer, so the mean of
 * dot(-wo, wi) = -μ is g. */
static void phase_mean_cosine_is_g(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof gs / sizeof gs[0]; ++i)
        assert_near(hg_moment(gs[i], 1), gs[i], 1e-6);
}

static void phase_known_values(void **state)
{
    (void)state;
    for (double c = -1.0; c <= 1.0; c += 0.25)
        assert_near(hg_phase(c, 0.0), 1.0 / (4.0 * HZ_PI), 1e-17);
    /* Forward scattering (g > 0) peaks at dot(wo, wi) = -1. */
    double g = 0.5;
    assert_near(hg_phase(-1.0, g), (1 - g * g) / (4 * HZ_PI * pow(1 - g, 3)), 1e-14);
    assert_near(hg_phase(1.0, g), (1 - g * g) / (4 * HZ_PI * pow(1 + g, 3)), 1e-14);
    assert_true(hg_phase(-1.0, g) > hg_phase(1.0, g));
    assert_true(hg_phase(1.0, -g) > hg_phase(-1.0, -g));
    /* The textbook formula at a generic point. */
    double c = 0.3, want = (1 - g * g) / (4 * HZ_PI * pow(1 + g * g + 2 * g * c, 1.5));
    assert_near(hg_phase(c, g), want, 1e-15);
    /* Symmetry p(c, g) = p(-c, -g). */
    assert_near(hg_phase(0.7, -0.8), hg_phase(-0.7, 0.8), 1e-12);
}

static void phase_extreme_g_is_finite(void **state)
{
    (void)state;
    const double ext[] = {0.99999, -0.99999, 1.0 - 1e-9, -(1.0 - 1e-9)};
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; ++i) {
        double g = ext[i];
        for (double c = -1.0; c <= 1.0; c += 1.0 / 64) {
            double p = hg_phase(c, g);
            if (!(isfinite(p) && p > 0.0))
                fail_msg("hg_phase(%g, %.17g) = %g", c, g, p);
        }
        /* Peak value (1 + |g|) / (4π (1 - |g|)²): relative precision kept. */
        double a = fabs(g);
        double peak = (1 + a) / (4 * HZ_PI * (1 - a) * (1 - a));
        double got = hg_phase(g > 0 ? -1.0 : 1.0, g);
        if (!(fabs(got - peak) <= 1e-6 * peak))
            fail_msg("peak for g = %.17g: got %.17g, want %.17g", g, got, peak);
    }
    assert_near(hg_moment(0.99999, 0), 1.0, 1e-5);
}

/* Radical inverse base 2 (van der Corput). */
static double van_der_corput(uint32_t i) { return smp_reverse_bits32(i) * 0x1p-32; }

#define SAMPLES 200000
#define BINS 20

/* ∫ over the μ bin [a, b] of 2π p(μ) dμ (midpoint rule, fine enough away from
 * the peak for the g used with it). */
static double bin_mass(double g, double a, double b)
{
    const int n = 20000;
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        sum += hg_phase(a + (b - a) * (i + 0.5) / n, g);
    return 2.0 * HZ_PI * sum * (b - a) / n;
}

static void check_sampling(vec3 wo, double g)
{
    double sum = 0.0, sum_sq = 0.0;
    vec3 mean_wi = v3(0, 0, 0);
    double hist[BINS] = {0};
    for (uint32_t i = 0; i < SAMPLES; ++i) {
        vec2 u = v2((i + 0.5) / SAMPLES, van_der_corput(i));
        double pdf = -1.0;
        vec3 wi = hg_sample(wo, g, u, &pdf);
        assert_near(v3_length(wi), 1.0, 1e-12);
        double mu = v3_dot(wo, wi);
        double want = hg_phase(mu, g);
        if (!(fabs(pdf - want) <= 1e-9 * want))
            fail_msg("g = %g, u = (%g, %g): pdf %.17g, hg_phase %.17g", g, u.x, u.y, pdf, want);
        sum += -mu;
        sum_sq += mu * mu;
        mean_wi = v3_add(mean_wi, wi);
        int b = (int)((mu + 1.0) * 0.5 * BINS);
        hist[b < 0 ? 0 : (b >= BINS ? BINS - 1 : b)] += 1.0;
    }
    double mean = sum / SAMPLES;
    double se = sqrt(fmax(sum_sq / SAMPLES - mean * mean, 0.0) / SAMPLES);
    if (!(fabs(mean - g) <= fmax(3.0 * se, 1e-4)))
        fail_msg("g = %g: mean of dot(-wo, wi) = %.9g (standard error %g)", g, mean, se);
    /* Azimuthal symmetry around wo: the mean direction is -g wo. */
    assert_v3_near(v3_scale(mean_wi, 1.0 / SAMPLES), v3_scale(wo, -g), 2e-3);
    /* The distribution of μ matches the density (stratified u.x makes the bin
     * fractions accurate to about 1/SAMPLES). */
    for (int b = 0; b < BINS; ++b) {
        double lo = -1.0 + 2.0 * b / BINS, hi = lo + 2.0 / BINS;
        double want = bin_mass(g, lo, hi);
        if (!(fabs(hist[b] / SAMPLES - want) <= 1e-3))
            fail_msg("g = %g, bin [%g, %g): fraction %.6f, want %.6f", g, lo, hi,
                     hist[b] / SAMPLES, want);
    }
}

static void sample_matches_density(void **state)
{
    (void)state;
    const double g_list[] = {0.0, 0.3, -0.7, 0.9, 5e-4, -2e-3};
    vec3 wos[] = {v3(0, 0, 1), v3(0, 0, -1), v3_normalize(v3(0.3, -0.5, 0.8)),
                  v3_normalize(v3(-2, 1, -0.1))};
    for (size_t w = 0; w < sizeof wos / sizeof wos[0]; ++w)
        for (size_t i = 0; i < sizeof g_list / sizeof g_list[0]; ++i)
            check_sampling(wos[w], g_list[i]);
}

/* The same cosine as pbrt-v4's formula where that one is accurate. */
static void sample_agrees_with_pbrt_formula(void **state)
{
    (void)state;
    const double g_list[] = {0.3, -0.7, 0.9, -0.05};
    vec3 wo = v3(0, 0, 1);
    for (size_t i = 0; i < sizeof g_list / sizeof g_list[0]; ++i) {
        double g = g_list[i];
        for (double u0 = 0.0; u0 < 1.0; u0 += 1.0 / 128) {
            double r = (1 - g * g) / (1 + g - 2 * g * u0);
            double want = -1 / (2 * g) * (1 + g * g - r * r);
            vec3 wi = hg_sample(wo, g, v2(u0, 0.25), NULL);
            assert_near(wi.z, want, 1e-12);
        }
    }
}

static void sample_extreme_g_is_finite(void **state)
{
    (void)state;
    const double ext[] = {0.99999, -0.99999, 1.0 - 1e-12, -(1.0 - 1e-12), 0.0};
    const double us[] = {0.0, 0.5, 1.0 - 0x1.0p-53, 0x1.0p-53, 0.25};
    vec3 wos[] = {v3(0, 0, 1), v3(0, 0, -1), v3_normalize(v3(1, 2, -3))};
    for (size_t w = 0; w < sizeof wos / sizeof wos[0]; ++w)
        for (size_t i = 0; i < sizeof ext / sizeof ext[0]; ++i)
            for (size_t a = 0; a < sizeof us / sizeof us[0]; ++a)
                for (size_t b = 0; b < sizeof us / sizeof us[0]; ++b) {
                    double pdf = NAN;
                    vec3 wi = hg_sample(wos[w], ext[i], v2(us[a], us[b]), &pdf);
                    if (!v3_is_finite(wi) || !isfinite(pdf) || !(pdf > 0.0))
                        fail_msg("g = %.17g, u = (%g, %g): wi (%g, %g, %g), pdf %g", ext[i],
                                 us[a], us[b], wi.x, wi.y, wi.z, pdf);
                    assert_near(v3_length(wi), 1.0, 1e-12);
                }
    /* u.x = 0 is the peak: wi = -wo for g > 0, +wo for g < 0. */
    vec3 wo = v3_normalize(v3(0.2, -0.4, 0.6));
    assert_v3_near(hg_sample(wo, 0.99999, v2(0, 0.3), NULL), v3_neg(wo), 1e-12);
    assert_v3_near(hg_sample(wo, -0.99999, v2(1.0 - 0x1.0p-53, 0.3), NULL), wo, 1e-6);
    /* The mean cosine still comes out right at g = ±0.99999. */
    for (int s = -1; s <= 1; s += 2) {
        double g = s * 0.99999, sum = 0.0;
        for (uint32_t i = 0; i < SAMPLES; ++i)
            sum += -v3_dot(wo, hg_sample(wo, g, v2((i + 0.5) / SAMPLES, van_der_corput(i)), NULL));
        assert_near(sum / SAMPLES, g, 1e-4);
    }
}

/* Chi-square test of hg_sample against hg_phase (as pbrt-v4's and Mitsuba's
 * sampling tests): 1e6 directions binned by cos(wo, wi) and by the azimuth
 * around wo; expected counts from integrating the density over each bin (the
 * density's own quadrature, not the sampler's inverse CDF); bins expecting
 * fewer than 5 are pooled. The statistic's Wilson-Hilferty normal score must
 * stay below 4.5 (p ~ 3e-6 for a correct sampler); a sampler with its cosine
 * off by 1% fails by far. */
#define CHI_MU 24
#define CHI_PHI 12
#define CHI_N 1000000

static double chi_square_score(vec3 wo, double g, double skew)
{
    static double observed[CHI_MU][CHI_PHI];
    double expected[CHI_MU];
    for (int i = 0; i < CHI_MU; ++i) {
        for (int j = 0; j < CHI_PHI; ++j)
            observed[i][j] = 0.0;
        double a = -1.0 + 2.0 * i / CHI_MU, b = -1.0 + 2.0 * (i + 1) / CHI_MU, sum = 0.0;
        enum { SUB = 4000 };
        for (int k = 0; k < SUB; ++k)
            sum += hg_phase(a + (b - a) * (k + 0.5) / SUB, g);
        expected[i] = 2.0 * HZ_PI * sum * (b - a) / SUB / CHI_PHI * CHI_N;
    }
    vec3 b1, b2;
    v3_basis(wo, &b1, &b2);
    rng r = rng_seeded(0x5eed + (uint64_t)(1000.0 * (g + 2.0)));
    for (int n = 0; n < CHI_N; ++n) {
        vec2 u = v2(rng_uniform(&r), rng_uniform(&r));
        vec3 wi = hg_sample(wo, g, u, NULL);
        double mu = hz_clamp(v3_dot(wo, wi) * skew, -1.0, 1.0);
        double phi = atan2(v3_dot(wi, b2), v3_dot(wi, b1)) + HZ_PI;
        int i = (int)((mu + 1.0) * 0.5 * CHI_MU), j = (int)(phi / (2.0 * HZ_PI) * CHI_PHI);
        observed[i < CHI_MU ? i : CHI_MU - 1][j < CHI_PHI ? j : CHI_PHI - 1] += 1.0;
    }
    double chi2 = 0.0, pool_o = 0.0, pool_e = 0.0;
    int df = -1;
    for (int i = 0; i < CHI_MU; ++i)
        for (int j = 0; j < CHI_PHI; ++j) {
            double e = expected[i], o = observed[i][j];
            if (e < 5.0) {
                pool_o += o;
                pool_e += e;
                continue;
            }
            chi2 += (o - e) * (o - e) / e;
            ++df;
        }
    if (pool_e > 0.0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        ++df;
    }
    double k = 2.0 / (9.0 * df);
    return (cbrt(chi2 / df) - (1.0 - k)) / sqrt(k);
}

static void sample_passes_chi_square(void **state)
{
    (void)state;
    const double gs[] = {0.0, 0.3, -0.7, 0.9};
    const vec3 wos[] = {v3(0, 0, 1), v3_normalize(v3(0.3, -0.8, 0.52))};
    for (size_t i = 0; i < sizeof gs / sizeof gs[0]; ++i)
        for (size_t w = 0; w < 2; ++w) {
            double z = chi_square_score(wos[w], gs[i], 1.0);
            if (getenv("HAZE_CHI_VERBOSE"))
                print_message("g %g wo %zu: z %.2f\n", gs[i], w, z);
            assert_true(z < 4.5);
        }
    /* The test has power: cosines squeezed by 1% are rejected. */
    assert_true(chi_square_score(wos[0], 0.3, 0.99) > 10.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(phase_integrates_to_one),
        cmocka_unit_test(phase_mean_cosine_is_g),
        cmocka_unit_test(phase_known_values),
        cmocka_unit_test(phase_extreme_g_is_finite),
        cmocka_unit_test(sample_matches_density),
        cmocka_unit_test(sample_agrees_with_pbrt_formula),
        cmocka_unit_test(sample_extreme_g_is_finite),
        cmocka_unit_test(sample_passes_chi_square),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
