#include "color/wavelengths.h"

#include <math.h>

#include "scene/spectrum.h"

enum { CENTRE = 538 };
#define SHARPNESS 0.0072

/* tanh(k (lambda - centre)) at the range's ends: the CDF is linear in the
 * tanh between them. */
static double tanh_at(double lambda) { return tanh(SHARPNESS * (lambda - CENTRE)); }

double wavelength_visible_pdf(double lambda)
{
    if (!(lambda >= WAVELENGTH_MIN && lambda <= WAVELENGTH_MAX))
        return 0.0;
    double c = cosh(SHARPNESS * (lambda - CENTRE));
    return SHARPNESS / ((tanh_at(WAVELENGTH_MAX) - tanh_at(WAVELENGTH_MIN)) * c * c);
}

double wavelength_visible_sample(double u)
{
    double t0 = tanh_at(WAVELENGTH_MIN), t1 = tanh_at(WAVELENGTH_MAX);
    double lambda = CENTRE + atanh(t0 + u * (t1 - t0)) / SHARPNESS;
    return fmin(fmax(lambda, WAVELENGTH_MIN), WAVELENGTH_MAX);
}

wavelengths wavelengths_sample_visible(double u)
{
    /* The pdf from the sample's tanh T: 1 / cosh^2 = 1 - T^2 (no cosh). */
    double t0 = tanh_at(WAVELENGTH_MIN), t1 = tanh_at(WAVELENGTH_MAX);
    double norm = SHARPNESS / (t1 - t0);
    wavelengths w;
    for (int i = 0; i < WAVELENGTH_LANES; ++i) {
        double ui = u + (double)i / WAVELENGTH_LANES;
        if (ui >= 1.0)
            ui -= 1.0;
        double T = t0 + ui * (t1 - t0);
        double lambda = CENTRE + atanh(T) / SHARPNESS;
        w.lambda[i] = fmin(fmax(lambda, WAVELENGTH_MIN), WAVELENGTH_MAX);
        w.pdf[i] = norm * (1.0 - T * T);
    }
    return w;
}

vec3 wavelengths_xyz(const wavelengths *w, rgb L)
{
    const double v[WAVELENGTH_LANES] = {L.r, L.g, L.b, L.w};
    vec3 xyz = v3(0.0, 0.0, 0.0);
    for (int i = 0; i < WAVELENGTH_LANES; ++i) {
        if (!(w->pdf[i] > 0.0) || v[i] == 0.0)
            continue;
        xyz = v3_add(xyz, v3_scale(spectrum_cie_xyz(w->lambda[i]), v[i] / w->pdf[i]));
    }
    return v3_scale(xyz, 1.0 / (WAVELENGTH_LANES * SPECTRUM_CIE_Y_INTEGRAL));
}
