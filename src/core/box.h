/* Axis-aligned boxes. */
#ifndef HAZE_CORE_BOX_H
#define HAZE_CORE_BOX_H

#include <stdbool.h>

#include "core/vec.h"

/* Slab test: [*t0, *t1] clipped to where o + t d lies in the box [lo, hi].
 * False when nothing is left (also for an empty box or an empty interval). */
bool box_clip_ray(vec3 o, vec3 d, vec3 lo, vec3 hi, double *t0, double *t1);

#endif
