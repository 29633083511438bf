/* Private to src/geometry: the tests every ray query makes before Embree and
 * the Embree query itself, shared by intersect.c and convex_mesh.c (whose
 * hits found from planes fall back to Embree). Inline: they run on every
 * query. */
#ifndef HAZE_GEOMETRY_INTERSECT_H
#define HAZE_GEOMETRY_INTERSECT_H

#include <math.h>

#include "core/ray.h"
#include "geometry/geometry_types.h"

/* What Embree's ray validity check accepts (kernels/common/ray.h: |org| and
 * |dir| components at most FLT_LARGE = 1.844e18, tnear and tfar not NaN),
 * with a margin, and tnear >= 0 (its documented range). */
static inline bool geom_embree_can_trace(vec3 o, vec3 d, double tmin, double tmax)
{
    const double large = 1e18;
    return point_within(o, large) && point_within(d, large) && tmin >= 0.0 && !isnan(tmax) &&
           (float)tmin <= large;
}

/* Whether the segment [tmin, tmax] of the ray certainly hits nothing: it
 * misses the padded box around every static shape. */
static inline bool geom_misses_box(vec3 box_lo, vec3 box_hi, vec3 o, vec3 d, double tmin,
                                   double tmax)
{
    /* The slab test with reciprocals (box_clip_ray divides: 6 divisions on
     * every Embree query were 5% of a peer render). A NaN (0 * inf where the
     * origin lies on a slab's plane and the ray runs in it) restricts
     * nothing: the answer is then "may hit", which is always safe. */
    const double o3[3] = {o.x, o.y, o.z}, d3[3] = {d.x, d.y, d.z};
    const double lo[3] = {box_lo.x, box_lo.y, box_lo.z};
    const double hi[3] = {box_hi.x, box_hi.y, box_hi.z};
    double t0 = tmin, t1 = tmax;
    for (int a = 0; a < 3; ++a) {
        double inv = 1.0 / d3[a];
        double tn = (lo[a] - o3[a]) * inv, tf = (hi[a] - o3[a]) * inv;
        if (tn > tf) {
            double t = tn;
            tn = tf;
            tf = t;
        }
        t0 = tn > t0 ? tn : t0;
        t1 = tf < t1 ? tf : t1;
    }
    return t0 > t1;
}

static inline bool geom_misses_world_box(const geometry *g, vec3 o, vec3 d, double tmin,
                                         double tmax)
{
    return g->has_world_box &&
           geom_misses_box(g->world_box[0], g->world_box[1], o, d, tmin, tmax);
}

/* geometry_intersect after the box test. */
bool geom_trace(const geometry *g, vec3 o, vec3 d, double tmin, double tmax, double time,
                geom_hit *hit);

#endif
