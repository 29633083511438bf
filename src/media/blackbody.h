/* The emission of a temperature grid (pbrt-v4's nanovdb media): the RGB of
 * pbrt-v4's peak-normalised blackbody (scene/spectrum.h,
 * spectrum_blackbody_peak_to_rgb) tabulated over a medium's temperature range,
 * uniformly in log T, and interpolated linearly: a lookup per sample instead
 * of a spectral integral. Zero at or below 100 K, as pbrt-v4. */
#ifndef HAZE_MEDIA_BLACKBODY_H
#define HAZE_MEDIA_BLACKBODY_H

#include <math.h>
#include <stdbool.h>

#include "core/error.h"
#include "core/vec.h"

/* Entries of a table. Measured against spectrum_blackbody_peak_to_rgb
 * (worst relative luminance error over 20000 temperatures from 800 K up):
 * 4.6e-5 for a table over 100..3000 K, 3.4e-4 over 100 K..1e6 K; below
 * 800 K, where nothing visibly glows, up to 1e-3 and 8e-3. */
enum { BLACKBODY_TABLE_SIZE = 4096 };

/* Temperatures at or below this emit nothing (pbrt-v4's cut-off). */
#define BLACKBODY_MIN_KELVIN 100.0

typedef struct {
    double ln_lo, inv_step; /* table index = (ln T - ln_lo) * inv_step */
    double t_lo, t_hi;      /* the range covered; T above t_hi takes t_hi's value */
    rgb *rgb;               /* BLACKBODY_TABLE_SIZE entries, owned */
} blackbody_table;

/* A table over [max(t_lo, 100 K), t_hi]. False (and an empty table) when
 * t_hi <= 100 K: nothing in that range emits. */
hz_status blackbody_table_build(blackbody_table *t, double t_lo, double t_hi, bool *emits,
                                hz_error *err);
void blackbody_table_free(blackbody_table *t);

static inline rgb blackbody_table_at(const blackbody_table *t, double kelvin)
{
    if (!(kelvin > BLACKBODY_MIN_KELVIN))
        return rgb_grey(0.0);
    if (kelvin <= t->t_lo)
        kelvin = t->t_lo;
    if (kelvin >= t->t_hi)
        return t->rgb[BLACKBODY_TABLE_SIZE - 1];
    double x = (log(kelvin) - t->ln_lo) * t->inv_step;
    int i = (int)x;
    if (i >= BLACKBODY_TABLE_SIZE - 1)
        return t->rgb[BLACKBODY_TABLE_SIZE - 1];
    double f = x - i;
    rgb a = t->rgb[i], b = t->rgb[i + 1];
    return rgb_make(a.r + f * (b.r - a.r), a.g + f * (b.g - a.g), a.b + f * (b.b - a.b));
}

#endif
