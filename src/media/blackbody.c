#include "media/blackbody.h"

#include <math.h>
#include <stdlib.h>

#include "scene/spectrum.h"

hz_status blackbody_table_build(blackbody_table *t, double t_lo, double t_hi, bool *emits,
                                hz_error *err)
{
    *t = (blackbody_table){0};
    *emits = false;
    if (!(t_hi > BLACKBODY_MIN_KELVIN))
        return HZ_OK;
    if (!isfinite(t_hi))
        return hz_fail(err, "the temperature range is not finite");
    t_lo = fmax(t_lo, BLACKBODY_MIN_KELVIN);
    t->rgb = malloc(BLACKBODY_TABLE_SIZE * sizeof *t->rgb);
    if (!t->rgb)
        return hz_fail(err, "out of memory");
    t->t_lo = t_lo;
    t->t_hi = t_hi;
    t->ln_lo = log(t_lo);
    double span = log(t_hi) - t->ln_lo;
    t->inv_step = span > 0.0 ? (BLACKBODY_TABLE_SIZE - 1) / span : 0.0;
    double *kelvin = malloc(BLACKBODY_TABLE_SIZE * sizeof *kelvin);
    if (!kelvin) {
        blackbody_table_free(t);
        return hz_fail(err, "out of memory");
    }
    for (int i = 0; i < BLACKBODY_TABLE_SIZE; ++i)
        kelvin[i] = span > 0.0 ? exp(t->ln_lo + i / t->inv_step) : t_lo;
    spectrum_blackbody_peak_to_rgb_n(kelvin, t->rgb, BLACKBODY_TABLE_SIZE);
    free(kelvin);
    *emits = true;
    return HZ_OK;
}

void blackbody_table_free(blackbody_table *t)
{
    free(t->rgb);
    *t = (blackbody_table){0};
}
