#include "core/phase.h"

#include <math.h>

/* 1 + g² + 2 g c written as a sum of two non-negative terms,
 * (1 - |g|)² + 2 |g| (1 + sign(g) c), so that it keeps its relative precision at
 * the peak (c = -sign(g)), where it shrinks to (1 - |g|)². */
static double hg_denominator(double c, double g)
{
    double a = fabs(g);
    double one_minus = 1.0 - a;
    double s = g < 0.0 ? -c : c;
    return one_minus * one_minus + 2.0 * a * (1.0 + s);
}

double hg_phase(double cos_theta, double g)
{
    double c = hz_clamp(cos_theta, -1.0, 1.0);
    double denom = hg_denominator(c, g);
    /* 1 - g² as (1 - g)(1 + g): exact enough near |g| = 1. */
    return (1.0 / (4.0 * HZ_PI)) * ((1.0 - g) * (1.0 + g)) / (denom * sqrt(denom));
}

/* The cosine between wo and wi of pbrt-v4's SampleHenyeyGreenstein,
 *     cos = -1/(2g) (1 + g² - ((1 - g²) / (1 + g - 2 g u))²),
 * rewritten with ξ = 1 - 2u (so 1 + g - 2 g u = 1 + g ξ) and the 1/g cancelled:
 *     cos = -(2 ξ (1 + g²) + g (ξ² + 3) + g³ (ξ² - 1)) / (2 (1 + g ξ)²).
 * The two forms agree in exact arithmetic for every g ≠ 0, but this one has no
 * division by g, so it needs no special case near g = 0 (pbrt-v4 switches to
 * the uniform 1 - 2u for |g| < 1e-3, whose density then differs slightly from
 * the HG pdf it returns; here the samples follow HG exactly for every g, and g = 0
 * gives the uniform cos = 2u - 1). 1 + g ξ is computed as a sum of non-negative
 * terms, so it stays accurate (and positive) for |g| up to 1 - 1e-5 and beyond. */
static double hg_sample_cos(double g, double u)
{
    double xi = 1.0 - 2.0 * u;
    /* 1 + g ξ = (1 - |g|) + |g| (1 + sign(g) ξ), with 1 + ξ = 2 (1 - u), 1 - ξ = 2u. */
    double a = fabs(g);
    double one_plus_g_xi = (1.0 - a) + a * (g < 0.0 ? 2.0 * u : 2.0 * (1.0 - u));
    double num = 2.0 * xi * (1.0 + g * g) + g * (xi * xi + 3.0) + g * g * g * (xi * xi - 1.0);
    double c = -num / (2.0 * one_plus_g_xi * one_plus_g_xi);
    if (isnan(c)) /* 0/0 only for |g| = 1, a delta at cos = -sign(g) */
        c = g > 0.0 ? -1.0 : 1.0;
    return hz_clamp(c, -1.0, 1.0);
}

vec3 hg_sample(vec3 wo, double g, vec2 u, double *pdf)
{
    double c = hg_sample_cos(g, u.x);
    /* sin² = (1 - c)(1 + c): keeps small angles at the poles. */
    double s = sqrt(fmax(0.0, (1.0 - c) * (1.0 + c)));
    double phi = 2.0 * HZ_PI * u.y;
    vec3 b1, b2;
    v3_basis(wo, &b1, &b2);
    vec3 wi = v3_add(v3_add(v3_scale(b1, s * cos(phi)), v3_scale(b2, s * sin(phi))),
                     v3_scale(wo, c));
    wi = v3_normalize(wi);
    if (pdf)
        *pdf = hg_phase(v3_dot(wo, wi), g);
    return wi;
}
