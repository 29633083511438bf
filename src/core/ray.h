/* Rays in render space. The medium travels with the ray (index into the
 * scene's media, -1 = vacuum). */
#ifndef HAZE_CORE_RAY_H
#define HAZE_CORE_RAY_H

#include <math.h>
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

/* pbrt-v4's ScaleDifferentials: the offset rays moved towards the main one. */
static inline void ray_scale_differentials(ray_differential *rd, double s)
{
    rd->rx_o = v3_add(rd->r.o, v3_scale(v3_sub(rd->rx_o, rd->r.o), s));
    rd->ry_o = v3_add(rd->r.o, v3_scale(v3_sub(rd->ry_o, rd->r.o), s));
    rd->rx_d = v3_add(rd->r.d, v3_scale(v3_sub(rd->rx_d, rd->r.d), s));
    rd->ry_d = v3_add(rd->r.d, v3_scale(v3_sub(rd->ry_d, rd->r.d), s));
}

/* Coordinates haze can trace. Embree refuses (asserts on) a ray whose origin or
 * direction has a component beyond FLT_LARGE (~1.8e18), and float rounding
 * makes surfaces meaningless long before that. Scene values that would put a
 * ray origin beyond HZ_MAX_COORD (light positions, lens radii) are refused
 * where they are parsed; a path through an unbounded medium ends at
 * HZ_FAR_COORD (ray_far_t) and continues as if it had left the scene there. */
#define HZ_MAX_COORD 1e16
#define HZ_FAR_COORD 1e17

static inline bool point_within(vec3 p, double limit)
{
    /* & not &&: three compares without branches (false for a NaN, as ever). */
    return (fabs(p.x) <= limit) & (fabs(p.y) <= limit) & (fabs(p.z) <= limit);
}

/* The distance along o + t d (unit d, o within HZ_MAX_COORD) to where a
 * coordinate first reaches HZ_FAR_COORD: the far end of a ray that hits
 * nothing, for media. */
static inline double ray_far_t(vec3 o, vec3 d)
{
    double t = INFINITY;
    const double oc[3] = {o.x, o.y, o.z}, dc[3] = {d.x, d.y, d.z};
    for (int i = 0; i < 3; ++i)
        if (dc[i] != 0.0)
            t = fmin(t, ((dc[i] > 0.0 ? HZ_FAR_COORD : -HZ_FAR_COORD) - oc[i]) / dc[i]);
    return t;
}

static inline vec3 ray_at(const ray *r, double t) { return v3_add(r->o, v3_scale(r->d, t)); }

#endif
