/* Spectral rendering's per-sample view of colours: the camera sample's
 * wavelengths and the RGB -> spectrum table of haze's working space (sRGB,
 * where the parser puts every rgb value). An integrator carries a
 * `const spectral_ctx *` (NULL: RGB rendering) and turns each colour it
 * meets into the four lanes of color/wavelengths.h:
 *   - reflectances (albedo), coefficients and indices (unbounded) and
 *     emission (illuminant) given as RGB, as pbrt-v4's RGBAlbedoSpectrum,
 *     RGBUnboundedSpectrum and RGBIlluminantSpectrum;
 *   - spectra given as spectra (scene/spectrum_value.h: blackbodies, sampled
 *     spectra, named metals and illuminants) at the wavelengths themselves.
 * Plain value; the table is borrowed (the render's). */
#ifndef HAZE_COLOR_SPECTRAL_H
#define HAZE_COLOR_SPECTRAL_H

#include <stdbool.h>

#include "color/rgb2spec_table.h"
#include "color/rgb_spectrum.h"
#include "color/wavelengths.h"
#include "core/vec.h"
#include "scene/spectrum_value.h"

typedef enum { SPECTRAL_ALBEDO, SPECTRAL_UNBOUNDED, SPECTRAL_ILLUMINANT } spectral_use;

typedef struct {
    const rgb2spec_table *table; /* sRGB's */
    wavelengths wl;
    double illuminant[WAVELENGTH_LANES]; /* the table's illuminant at the lanes */
} spectral_ctx;

/* The context of one camera sample: its wavelengths from u (the sampler's
 * wavelength dimension). */
spectral_ctx spectral_ctx_make(const rgb2spec_table *table, double u);

/* The lanes of RGB colour c (sRGB) used as `use`. */
rgb spectral_from_rgb(const spectral_ctx *sp, rgb c, spectral_use use);

/* An RGB colour whose spectrum is looked up once (spectral_prepare), so a
 * path only evaluates it; `ready` false: not prepared (spectral_from_rgb). */
typedef struct {
    bool ready;
    spectral_use use;
    double scale;
    sigmoid_poly poly;
} spectral_color;
spectral_color spectral_prepare(const rgb2spec_table *t, rgb c, spectral_use use);
/* The lanes of a prepared colour (c->ready). */
rgb spectral_eval(const spectral_ctx *sp, const spectral_color *c);
/* The lanes of a scene spectrum: an RGB one as spectral_from_rgb for its
 * use, a native one (blackbody, sampled) at the wavelengths themselves. */
rgb spectral_from_value(const spectral_ctx *sp, const spectrum_value *s);
/* The RGB (sRGB) the lanes L estimate: XYZ (wavelengths_xyz) through the
 * table's matrix, whose white is its illuminant's (an illuminant spectrum
 * of RGB (1, 1, 1) comes out (1, 1, 1) in expectation). */
rgb spectral_to_rgb(const spectral_ctx *sp, rgb L);

#endif
