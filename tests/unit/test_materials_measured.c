/* materials/measured: pbrt-v4's MeasuredBxDF on RGL .bsdf files written by
 * tests/bsdf/make_bsdf.c from analytic BRDFs. A measured Lambertian of
 * albedo a evaluates to a / pi and reflects a under a white furnace; its
 * colour is the RGB haze gives the albedo spectrum; the sampling pdf
 * integrates to the fraction of samples that succeed and matches the
 * histogram of sampled directions (chi-square); a measured GGX conductor
 * evaluates close to the analytic conductor it was made from. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "materials/bsdf.h"
#include "scene/spectrum.h"

#include "chi2_util.h"

/* The chi-square tests of this file (Sidak's correction). */
#define CHI2_TESTS 7

static measured_brdf *load(const char *name)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", HAZE_TEST_BSDF, name);
    measured_brdf *m = NULL;
    hz_error err;
    if (measured_brdf_read(path, &m, &err) != HZ_OK)
        fail_msg("%s", err.message);
    return m;
}

static bsdf make(const measured_brdf *m)
{
    material mat = {.kind = MATERIAL_MEASURED, .measured = m};
    bsdf b;
    assert_true(bsdf_from_material(&mat, v3(0, 0, 1), v3(1, 0, 0), 0.5, &b));
    return b;
}

/* The relative error of f against want / pi over wo and wi at elevations
 * 0..80 degrees and a few azimuths: its mean, its largest with both
 * directions within 60 degrees of the normal (below max_tol) and its
 * largest anywhere (reported: pairs near the horizon lose to the tables'
 * resolution, see tests/bsdf/make_bsdf.c). */
static void expect_constant_f(const char *what, const measured_brdf *m, rgb want, double max_tol,
                              double mean_tol)
{
    bsdf b = make(m);
    double worst = 0.0, worst60 = 0.0, sum = 0.0;
    int n = 0;
    for (int to = 0; to <= 8; ++to)
        for (int po = 0; po < 3; ++po)
            for (int ti = 0; ti <= 8; ++ti)
                for (int pi = 0; pi < 8; ++pi) {
                    vec3 wo = dir(cos(hz_radians(10.0 * to)), 0.7 + 2.1 * po);
                    vec3 wi = dir(cos(hz_radians(10.0 * ti)), pi * HZ_PI / 4.0 + 0.1);
                    rgb f = bsdf_f(&b, wo, wi);
                    for (int c = 0; c < 3; ++c) {
                        double e = fabs(rgb_ch(f, c) * HZ_PI / rgb_ch(want, c) - 1.0);
                        worst = fmax(worst, e);
                        if (to <= 6 && ti <= 6)
                            worst60 = fmax(worst60, e);
                        sum += e;
                        ++n;
                    }
                }
    print_message("%s: f against %.4f %.4f %.4f / pi: mean error %.3f%%, largest %.2f%% within "
                  "60 deg, %.2f%% in all\n",
                  what, want.r, want.g, want.b, 100.0 * sum / n, 100.0 * worst60, 100.0 * worst);
    assert_true(worst60 < max_tol);
    assert_true(sum / n < mean_tol);
}

static void lambert_closed_form(void **state)
{
    (void)state;
    measured_brdf *m = load("lambert.bsdf");
    expect_constant_f("lambert", m, rgb_grey(0.5), 0.04, 0.006);
    measured_brdf_destroy(m);
    m = load("lambert-nojac.bsdf");
    expect_constant_f("lambert, jacobian 0", m, rgb_grey(0.5), 0.04, 0.006);
    measured_brdf_destroy(m);
    /* The albedo spectrum as haze reduces a reflectance spectrum, held at
     * its end values outside 400..700 nm. */
    const double l[] = {360, 400, 500, 600, 700, 830}, a[] = {0.1, 0.1, 0.3, 0.6, 0.8, 0.8};
    rgb want = spectrum_sampled_to_rgb(l, a, 6);
    print_message("colour albedo as RGB: %.5f %.5f %.5f\n", want.r, want.g, want.b);
    m = load("lambert-colour.bsdf");
    expect_constant_f("lambert, colour", m, want, 0.04, 0.006);
    measured_brdf_destroy(m);
}

/* The per-wavelength weights the spectra are reduced with sum to the RGB
 * of the spectrum itself (the reduction is linear). */
static void spectrum_basis(void **state)
{
    (void)state;
    const double sets[3][5] = {{360, 400, 555.5, 700, 830},
                               {300, 450, 451, 452, 900},
                               {380, 390, 400, 780, 800}};
    rng r = rng_seeded(9);
    for (int k = 0; k < 3; ++k)
        for (int trial = 0; trial < 4; ++trial) {
            double v[5];
            rgb basis[5], sum = rgb_grey(0.0);
            spectrum_sampled_basis_to_rgb(sets[k], 5, basis);
            for (int j = 0; j < 5; ++j) {
                v[j] = rng_uniform(&r) * 2.0 - 0.5;
                sum = rgb_add(sum, rgb_scale(basis[j], v[j]));
            }
            rgb want = spectrum_sampled_to_rgb(sets[k], v, 5);
            for (int c = 0; c < 3; ++c)
                assert_true(fabs(rgb_ch(sum, c) - rgb_ch(want, c)) < 1e-12);
        }
}

/* The directional albedo at wo by quadrature of f cos over the hemisphere
 * (cos theta x phi midpoints), and the integral of the pdf. */
static void quadrature(const bsdf *b, vec3 wo, double *albedo, double *pdf_sum)
{
    const int nc = 400, np = 400;
    double a = 0.0, p = 0.0, dw = (1.0 / nc) * (2.0 * HZ_PI / np);
    for (int i = 0; i < nc; ++i)
        for (int j = 0; j < np; ++j) {
            vec3 wi = dir((i + 0.5) / nc, (j + 0.5) * 2.0 * HZ_PI / np);
            a += bsdf_f(b, wo, wi).g * wi.z * dw;
            p += bsdf_pdf(b, wo, wi) * dw;
        }
    *albedo = a;
    *pdf_sum = p;
}

/* The albedo estimated by sampling (mean and standard error), and the
 * fraction of samples that gave a direction. */
static void sampled_albedo(const bsdf *b, vec3 wo, int n, double *mean, double *se,
                           double *success)
{
    rng r = rng_seeded(5);
    double s = 0.0, s2 = 0.0;
    int ok = 0;
    for (int i = 0; i < n; ++i) {
        double uc = rng_uniform(&r);
        vec2 u;
        u.x = rng_uniform(&r);
        u.y = rng_uniform(&r);
        bsdf_sample bs;
        double v = 0.0;
        if (bsdf_sample_f(b, wo, uc, u, &bs)) {
            v = bs.f.g * fabs(bs.wi.z) / bs.pdf;
            ++ok;
        }
        s += v;
        s2 += v * v;
    }
    *mean = s / n;
    *se = sqrt(fmax(s2 / n - *mean * *mean, 0.0) / n);
    *success = (double)ok / n;
}

/* Under a white furnace the measured Lambertian reflects its albedo 0.5:
 * the quadrature of its f within the tables' interpolation error, the
 * sampled estimate within noise of the quadrature (sampling is unbiased).
 * Its pdf integrates to the fraction of samples that succeed (the rest
 * leave below the horizon, where the tables interpolate across it). */
static void lambert_furnace(void **state)
{
    (void)state;
    measured_brdf *m = load("lambert.bsdf");
    bsdf b = make(m);
    const double angles[] = {0.0, 30.0, 60.0, 80.0, 89.0};
    for (size_t k = 0; k < sizeof angles / sizeof angles[0]; ++k) {
        vec3 wo = dir(cos(hz_radians(angles[k])), 0.4);
        double quad, pdf_sum, mean, se, success;
        quadrature(&b, wo, &quad, &pdf_sum);
        sampled_albedo(&b, wo, 200000, &mean, &se, &success);
        print_message("lambert at %2.0f deg: albedo %.5f (quadrature), %.5f +- %.5f (sampled); "
                      "pdf integral %.5f, samples kept %.5f\n",
                      angles[k], quad, mean, se, pdf_sum, success);
        assert_true(fabs(quad - 0.5) < 0.005);
        assert_true(fabs(mean - quad) < 4.0 * se && se < 0.002);
        assert_true(fabs(pdf_sum - success) < 0.003 && pdf_sum > 0.97);
    }
    measured_brdf_destroy(m);
}

static void chi2_measured(void **state)
{
    (void)state;
    measured_brdf *m = load("lambert.bsdf");
    bsdf b = make(m);
    chi2_bsdf("measured lambert", &b, dir(0.8, 0.5), 24, CHI2_TESTS, 1e-6);
    chi2_bsdf("measured lambert from below", &b, dir(-0.3, 2.0), 24, CHI2_TESTS, 1e-6);
    measured_brdf_destroy(m);
    m = load("ggx.bsdf");
    b = make(m);
    chi2_bsdf("measured ggx head-on", &b, dir(0.95, 0.3), 24, CHI2_TESTS, 1e-6);
    chi2_bsdf("measured ggx grazing", &b, dir(0.2, 1.0), 24, CHI2_TESTS, 1e-6);
    chi2_bsdf("measured ggx between tabulated angles", &b, dir(cos(0.77), -2.0), 24,
              CHI2_TESTS, 1e-6);
    measured_brdf_destroy(m);
    m = load("ggx-aniso.bsdf");
    b = make(m);
    chi2_bsdf("measured ggx 0.2 x 0.5", &b, dir(0.6, 2.0), 24, CHI2_TESTS, 1e-6);
    chi2_bsdf("measured ggx 0.2 x 0.5 from below", &b, dir(-0.7, -0.4), 24, CHI2_TESTS, 1e-6);
    measured_brdf_destroy(m);
}

/* The measured conductor against the analytic one it was made from (alpha
 * d, eta 1, k 4): the directional albedo within 1.5% at every elevation, and
 * f where the lobe holds most of its energy (f cos above a tenth of its
 * largest value) within `f_tol` for 90% of the pairs. */
static void expect_ggx(const char *what, const char *file, tr_distribution d, double f_tol)
{
    measured_brdf *m = load(file);
    bsdf b = make(m);
    material cm = {.kind = MATERIAL_CONDUCTOR, .eta_rgb = rgb_grey(1.0), .k = rgb_grey(4.0),
                   .alpha_x = d.alpha_x, .alpha_y = d.alpha_y};
    bsdf c;
    assert_true(bsdf_from_material(&cm, v3(0, 0, 1), v3(1, 0, 0), 0.5, &c));
    for (int to = 0; to <= 8; ++to) {
        vec3 wo = dir(cos(hz_radians(10.0 * to + 2.5)), 0.3 + to);
        double qm, qc, pm, pc;
        quadrature(&b, wo, &qm, &pm);
        quadrature(&c, wo, &qc, &pc);
        int n = 0, bad = 0;
        double peak = 0.0;
        for (int pass = 0; pass < 2; ++pass)
            for (int i = 0; i < 60; ++i)
                for (int j = 0; j < 60; ++j) {
                    vec3 wi = dir((i + 0.5) / 60.0, (j + 0.5) * 2.0 * HZ_PI / 60.0);
                    double fc = bsdf_f(&c, wo, wi).g, fm = bsdf_f(&b, wo, wi).g;
                    if (pass == 0) {
                        peak = fmax(peak, fc * wi.z);
                    } else if (fc * wi.z > 0.1 * peak) {
                        ++n;
                        bad += fabs(fm / fc - 1.0) > f_tol;
                    }
                }
        print_message("%s at %4.1f deg: albedo %.5f measured, %.5f analytic (%+.2f%%); f beyond "
                      "%.0f%% at %d of %d pairs in the lobe\n",
                      what, 10.0 * to + 2.5, qm, qc, 100.0 * (qm / qc - 1.0), 100.0 * f_tol,
                      bad, n);
        assert_true(fabs(qm / qc - 1.0) < 0.015);
        assert_true(n > 20 && bad <= n / 10);
    }
    measured_brdf_destroy(m);
}

static void ggx_matches_analytic(void **state)
{
    (void)state;
    expect_ggx("ggx 0.3", "ggx.bsdf", (tr_distribution){0.3, 0.3}, 0.05);
    expect_ggx("ggx 0.2 x 0.5", "ggx-aniso.bsdf", (tr_distribution){0.2, 0.5}, 0.05);
}

/* Directions below the surface: reflection on wo's side, nothing across. */
static void two_sided(void **state)
{
    (void)state;
    measured_brdf *m = load("ggx.bsdf");
    bsdf b = make(m);
    vec3 wo = dir(0.7, 0.2), wi = dir(0.5, 2.0);
    rgb up = bsdf_f(&b, wo, wi), down = bsdf_f(&b, v3_neg(wo), v3_neg(wi));
    assert_true(up.g > 0.0 && up.g == down.g);
    assert_true(bsdf_pdf(&b, wo, wi) == bsdf_pdf(&b, v3_neg(wo), v3_neg(wi)));
    assert_true(rgb_is_black(bsdf_f(&b, wo, v3_neg(wi))) && bsdf_pdf(&b, wo, v3_neg(wi)) == 0.0);
    assert_true(bsdf_is_non_specular(&b));
    measured_brdf_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(spectrum_basis),
        cmocka_unit_test(lambert_closed_form),  cmocka_unit_test(lambert_furnace),
        cmocka_unit_test(chi2_measured),        cmocka_unit_test(ggx_matches_analytic),
        cmocka_unit_test(two_sided),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
