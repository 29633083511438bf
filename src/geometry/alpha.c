/* pbrt-v4's alpha cut-outs (GeometricPrimitive's alpha test): the filter
 * Embree runs on a cut-out triangle mesh's hits, and the test of an area
 * light's sampled points. Spheres and curves test their hits in their
 * intersectors (user_shapes.c). */
#include "geometry/alpha.h"
#include "geometry/surface_hit.h"

#include <string.h>

bool geometry_alpha_masked(const geom_shape *s, vec2 uv, vec3 p)
{
    if (!s->has_alpha)
        return false;
    double a = geom_shape_alpha_at(s, uv.x, uv.y, p);
    if (a >= 1.0)
        return false;
    if (!(a > 0.0))
        return true;
    const float v[3] = {(float)p.x, (float)p.y, (float)p.z};
    uint64_t h = fnv1a(HZ_FNV_OFFSET, v, sizeof v);
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return (double)(h >> 11) * 0x1.0p-53 > a;
}

void geom_alpha_filter(const struct RTCFilterFunctionNArguments *args)
{
    const geom_shape *s = args->geometryUserPtr;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0)
            continue;
        /* Embree's SOA layouts (RTCRayN, RTCHitN; C has no accessors): a
         * field's N values in a row, the fields in struct order. */
        const float *ray = (const float *)args->ray, *hit = (const float *)args->hit;
        unsigned n = args->N, prim;
        memcpy(&prim, &hit[5 * n + i], sizeof prim);
        double b1 = hit[3 * n + i], b2 = hit[4 * n + i];
        vec3 o = v3(ray[0 * n + i], ray[1 * n + i], ray[2 * n + i]);
        vec3 d = v3(ray[4 * n + i], ray[5 * n + i], ray[6 * n + i]);
        double t = ray[8 * n + i];
        double uv[3][2];
        geom_triangle_corner_uv(s, prim, uv);
        double b0 = 1.0 - b1 - b2;
        double u = b0 * uv[0][0] + b1 * uv[1][0] + b2 * uv[2][0];
        double v = b0 * uv[0][1] + b1 * uv[1][1] + b2 * uv[2][1];
        if (!geom_alpha_keeps(geom_shape_alpha_at(s, u, v, v3_add(o, v3_scale(d, t))), o, d, t))
            args->valid[i] = 0;
    }
}
