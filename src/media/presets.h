/* pbrt-v4's named homogeneous media ("string preset"): measured scattering
 * coefficients of real materials, sigma_s being the reduced scattering
 * coefficient sigma_s' (for use with g = 0), in the units the measurements
 * give (mm^-1), as pbrt-v4 takes them: scale them with "scale". */
#ifndef HAZE_MEDIA_PRESETS_H
#define HAZE_MEDIA_PRESETS_H

#include <stdbool.h>
#include <stddef.h>

#include "core/vec.h"

/* The coefficients of the preset `name` (exact, case-sensitive match, as
 * pbrt-v4). False when there is no such preset. */
bool medium_preset(const char *name, rgb *sigma_a, rgb *sigma_s);

/* The number of presets and the i-th one's name (for messages and docs). */
size_t medium_preset_count(void);
const char *medium_preset_name(size_t i);

#endif
