/* Spectra to linear sRGB, because haze renders in RGB.
 *
 * Rules (also in the README's list of differences from pbrt-v4):
 * - Sampled spectra ((lambda nm, value) pairs, piecewise linear, zero outside
 *   the given range, as pbrt-v4's PiecewiseLinearSpectrum) are integrated over
 *   360..830 nm against the CIE 1931 2-degree colour matching functions
 *   (the CIE's 10 nm table, Catmull-Rom interpolated to 1 nm) to XYZ, converted to
 *   linear sRGB, then divided per channel by the rgb of the constant spectrum 1,
 *   so a constant spectrum c gives rgb (c, c, c). This makes reflectances and
 *   grey media behave as their rgb equivalents.
 * - A blackbody of temperature T (kelvin) gives the linear sRGB of Planck's law,
 *   scaled to luminance Y = 1. pbrt-v4 normalises a blackbody to peak 1 and then
 *   every light divides by the spectrum's luminance (SpectrumToPhotometric), so
 *   a "blackbody L" light with scale 1 has luminance 1, as an rgb (1,1,1) light
 *   does: the renderer gets the same radiance as pbrt-v4. */
#ifndef HAZE_SCENE_SPECTRUM_H
#define HAZE_SCENE_SPECTRUM_H

#include <stdbool.h>
#include <stddef.h>

#include "core/vec.h"

/* The integral of the CIE 1931 y-bar over 360..830 nm in nanometres: what a
 * radiance of unit-luminance spectrum reaches pbrt-v4's film as when the
 * spectrum is not divided by it (rgbgrid Le, temperature blackbodies). */
#define SPECTRUM_CIE_Y_INTEGRAL 106.856895

/* Wavelengths must be strictly increasing (checked by the caller); n >= 1. */
rgb spectrum_sampled_to_rgb(const double *lambda, const double *value, size_t n);
/* The linear sRGB of each tabulated wavelength's hat (value 1 there, 0 at
 * the others) under the same rules, so that spectrum_sampled_to_rgb of any
 * values v is the sum of v[j] out[j]: one pass over the wavelengths, for
 * tables of many spectra on one set of wavelengths (measured BRDFs). */
void spectrum_sampled_basis_to_rgb(const double *lambda, size_t n, rgb *out);
/* The same spectrum as an illuminant, as pbrt-v4 normalises a light's: its
 * XYZ to linear sRGB (no per-channel division by a constant spectrum's RGB),
 * scaled to luminance 1; n == 1 is a constant. Zero for a spectrum without
 * visible light. */
rgb spectrum_sampled_to_illuminant(const double *lambda, const double *value, size_t n);
/* The luminance of the spectrum as pbrt-v4 holds it, before a light divides
 * it out (pbrt-v4's SpectrumToPhotometric): the sampled values as given, a
 * blackbody normalised to 1 at its peak; in units where a constant 1 is 1. */
double spectrum_sampled_luminance(const double *lambda, const double *value, size_t n);
double spectrum_blackbody_luminance(double kelvin);
/* T > 0. */
rgb spectrum_blackbody_to_rgb(double kelvin);
/* pbrt-v4's BlackbodySpectrum at lambda (nm): Planck's law over its value at
 * the peak wavelength (Wien's displacement law), so 1 at the peak. T > 0. */
double spectrum_blackbody_at(double lambda, double kelvin);
/* pbrt-v4's BlackbodySpectrum (Planck's law divided by its value at the
 * peak wavelength, so at most 1) as pbrt-v4's film sees a radiance of that
 * spectrum: its XYZ integrals over 360..830 nm in nanometres, without the
 * division by the CIE Y integral that lights get (about 20 at 2500 K), to
 * linear sRGB. What a temperature grid's emission is. T > 0. */
rgb spectrum_blackbody_peak_to_rgb(double kelvin);
/* The same for n temperatures at once (the colour matching functions are
 * evaluated once); out[i] for kelvin[i]. */
void spectrum_blackbody_peak_to_rgb_n(const double *kelvin, rgb *out, size_t n);
/* CIE 1931 colour matching functions, lambda in nm: the standard's 10 nm
 * table (scene/cie1931.c) interpolated by Catmull-Rom splines, 0 outside
 * 340..830 nm. Integrals of blackbodies from 1000 to 6500 K come within 0.2%
 * of the standard's 1 nm table (what pbrt-v4 integrates with). */
vec3 spectrum_cie_xyz(double lambda);
enum { SPECTRUM_CIE_ROWS = 50 };
extern const double spectrum_cie1931_10nm[SPECTRUM_CIE_ROWS][3];
rgb spectrum_srgb_from_xyz(vec3 xyz);

#endif
