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
 * few percent. */
#ifndef HAZE_SCENE_NAMED_SPECTRA_H
#define HAZE_SCENE_NAMED_SPECTRA_H

#include <stdbool.h>

#include "core/vec.h"

/* The RGB of pbrt-v4's named spectrum `name`; false when there is none. */
bool named_spectrum_rgb(const char *name, rgb *out);

#endif
