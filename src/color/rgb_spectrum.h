/* RGB colours as spectra, as pbrt-v4 defines them: the sigmoid polynomial of
 * Jakob and Hanika 2019 looked up in the colour space's table
 * (color/rgb2spec_table.h, made at build time by tools/rgb2spec_opt.c and
 * loaded with rgb2spec_tables_load, color/rgb2spec_module.h), and
 * the three spectra pbrt-v4 builds on it:
 *   - rgb_albedo_spectrum: a reflectance, RGB in [0, 1] (pbrt-v4's
 *     RGBAlbedoSpectrum);
 *   - rgb_unbounded_spectrum: any non-negative RGB, as 2 max(r, g, b) times
 *     the reflectance of RGB / (2 max) (RGBUnboundedSpectrum);
 *   - rgb_illuminant_spectrum: an emitter, the unbounded spectrum times the
 *     colour space's illuminant at luminance 1 (RGBIlluminantSpectrum).
 * Under the colour space's illuminant a reflectance has the XYZ
 * integral(s I xyz-bar) / integral(y-bar) over 360..830 nm, and that XYZ
 * through rgb_spectrum_rgb_from_xyz gives back the RGB (docs/spectral.md
 * has the measured error). Plain values, pure functions, no allocation; each
 * function takes the table of the colour space it works in. */
#ifndef HAZE_COLOR_RGB_SPECTRUM_H
#define HAZE_COLOR_RGB_SPECTRUM_H

#include "color/rgb2spec_table.h"
#include "core/vec.h"

/* s(c0 l^2 + c1 l + c2) with l in nm and s(x) = 1/2 + x / (2 sqrt(1 + x^2));
 * c2 may be infinite (black and white). */
typedef struct {
    double c0, c1, c2;
} sigmoid_poly;

double sigmoid_poly_eval(sigmoid_poly p, double lambda);
/* The largest value over 360..830 nm. */
double sigmoid_poly_max(sigmoid_poly p);
/* The table's polynomial for c (each component clamped to [0, 1], NaN as 0):
 * trilinear between the nodes around c; a grey is exact. */
sigmoid_poly sigmoid_poly_from_rgb(const rgb2spec_table *t, rgb c);

typedef struct {
    sigmoid_poly poly;
} rgb_albedo_spectrum;

typedef struct {
    double scale; /* 2 max(r, g, b) */
    sigmoid_poly poly;
} rgb_unbounded_spectrum;

typedef struct {
    double scale; /* 2 max(r, g, b) */
    sigmoid_poly poly;
    const rgb2spec_table *table; /* whose illuminant multiplies the spectrum */
} rgb_illuminant_spectrum;

/* c clamped to [0, 1] as sigmoid_poly_from_rgb. */
rgb_albedo_spectrum rgb_albedo_spectrum_from_rgb(const rgb2spec_table *t, rgb c);
double rgb_albedo_spectrum_eval(rgb_albedo_spectrum s, double lambda);
/* c's negative (and NaN) components taken as 0. */
rgb_unbounded_spectrum rgb_unbounded_spectrum_from_rgb(const rgb2spec_table *t, rgb c);
double rgb_unbounded_spectrum_eval(rgb_unbounded_spectrum s, double lambda);
/* Holds t: the table must outlive the spectrum (the module is never unloaded). */
rgb_illuminant_spectrum rgb_illuminant_spectrum_from_rgb(const rgb2spec_table *t, rgb c);
double rgb_illuminant_spectrum_eval(rgb_illuminant_spectrum s, double lambda);

/* The colour space's illuminant (color/illuminant.h) at luminance 1, as
 * pbrt-v4's RGBColorSpace holds it: integral(I y-bar) = integral(y-bar). */
double rgb_spectrum_illuminant(const rgb2spec_table *t, double lambda);
/* That illuminant's XYZ (Y = 1): the white of the colour space for a
 * spectral film. */
vec3 rgb_spectrum_white_xyz(const rgb2spec_table *t);
/* RGB of the colour space from XYZ, and back, with that white. */
rgb rgb_spectrum_rgb_from_xyz(const rgb2spec_table *t, vec3 xyz);
vec3 rgb_spectrum_xyz_from_rgb(const rgb2spec_table *t, rgb c);

#endif
