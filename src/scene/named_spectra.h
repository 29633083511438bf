/* pbrt-v4's named spectra ("spectrum eta" "metal-Au-eta"), reduced to RGB
 * once, offline, from pbrt-v4's measured tables under the CIE 1931 observer,
 * D65 and linear sRGB:
 *   - metal-*-eta / metal-*-k: per channel, eta is the spectrum's mean
 *     weighted by the channel's (non-negative) sRGB matching function under
 *     D65, and k is the value that makes the normal-incidence reflectance
 *     equal the RGB of the spectral one (at most 0.99: gold's red);
 *   - glass-*: the index at 550 nm, grey (haze does not disperse);
 *   - stdillum-*: the illuminant's RGB at luminance 1, as a light's
 *     spectrum is normalised.
 * Used as pairs (a metal's eta with its k), the reductions reproduce the
 * spectral normal-incidence reflectance exactly and grazing ones within a
 * few percent.
 *
 * For spectral rendering the spectra themselves are kept too
 * (named_spectra_table.c, written by tools/named_spectra_table.py from
 * pbrt-v4's tables): as pbrt-v4 holds them once loaded, extended to 359 and
 * 831 nm where a table stops short of 360..830 nm, illuminants scaled to
 * luminance 1. */
#ifndef HAZE_SCENE_NAMED_SPECTRA_H
#define HAZE_SCENE_NAMED_SPECTRA_H

#include <stdbool.h>
#include <stddef.h>

#include "core/vec.h"

/* The RGB of pbrt-v4's named spectrum `name`; false when there is none. */
bool named_spectrum_rgb(const char *name, rgb *out);

/* A named spectrum as sampled: n (lambda nm, value) pairs, lambda
 * increasing, piecewise linear and zero outside [lambda[0], lambda[n-1]]
 * (pbrt-v4's PiecewiseLinearSpectrum). */
typedef struct {
    const char *name;
    const double *lambda, *value;
    size_t n;
} named_spectrum_samples;

extern const named_spectrum_samples named_spectra_table[];
extern const size_t named_spectra_table_count;

/* The samples of pbrt-v4's named spectrum `name`; NULL when there is none.
 * Every name named_spectrum_rgb knows has them. */
const named_spectrum_samples *named_spectrum_find(const char *name);

#endif
