/* Private to src/geometry: pbrt-v4's alpha test (GeometricPrimitive), shared
 * by the triangle filter (alpha.c) and the user shapes' intersectors
 * (user_shapes.c). Inline: they run on every candidate hit of a cut-out
 * shape. */
#ifndef HAZE_GEOMETRY_ALPHA_H
#define HAZE_GEOMETRY_ALPHA_H

#include <embree3/rtcore.h>

#include "core/hash.h"
#include "geometry/geometry.h"

/* Whether the hit at distance t of the ray (o, d) where the alpha is `a`
 * counts: always at 1 and above, never at 0 and below, otherwise when a hash
 * of the ray and t is at most a. pbrt-v4 hashes the ray, and after ignoring a
 * hit traces a new ray from it, so each surface along the way decides anew
 * (the back of a sphere of alpha 1/2 shows through its front half the time):
 * hashing t as well gives each hit its own decision along the one ray Embree
 * keeps tracing. */
static inline bool geom_alpha_keeps(double a, vec3 o, vec3 d, double t)
{
    if (a >= 1.0)
        return true;
    if (!(a > 0.0))
        return false;
    const float v[7] = {(float)o.x, (float)o.y, (float)o.z, (float)d.x,
                        (float)d.y, (float)d.z, (float)t};
    uint64_t h = fnv1a(HZ_FNV_OFFSET, v, sizeof v);
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return (double)(h >> 11) * 0x1.0p-53 <= a;
}

/* The shape's alpha at surface parameters (u, v) and point p. */
static inline double geom_shape_alpha_at(const geom_shape *s, double u, double v, vec3 p)
{
    if (!s->alpha_tex)
        return s->alpha;
    texture_ctx c = {.u = u, .v = v, .p = p};
    return texture_eval_float(s->alpha_tex, &c);
}

/* Embree's filter for triangles with an alpha: drops the hits the alpha test
 * ignores, so Embree goes on to the next surface (camera and shadow rays). */
void geom_alpha_filter(const struct RTCFilterFunctionNArguments *args);

#endif
