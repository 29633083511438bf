#include "materials/microfacet.h"

#include <complex.h>
#include <math.h>

#include "core/sampling.h"

double tr_roughness_to_alpha(double roughness) { return sqrt(roughness); }

void tr_regularize(tr_distribution *d)
{
    if (d->alpha_x < 0.3)
        d->alpha_x = hz_clamp(2.0 * d->alpha_x, 0.1, 0.3);
    if (d->alpha_y < 0.3)
        d->alpha_y = hz_clamp(2.0 * d->alpha_y, 0.1, 0.3);
}

/* tan^2 theta and the cos^2 phi, sin^2 phi of a direction. */
static void angles(vec3 w, double *tan2, double *cos2phi, double *sin2phi)
{
    double cos2 = w.z * w.z, sin2 = fmax(0.0, 1.0 - cos2);
    *tan2 = sin2 / cos2;
    if (sin2 > 0.0) {
        *cos2phi = hz_clamp(w.x * w.x / sin2, 0.0, 1.0);
        *sin2phi = hz_clamp(w.y * w.y / sin2, 0.0, 1.0);
    } else {
        *cos2phi = 1.0;
        *sin2phi = 0.0;
    }
}

double tr_d(tr_distribution d, vec3 wm)
{
    double tan2, c2, s2;
    angles(wm, &tan2, &c2, &s2);
    if (isinf(tan2) || isnan(tan2))
        return 0.0;
    double cos4 = wm.z * wm.z * wm.z * wm.z;
    if (cos4 < 1e-16)
        return 0.0;
    double e = tan2 * (c2 / (d.alpha_x * d.alpha_x) + s2 / (d.alpha_y * d.alpha_y));
    return 1.0 / (HZ_PI * d.alpha_x * d.alpha_y * cos4 * (1.0 + e) * (1.0 + e));
}

double tr_lambda(tr_distribution d, vec3 w)
{
    double tan2, c2, s2;
    angles(w, &tan2, &c2, &s2);
    if (isinf(tan2) || isnan(tan2))
        return 0.0;
    double alpha2 = c2 * d.alpha_x * d.alpha_x + s2 * d.alpha_y * d.alpha_y;
    return (sqrt(1.0 + alpha2 * tan2) - 1.0) / 2.0;
}

double tr_g1(tr_distribution d, vec3 w) { return 1.0 / (1.0 + tr_lambda(d, w)); }

double tr_g(tr_distribution d, vec3 wo, vec3 wi)
{
    return 1.0 / (1.0 + tr_lambda(d, wo) + tr_lambda(d, wi));
}

double tr_d_visible(tr_distribution d, vec3 w, vec3 wm)
{
    if (w.z == 0.0)
        return 0.0;
    return tr_g1(d, w) / fabs(w.z) * tr_d(d, wm) * fabs(v3_dot(w, wm));
}

vec3 tr_sample_wm(tr_distribution d, vec3 w, vec2 u)
{
    /* The hemispherical configuration of the stretched direction. */
    vec3 wh = v3_normalize(v3(d.alpha_x * w.x, d.alpha_y * w.y, w.z));
    if (wh.z < 0.0)
        wh = v3_neg(wh);
    vec3 t1 = wh.z < 0.99999 ? v3_normalize(v3_cross(v3(0, 0, 1), wh)) : v3(1, 0, 0);
    vec3 t2 = v3_cross(wh, t1);
    vec2 p = sample_uniform_disk_polar(u);
    /* Warp to the visible part of the disk. */
    double h = sqrt(1.0 - p.x * p.x);
    p.y = hz_lerp((1.0 + wh.z) / 2.0, h, p.y);
    double pz = sqrt(fmax(0.0, 1.0 - (p.x * p.x + p.y * p.y)));
    vec3 nh = v3_add(v3_add(v3_scale(t1, p.x), v3_scale(t2, p.y)), v3_scale(wh, pz));
    return v3_normalize(v3(d.alpha_x * nh.x, d.alpha_y * nh.y, fmax(1e-6, nh.z)));
}

double fresnel_dielectric(double cos_i, double eta)
{
    cos_i = hz_clamp(cos_i, -1.0, 1.0);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    double sin2_i = 1.0 - cos_i * cos_i, sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0)
        return 1.0;
    double cos_t = sqrt(fmax(0.0, 1.0 - sin2_t));
    double r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    double r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return (r_parl * r_parl + r_perp * r_perp) / 2.0;
}

static double fresnel_complex1(double cos_i, double eta_re, double k)
{
    cos_i = hz_clamp(cos_i, 0.0, 1.0);
    double complex eta = eta_re + k * I;
    double sin2_i = 1.0 - cos_i * cos_i;
    double complex sin2_t = sin2_i / (eta * eta);
    double complex cos_t = csqrt(1.0 - sin2_t);
    double complex r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    double complex r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    double a = cabs(r_parl), b = cabs(r_perp);
    return (a * a + b * b) / 2.0;
}

rgb fresnel_complex(double cos_i, rgb eta, rgb k)
{
    return (rgb){fresnel_complex1(cos_i, eta.r, k.r), fresnel_complex1(cos_i, eta.g, k.g),
                 fresnel_complex1(cos_i, eta.b, k.b), fresnel_complex1(cos_i, eta.w, k.w)};
}

bool refract_dir(vec3 wi, vec3 n, double eta, double *etap, vec3 *wt)
{
    double cos_i = v3_dot(n, wi);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = v3_neg(n);
    }
    double sin2_i = fmax(0.0, 1.0 - cos_i * cos_i), sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0)
        return false;
    double cos_t = sqrt(1.0 - sin2_t);
    *wt = v3_add(v3_scale(wi, -1.0 / eta), v3_scale(n, cos_i / eta - cos_t));
    *etap = eta;
    return true;
}
