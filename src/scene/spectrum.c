#include "scene/spectrum.h"

#include <math.h>

#define LAMBDA_MIN 360.0
#define LAMBDA_MAX 830.0

static double cie_row(int i, int c)
{
    i = i < 0 ? 0 : i >= SPECTRUM_CIE_ROWS ? SPECTRUM_CIE_ROWS - 1 : i;
    return spectrum_cie1931_10nm[i][c];
}

vec3 spectrum_cie_xyz(double l)
{
    if (!(l >= 340.0 && l <= 830.0))
        return v3(0.0, 0.0, 0.0);
    double x = (l - 340.0) / 10.0, fi = floor(x), t = x - fi;
    int i = (int)fi;
    double v[3];
    for (int c = 0; c < 3; ++c) {
        double p0 = cie_row(i - 1, c), p1 = cie_row(i, c), p2 = cie_row(i + 1, c),
               p3 = cie_row(i + 2, c);
        v[c] = 0.5 * (2.0 * p1 + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t * t +
                      (3.0 * p1 - p0 - 3.0 * p2 + p3) * t * t * t);
    }
    return v3(v[0], v[1], v[2]);
}

rgb spectrum_srgb_from_xyz(vec3 c)
{
    return rgb_make(3.2404542 * c.x - 1.5371385 * c.y - 0.4985314 * c.z,
                    -0.9692660 * c.x + 1.8760108 * c.y + 0.0415560 * c.z,
                    0.0556434 * c.x - 0.2040259 * c.y + 1.0572252 * c.z);
}

static double sample_piecewise(const double *lambda, const double *value, size_t n, double l)
{
    if (l < lambda[0] || l > lambda[n - 1])
        return 0.0;
    if (n == 1)
        return value[0];
    size_t i = 0;
    while (i + 2 < n && l > lambda[i + 1])
        ++i;
    double t = (l - lambda[i]) / (lambda[i + 1] - lambda[i]);
    return hz_lerp(t, value[i], value[i + 1]);
}

/* 1 nm steps (trapezoid ends ignored: the CMFs are ~0 there). */
static vec3 integrate_xyz(const double *lambda, const double *value, size_t n)
{
    vec3 sum = v3(0, 0, 0);
    for (double l = LAMBDA_MIN; l <= LAMBDA_MAX; l += 1.0) {
        double s = lambda ? sample_piecewise(lambda, value, n, l) : 1.0;
        sum = v3_add(sum, v3_scale(spectrum_cie_xyz(l), s));
    }
    return sum;
}

rgb spectrum_sampled_to_rgb(const double *lambda, const double *value, size_t n)
{
    rgb white = spectrum_srgb_from_xyz(integrate_xyz(NULL, NULL, 0));
    rgb c = spectrum_srgb_from_xyz(integrate_xyz(lambda, value, n));
    return rgb_make(c.r / white.r, c.g / white.g, c.b / white.b);
}

void spectrum_sampled_basis_to_rgb(const double *lambda, size_t n, rgb *out)
{
    vec3 white = integrate_xyz(NULL, NULL, 0);
    rgb w = spectrum_srgb_from_xyz(white);
    for (size_t j = 0; j < n; ++j)
        out[j] = rgb_grey(0.0);
    size_t i = 0;
    for (double l = LAMBDA_MIN; l <= LAMBDA_MAX; l += 1.0) {
        if (l < lambda[0] || l > lambda[n - 1])
            continue;
        rgb c = spectrum_srgb_from_xyz(spectrum_cie_xyz(l));
        if (n == 1) {
            out[0] = rgb_add(out[0], c);
            continue;
        }
        while (i + 2 < n && l > lambda[i + 1])
            ++i;
        double t = (l - lambda[i]) / (lambda[i + 1] - lambda[i]);
        out[i] = rgb_add(out[i], rgb_scale(c, 1.0 - t));
        out[i + 1] = rgb_add(out[i + 1], rgb_scale(c, t));
    }
    for (size_t j = 0; j < n; ++j)
        out[j] = rgb_make(out[j].r / w.r, out[j].g / w.g, out[j].b / w.b);
}

rgb spectrum_sampled_to_illuminant(const double *lambda, const double *value, size_t n)
{
    vec3 xyz = n == 1 ? integrate_xyz(NULL, NULL, 0) : integrate_xyz(lambda, value, n);
    if (!(xyz.y > 0.0) || !v3_is_finite(xyz))
        return rgb_grey(0.0);
    return spectrum_srgb_from_xyz(v3_scale(xyz, 1.0 / xyz.y));
}

static double planck(double lambda_nm, double kelvin)
{
    const double c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    double l = lambda_nm * 1e-9;
    return (2.0 * h * c * c) / (pow(l, 5) * (exp((h * c) / (l * kb * kelvin)) - 1.0));
}

static vec3 blackbody_xyz(double kelvin)
{
    vec3 xyz = v3(0, 0, 0);
    for (double l = LAMBDA_MIN; l <= LAMBDA_MAX; l += 1.0)
        xyz = v3_add(xyz, v3_scale(spectrum_cie_xyz(l), planck(l, kelvin)));
    return xyz;
}

/* Planck's law over its value at the peak wavelength (Wien's displacement
 * law), from the XYZ integrals of the unnormalised spectrum. */
static rgb peak_normalised(vec3 xyz, double kelvin)
{
    double peak = planck(2.8977721e6 / kelvin, kelvin);
    if (!(peak > 0.0) || !v3_is_finite(xyz) || !(xyz.y > 0.0))
        return rgb_grey(0.0);
    return spectrum_srgb_from_xyz(v3_scale(xyz, 1.0 / peak));
}

rgb spectrum_blackbody_peak_to_rgb(double kelvin)
{
    return peak_normalised(blackbody_xyz(kelvin), kelvin);
}

void spectrum_blackbody_peak_to_rgb_n(const double *kelvin, rgb *out, size_t n)
{
    enum { STEPS = 830 - 360 + 1 }; /* LAMBDA_MIN..LAMBDA_MAX in 1 nm steps */
    vec3 cmf[STEPS];
    for (int i = 0; i < STEPS; ++i)
        cmf[i] = spectrum_cie_xyz(LAMBDA_MIN + i);
    for (size_t k = 0; k < n; ++k) {
        vec3 xyz = v3(0, 0, 0);
        for (int i = 0; i < STEPS; ++i)
            xyz = v3_add(xyz, v3_scale(cmf[i], planck(LAMBDA_MIN + i, kelvin[k])));
        out[k] = peak_normalised(xyz, kelvin[k]);
    }
}

double spectrum_blackbody_at(double lambda, double kelvin)
{
    double peak = planck(2.8977721e6 / kelvin, kelvin);
    double v = planck(lambda, kelvin) / peak;
    return peak > 0.0 && isfinite(v) ? v : 0.0;
}

double spectrum_sampled_luminance(const double *lambda, const double *value, size_t n)
{
    return integrate_xyz(lambda, value, n).y / SPECTRUM_CIE_Y_INTEGRAL;
}

double spectrum_blackbody_luminance(double kelvin)
{
    double peak = planck(2.8977721e6 / kelvin, kelvin);
    double y = blackbody_xyz(kelvin).y / SPECTRUM_CIE_Y_INTEGRAL;
    return peak > 0.0 && isfinite(y / peak) ? y / peak : 0.0;
}

rgb spectrum_blackbody_to_rgb(double kelvin)
{
    vec3 xyz = blackbody_xyz(kelvin);
    if (!(xyz.y > 0.0) || !v3_is_finite(xyz))
        return rgb_grey(0.0); /* too cold to emit visible light in double precision */
    return spectrum_srgb_from_xyz(v3_scale(xyz, 1.0 / xyz.y));
}
