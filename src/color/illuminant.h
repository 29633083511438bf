/* The illuminants of pbrt-v4's RGB colour spaces as spectra: CIE D65 (sRGB,
 * Rec. 2020, DCI-P3) and the ACES white (ACES2065-1, pbrt-v4's
 * "illum-acesD60"). Raw tables at 5 nm (src/color/illuminant_table.c, made by
 * tools/illuminant_table.py), linear between samples as pbrt-v4's
 * PiecewiseLinearSpectrum. The spectra normalised to luminance 1 as pbrt-v4
 * holds them are rgb_spectrum_illuminant (color/rgb_spectrum.h). */
#ifndef HAZE_COLOR_ILLUMINANT_H
#define HAZE_COLOR_ILLUMINANT_H

#include "core/color_space.h"

typedef enum { ILLUMINANT_D65 = 0, ILLUMINANT_ACES_D60, ILLUMINANT_COUNT } illuminant;

#define ILLUMINANT_LAMBDA_MIN 300.0
#define ILLUMINANT_LAMBDA_STEP 5.0
enum { ILLUMINANT_ROWS = 107 }; /* 300..830 nm */
extern const double illuminant_table_5nm[ILLUMINANT_COUNT][ILLUMINANT_ROWS];

/* The colour space's illuminant. */
illuminant illuminant_of_color_space(color_space cs);
/* Relative spectral power at lambda nm (100 at 560 nm); the end values beyond
 * the table, as pbrt-v4 extends a tabulated spectrum. */
double illuminant_raw(illuminant il, double lambda);

#endif
