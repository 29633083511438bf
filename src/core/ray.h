/* Rays in render space. The medium travels with the ray (index into the
 * scene's media, -1 = vacuum). */
#ifndef HAZE_CORE_RAY_H
#define HAZE_CORE_RAY_H

#include <stdbool.h>

#include "core/vec.h"

typedef struct {
    vec3 o, d;
    double time;
    int medium;
} ray;

/* A ray and its two neighbours one pixel to the right (x) and down (y). */
typedef struct {
    ray r;
    bool has_differentials;
    vec3 rx_o, rx_d, ry_o, ry_d;
} ray_differential;

static inline vec3 ray_at(const ray *r, double t) { return v3_add(r->o, v3_scale(r->d, t)); }

#endif
