/* The wavelengths of one camera sample in spectral rendering: a hero
 * wavelength drawn over the visible range with a density that follows the
 * eye's sensitivity, and companions at the same density shifted by 1/4, 2/4
 * and 3/4 of the sample (stratified: Wilkie et al. 2014's hero wavelengths,
 * as pbrt-v4's SampleVisibleWavelengths, four of them). Radiance along the
 * path is carried in an `rgb`'s four lanes r, g, b, w, one per wavelength
 * (WAVELENGTH_LANES), so every product, exponential and channel MIS of the
 * RGB path works unchanged; the film gets XYZ estimated from them. */
#ifndef HAZE_COLOR_WAVELENGTHS_H
#define HAZE_COLOR_WAVELENGTHS_H

#include "core/vec.h"

enum { WAVELENGTH_LANES = 4 };
#define WAVELENGTH_MIN 360.0
#define WAVELENGTH_MAX 830.0

typedef struct {
    double lambda[WAVELENGTH_LANES]; /* nm */
    double pdf[WAVELENGTH_LANES];    /* per nm */
} wavelengths;

/* The density of a visible wavelength: proportional to 1 / cosh^2(k (lambda
 * - 538 nm)) with k = 0.0072 / nm over [360, 830] nm (Radziszewski et al.
 * 2009's fit of the CIE y-bar), 0 outside. */
double wavelength_visible_pdf(double lambda);
/* Inverts that density's CDF: u in [0, 1) to a wavelength. */
double wavelength_visible_sample(double u);
/* The hero at u and its companions at u + 1/4, u + 2/4, u + 3/4 (mod 1). */
wavelengths wavelengths_sample_visible(double u);

/* The XYZ (Y = 1 for a radiance of luminance 1) the lanes of `L` estimate:
 * the mean over lanes of L(lambda) * xyz-bar(lambda) / pdf(lambda), divided
 * by the integral of y-bar. */
vec3 wavelengths_xyz(const wavelengths *w, rgb L);

/* The lanes v[0..3] as one value. */
static inline rgb wavelengths_lanes(const double v[WAVELENGTH_LANES])
{
    return (rgb){v[0], v[1], v[2], v[3]};
}

#endif
