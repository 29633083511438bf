/* The chi-square test of a BSDF's sampling shared by the BSDF tests:
 * histogram of sampled directions against the pdf integrated over the same
 * bins (cos theta x phi, sub x sub midpoints per bin); the statistic over
 * bins expecting at least 5 (the rest pooled) must not be significant at 1%
 * over all the n_tests tests of a file (Sidak's correction, as pbrt-v4's test
 * does). Also checks each sample's f and pdf against bsdf_f and bsdf_pdf
 * (relative tolerance tol). */
#ifndef HAZE_TESTS_UNIT_CHI2_UTIL_H
#define HAZE_TESTS_UNIT_CHI2_UTIL_H

#include <math.h>

#include "core/rng.h"
#include "materials/bsdf.h"

#define N_COS 32
#define N_PHI 64

static inline vec3 dir(double cos_theta, double phi)
{
    double s = sqrt(fmax(0.0, 1.0 - cos_theta * cos_theta));
    return v3(s * cos(phi), s * sin(phi), cos_theta);
}

/* Q(a, x), the regularised upper incomplete gamma function: series below
 * a + 1, Lentz's continued fraction above. */
static inline double gamma_q(double a, double x)
{
    if (x <= 0.0)
        return 1.0;
    double gln = lgamma(a);
    if (x < a + 1.0) {
        double ap = a, del = 1.0 / a, sum = del;
        for (int n = 0; n < 100000 && fabs(del) > fabs(sum) * 1e-15; ++n) {
            ap += 1.0;
            del *= x / ap;
            sum += del;
        }
        return 1.0 - sum * exp(-x + a * log(x) - gln);
    }
    double b = x + 1.0 - a, c = 1e300, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        d = fabs(d) < 1e-300 ? 1e-300 : d;
        c = b + an / c;
        c = fabs(c) < 1e-300 ? 1e-300 : c;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-15)
            break;
    }
    return exp(-x + a * log(x) - gln) * h;
}

static inline void chi2_bsdf(const char *what, const bsdf *pb, vec3 wo, int sub, int n_tests,
                              double tol)
{
    const bsdf b = *pb;
    const int n = 1000000;
    static double obs[N_COS * N_PHI], expct[N_COS * N_PHI];
    for (int i = 0; i < N_COS * N_PHI; ++i)
        obs[i] = expct[i] = 0.0;
    rng r = rng_seeded(17);
    for (int i = 0; i < n; ++i) {
        double uc = rng_uniform(&r);
        vec2 u = v2(rng_uniform(&r), rng_uniform(&r));
        bsdf_sample s;
        if (!bsdf_sample_f(&b, wo, uc, u, &s) || s.specular)
            continue;
        double pdf = bsdf_pdf(&b, wo, s.wi);
        rgb f = bsdf_f(&b, wo, s.wi);
        if (fabs(pdf - s.pdf) > tol * s.pdf || fabs(f.g - s.f.g) > tol * s.f.g + 1e-12)
            fail_msg("%s: sample %d: pdf %g vs %g, f %g vs %g", what, i, s.pdf, pdf, s.f.g, f.g);
        int ci = (int)((s.wi.z + 1.0) / 2.0 * N_COS), pi;
        double phi = atan2(s.wi.y, s.wi.x);
        phi = phi < 0.0 ? phi + 2.0 * HZ_PI : phi;
        pi = (int)(phi / (2.0 * HZ_PI) * N_PHI);
        ci = ci < 0 ? 0 : ci >= N_COS ? N_COS - 1 : ci;
        pi = pi < 0 ? 0 : pi >= N_PHI ? N_PHI - 1 : pi;
        obs[ci * N_PHI + pi] += 1.0;
    }
    double dc = 2.0 / N_COS, dp = 2.0 * HZ_PI / N_PHI;
    for (int ci = 0; ci < N_COS; ++ci)
        for (int pi = 0; pi < N_PHI; ++pi) {
            double sum = 0.0;
            for (int a = 0; a < sub; ++a)
                for (int c = 0; c < sub; ++c) {
                    double ct = -1.0 + (ci + (a + 0.5) / sub) * dc;
                    double ph = (pi + (c + 0.5) / sub) * dp;
                    sum += bsdf_pdf(&b, wo, dir(ct, ph));
                }
            expct[ci * N_PHI + pi] = sum / (sub * sub) * dc * dp * n;
        }
    double chi2 = 0.0, pool_obs = 0.0, pool_exp = 0.0;
    int dof = -1;
    for (int i = 0; i < N_COS * N_PHI; ++i) {
        if (expct[i] < 5.0) {
            pool_obs += obs[i];
            pool_exp += expct[i];
            continue;
        }
        chi2 += (obs[i] - expct[i]) * (obs[i] - expct[i]) / expct[i];
        ++dof;
    }
    if (pool_exp >= 5.0) {
        chi2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        ++dof;
    }
    double p = gamma_q(dof / 2.0, chi2 / 2.0);
    print_message("%s: chi2 %.1f, %d dof, p %.3f\n", what, chi2, dof, p);
    assert_true(dof > 20);
    assert_true(p > 1.0 - pow(1.0 - 0.01, 1.0 / n_tests));
}


#endif
