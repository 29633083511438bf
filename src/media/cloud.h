/* pbrt-v4's "cloud" medium: a procedural cloud in the box p0..p1 of medium
 * space. Density at a medium-space point p (in [0, 1]):
 *   pp = frequency p, moved twice along the noise's finite-difference
 *   gradient (step 0.01) when wispiness > 0: pp += 0.05 wispiness 0.5^i
 *   grad(noise)(10 1.99^i pp);
 *   d = sum over 5 octaves of 0.5^(i+1) noise(1.99^i pp);
 *   d = clamp((1 - p.y) 4.5 density d, 0, 1) + 2 max(0, 0.5 - p.y), clamped to [0, 1].
 * Coefficients are per unit density, so the majorant is sigma_t itself. */
#ifndef HAZE_MEDIA_CLOUD_H
#define HAZE_MEDIA_CLOUD_H

#include "core/vec.h"

typedef struct {
    float density, wispiness, frequency;
} cloud_params;

double cloud_density(const cloud_params *c, vec3 p);

#endif
