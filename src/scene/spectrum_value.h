/* A scene spectrum as the scene gave it, for spectral rendering: the RGB
 * that RGB rendering uses for the same parameter, and the spectrum itself
 * when the scene gave one (a blackbody, sampled values, a .spd file, a named
 * spectrum). params_spectrum (scene/params.h) makes them; docs/spectral.md
 * ("Spectra as given") lists the kinds. */
#ifndef HAZE_SCENE_SPECTRUM_VALUE_H
#define HAZE_SCENE_SPECTRUM_VALUE_H

#include <stdbool.h>
#include <stddef.h>

#include "core/vec.h"

/* How a spectrum is used, which decides how an RGB value becomes a spectrum
 * (pbrt-v4's SpectrumType). */
typedef enum { SPECTRUM_USE_ALBEDO, SPECTRUM_USE_UNBOUNDED, SPECTRUM_USE_ILLUMINANT } spectrum_use;

typedef enum {
    SPECTRUM_VALUE_RGB,
    SPECTRUM_VALUE_BLACKBODY,
    SPECTRUM_VALUE_SAMPLED
} spectrum_value_kind;

/* A scene spectrum as given: an RGB (sRGB, as haze keeps every rgb), a
 * blackbody, or a sampled (piecewise-linear) spectrum. `rgb` is always what
 * RGB rendering uses for this parameter (what params_rgb, params_reflectance
 * or params_illuminant return), so the two modes agree on the parameter.
 * `scale` multiplies the native spectrum (BLACKBODY, SAMPLED): for
 * SPECTRUM_USE_ILLUMINANT it is 1 / the luminance of the native spectrum
 * (what params_illuminant divides out), so a light's spectrum has luminance
 * 1 as its rgb has; else 1. A plain value with borrowed arrays.
 *
 * SAMPLED holds every "spectrum" parameter: inline (lambda, value) pairs, a
 * .spd file, a named spectrum (pbrt-v4's tables as pbrt-v4 holds them:
 * named_spectra.h), and a constant ("spectrum" [0.5]) as two equal samples
 * at 359 and 831 nm, beyond the 360..830 nm that wavelengths are drawn
 * from. */
typedef struct {
    spectrum_value_kind kind;
    spectrum_use use;
    rgb rgb;
    double scale;
    /* BLACKBODY: pbrt-v4's BlackbodySpectrum, 1 at its peak, times scale. */
    double kelvin;
    /* SAMPLED: n pairs, lambda increasing (nm), 0 outside
     * [lambda[0], lambda[n-1]] as pbrt-v4's PiecewiseLinearSpectrum, times
     * scale. */
    const double *lambda, *value;
    size_t n;
} spectrum_value;

/* Kind RGB, scale 1. */
spectrum_value spectrum_value_rgb(rgb c, spectrum_use use);
/* The native spectrum at lambda (nm), times scale: BLACKBODY and SAMPLED
 * only (RGB needs the RGB -> spectrum tables of src/color). */
double spectrum_value_eval(const spectrum_value *s, double lambda);
/* True when the spectrum is the same at every wavelength (of 360..830 nm):
 * an RGB grey used as an albedo or unbounded value (not as an illuminant,
 * whose spectrum is the colour space's illuminant's), a sampled spectrum
 * whose values are all equal. */
bool spectrum_value_is_constant(const spectrum_value *s);

#endif
