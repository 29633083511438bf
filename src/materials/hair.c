#include "materials/hair.h"

#include <math.h>

#include "materials/microfacet.h"

static double sq(double x) { return x * x; }
static double safe_sqrt(double x) { return sqrt(fmax(x, 0.0)); }
static double safe_asin(double x) { return asin(fmin(fmax(x, -1.0), 1.0)); }

/* The modified Bessel function I0 by its series (10 terms, as pbrt-v4). */
static double bessel_i0(double x)
{
    double val = 0.0, x2i = 1.0, ifact = 1.0, i4 = 1.0;
    for (int i = 0; i < 10; ++i) {
        if (i > 1)
            ifact *= i;
        val += x2i / (i4 * sq(ifact));
        x2i *= x * x;
        i4 *= 4.0;
    }
    return val;
}

static double log_bessel_i0(double x)
{
    if (x > 12.0)
        return x + 0.5 * (-log(2.0 * HZ_PI) + log(1.0 / x) + 1.0 / (8.0 * x));
    return log(bessel_i0(x));
}

static double logistic(double x, double s)
{
    x = fabs(x);
    double e = exp(-x / s);
    return e / (s * sq(1.0 + e));
}

static double logistic_cdf(double x, double s) { return 1.0 / (1.0 + exp(-x / s)); }

static double trimmed_logistic(double x, double s, double a, double b)
{
    return logistic(x, s) / (logistic_cdf(b, s) - logistic_cdf(a, s));
}

static double sample_trimmed_logistic(double u, double s, double a, double b)
{
    double k = logistic_cdf(b, s) - logistic_cdf(a, s);
    double x = -s * log(1.0 / (u * k + logistic_cdf(a, s)) - 1.0);
    return fmin(fmax(x, a), b);
}

/* The longitudinal scattering function M_p. */
static double mp(double cos_i, double cos_o, double sin_i, double sin_o, double v)
{
    double a = cos_i * cos_o / v, b = sin_i * sin_o / v;
    if (v <= 0.1)
        return exp(log_bessel_i0(a) - b - 1.0 / v + 0.6931 + log(1.0 / (2.0 * v)));
    return exp(-b) * bessel_i0(a) / (sinh(1.0 / v) * 2.0 * v);
}

/* Attenuations A_0 .. A_pmax for transmittance T through the fibre once. */
static void ap(double cos_o, double eta, double h, rgb T, rgb out[HAIR_P_MAX + 1])
{
    double cos_gamma_o = safe_sqrt(1.0 - h * h);
    double f = fresnel_dielectric(cos_o * cos_gamma_o, eta);
    out[0] = rgb_grey(f);
    out[1] = rgb_scale(T, sq(1.0 - f));
    for (int p = 2; p < HAIR_P_MAX; ++p)
        out[p] = rgb_scale(rgb_mul(out[p - 1], T), f);
    rgb tf = rgb_scale(T, f);
    rgb den = rgb_sub(rgb_grey(1.0), tf);
    rgb num = rgb_mul(out[HAIR_P_MAX - 1], tf);
    out[HAIR_P_MAX] = rgb_div_or_zero(num, den);
}

static double phi_of(int p, double gamma_o, double gamma_t)
{
    return 2.0 * p * gamma_t - 2.0 * gamma_o + p * HZ_PI;
}

static double np(double phi, int p, double s, double gamma_o, double gamma_t)
{
    double dphi = phi - phi_of(p, gamma_o, gamma_t);
    dphi = remainder(dphi, 2.0 * HZ_PI); /* into [-pi, pi] */
    return trimmed_logistic(dphi, s, -HZ_PI, HZ_PI);
}

hair_bxdf hair_make(double h, double eta, rgb sigma_a, double beta_m, double beta_n,
                    double alpha_deg)
{
    hair_bxdf b = {.h = fmin(fmax(h, -1.0), 1.0), .eta = eta, .sigma_a = sigma_a, .lanes = 3};
    beta_m = fmin(fmax(beta_m, 0.01), 1.0);
    beta_n = fmin(fmax(beta_n, 0.01), 1.0);
    b.v[0] = sq(0.726 * beta_m + 0.812 * sq(beta_m) + 3.7 * pow(beta_m, 20));
    b.v[1] = 0.25 * b.v[0];
    b.v[2] = 4.0 * b.v[0];
    for (int p = 3; p <= HAIR_P_MAX; ++p)
        b.v[p] = b.v[2];
    const double sqrt_pi_over_8 = 0.626657069;
    b.s = sqrt_pi_over_8 * (0.265 * beta_n + 1.194 * sq(beta_n) + 5.372 * pow(beta_n, 22));
    b.sin2k_alpha[0] = sin(alpha_deg * HZ_PI / 180.0);
    b.cos2k_alpha[0] = safe_sqrt(1.0 - sq(b.sin2k_alpha[0]));
    for (int i = 1; i < HAIR_P_MAX; ++i) {
        b.sin2k_alpha[i] = 2.0 * b.cos2k_alpha[i - 1] * b.sin2k_alpha[i - 1];
        b.cos2k_alpha[i] = sq(b.cos2k_alpha[i - 1]) - sq(b.sin2k_alpha[i - 1]);
    }
    return b;
}

/* sin and cos of theta_o tilted by the scales for lobe p (R: -2 alpha, TT:
 * alpha, TRT: 4 alpha, as pbrt-v4). */
static void tilt(const hair_bxdf *b, int p, double sin_o, double cos_o, double *sp, double *cp)
{
    switch (p) {
    case 0:
        *sp = sin_o * b->cos2k_alpha[1] - cos_o * b->sin2k_alpha[1];
        *cp = cos_o * b->cos2k_alpha[1] + sin_o * b->sin2k_alpha[1];
        break;
    case 1:
        *sp = sin_o * b->cos2k_alpha[0] + cos_o * b->sin2k_alpha[0];
        *cp = cos_o * b->cos2k_alpha[0] - sin_o * b->sin2k_alpha[0];
        break;
    case 2:
        *sp = sin_o * b->cos2k_alpha[2] + cos_o * b->sin2k_alpha[2];
        *cp = cos_o * b->cos2k_alpha[2] - sin_o * b->sin2k_alpha[2];
        break;
    default:
        *sp = sin_o;
        *cp = cos_o;
    }
    *cp = fabs(*cp);
}

/* What f, pdf and sampling share about wo. */
typedef struct {
    double sin_o, cos_o, phi_o, gamma_o, gamma_t;
    rgb a[HAIR_P_MAX + 1];
} hair_wo;

static hair_wo at_wo(const hair_bxdf *b, vec3 wo)
{
    hair_wo w;
    w.sin_o = wo.x;
    w.cos_o = safe_sqrt(1.0 - sq(w.sin_o));
    w.phi_o = atan2(wo.z, wo.y);
    w.gamma_o = safe_asin(b->h);
    double sin_t = w.sin_o / b->eta, cos_t = safe_sqrt(1.0 - sq(sin_t));
    double etap = w.cos_o > 0.0 ? safe_sqrt(sq(b->eta) - sq(w.sin_o)) / w.cos_o : b->eta;
    double sin_gamma_t = b->h / etap, cos_gamma_t = safe_sqrt(1.0 - sq(sin_gamma_t));
    w.gamma_t = safe_asin(sin_gamma_t);
    double path = cos_t > 0.0 ? 2.0 * cos_gamma_t / cos_t : INFINITY;
    rgb T = rgb_exp_neg(b->sigma_a, path);
    ap(w.cos_o, b->eta, b->h, T, w.a);
    return w;
}

/* The lobes' sampling probabilities: their attenuations' channel means. */
static void ap_pdf(const hair_wo *w, int lanes, double pdf[HAIR_P_MAX + 1])
{
    double sum = 0.0;
    for (int p = 0; p <= HAIR_P_MAX; ++p)
        sum += rgb_lanes_avg(w->a[p], lanes);
    for (int p = 0; p <= HAIR_P_MAX; ++p)
        pdf[p] = sum > 0.0 ? rgb_lanes_avg(w->a[p], lanes) / sum : 0.0;
}

rgb hair_f(const hair_bxdf *b, vec3 wo, vec3 wi)
{
    hair_wo w = at_wo(b, wo);
    double sin_i = wi.x, cos_i = safe_sqrt(1.0 - sq(sin_i));
    double phi = atan2(wi.z, wi.y) - w.phi_o;
    rgb sum = rgb_grey(0.0);
    for (int p = 0; p < HAIR_P_MAX; ++p) {
        double sp, cp;
        tilt(b, p, w.sin_o, w.cos_o, &sp, &cp);
        sum = rgb_add(sum, rgb_scale(w.a[p], mp(cos_i, cp, sin_i, sp, b->v[p]) *
                                                 np(phi, p, b->s, w.gamma_o, w.gamma_t)));
    }
    sum = rgb_add(sum, rgb_scale(w.a[HAIR_P_MAX],
                                 mp(cos_i, w.cos_o, sin_i, w.sin_o, b->v[HAIR_P_MAX]) /
                                     (2.0 * HZ_PI)));
    if (fabs(wi.z) > 0.0)
        sum = rgb_scale(sum, 1.0 / fabs(wi.z));
    return sum;
}

static double pdf_given(const hair_bxdf *b, const hair_wo *w, const double apdf[], double sin_i,
                        double cos_i, double dphi)
{
    double pdf = 0.0;
    for (int p = 0; p < HAIR_P_MAX; ++p) {
        double sp, cp;
        tilt(b, p, w->sin_o, w->cos_o, &sp, &cp);
        pdf += mp(cos_i, cp, sin_i, sp, b->v[p]) * apdf[p] *
               np(dphi, p, b->s, w->gamma_o, w->gamma_t);
    }
    pdf += mp(cos_i, w->cos_o, sin_i, w->sin_o, b->v[HAIR_P_MAX]) * apdf[HAIR_P_MAX] /
           (2.0 * HZ_PI);
    return pdf;
}

double hair_pdf(const hair_bxdf *b, vec3 wo, vec3 wi)
{
    hair_wo w = at_wo(b, wo);
    double apdf[HAIR_P_MAX + 1];
    ap_pdf(&w, b->lanes, apdf);
    double sin_i = wi.x, cos_i = safe_sqrt(1.0 - sq(sin_i));
    return pdf_given(b, &w, apdf, sin_i, cos_i, atan2(wi.z, wi.y) - w.phi_o);
}

bool hair_sample(const hair_bxdf *b, vec3 wo, double uc, vec2 u, bsdf_sample *out)
{
    hair_wo w = at_wo(b, wo);
    double apdf[HAIR_P_MAX + 1];
    ap_pdf(&w, b->lanes, apdf);
    /* The lobe, and uc remapped to what is left of it. */
    int p = 0;
    double acc = 0.0;
    while (p < HAIR_P_MAX && acc + apdf[p] <= uc) {
        acc += apdf[p];
        ++p;
    }
    if (!(apdf[p] > 0.0))
        return false;
    uc = fmin((uc - acc) / apdf[p], 0x1.fffffffffffffp-1);
    double sp, cp;
    tilt(b, p, w.sin_o, w.cos_o, &sp, &cp);
    /* M_p: theta_i. */
    double cos_theta = 1.0 + b->v[p] * log(fmax(u.x, 1e-5) + (1.0 - u.x) * exp(-2.0 / b->v[p]));
    double sin_theta = safe_sqrt(1.0 - sq(cos_theta));
    double sin_i = -cos_theta * sp + sin_theta * cos(2.0 * HZ_PI * u.y) * cp;
    double cos_i = safe_sqrt(1.0 - sq(sin_i));
    /* N_p: the azimuth. */
    double dphi = p < HAIR_P_MAX ? phi_of(p, w.gamma_o, w.gamma_t) +
                                       sample_trimmed_logistic(uc, b->s, -HZ_PI, HZ_PI)
                                 : 2.0 * HZ_PI * uc;
    double phi_i = w.phi_o + dphi;
    out->wi = v3(sin_i, cos_i * cos(phi_i), cos_i * sin(phi_i));
    out->pdf = pdf_given(b, &w, apdf, sin_i, cos_i, dphi);
    out->f = hair_f(b, wo, out->wi);
    out->specular = out->transmission = out->pdf_proportional = false;
    out->eta = 1.0;
    return out->pdf > 0.0;
}

rgb hair_sigma_a_from_concentration(double eumelanin, double pheomelanin)
{
    const rgb eu = rgb_make(0.419, 0.697, 1.37), pheo = rgb_make(0.187, 0.4, 1.05);
    return rgb_add(rgb_scale(eu, fmax(eumelanin, 0.0)), rgb_scale(pheo, fmax(pheomelanin, 0.0)));
}

rgb hair_sigma_a_from_reflectance(rgb c, double beta_n)
{
    double d = 5.969 - 0.215 * beta_n + 2.532 * sq(beta_n) - 10.73 * pow(beta_n, 3) +
               5.574 * pow(beta_n, 4) + 0.245 * pow(beta_n, 5);
    double ch[3] = {c.r, c.g, c.b}, s[3];
    for (int i = 0; i < 3; ++i)
        s[i] = sq(log(fmin(fmax(ch[i], 1e-6), 1.0)) / d);
    return rgb_make(s[0], s[1], s[2]);
}
