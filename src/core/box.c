/* Axis-aligned boxes: the slab test. */
#include "core/box.h"

bool box_clip_ray(vec3 o, vec3 d, vec3 lo_box, vec3 hi_box, double *t0, double *t1)
{
    const double o3[3] = {o.x, o.y, o.z}, d3[3] = {d.x, d.y, d.z};
    const double lo3[3] = {lo_box.x, lo_box.y, lo_box.z};
    const double hi3[3] = {hi_box.x, hi_box.y, hi_box.z};
    double lo = *t0, hi = *t1;
    if (!(lo <= hi))
        return false;
    for (int a = 0; a < 3; ++a) {
        if (!(lo3[a] <= hi3[a]))
            return false; /* empty box */
        if (d3[a] == 0.0) {
            /* Parallel to the slab: all inside or all outside. */
            if (!(o3[a] >= lo3[a] && o3[a] <= hi3[a]))
                return false;
            continue;
        }
        /* Divisions (not a reciprocal times a difference): with a finite non-zero
         * d, (bound - o) / d is never NaN; a tiny d gives ±inf, which is right. */
        double tn = (lo3[a] - o3[a]) / d3[a];
        double tf = (hi3[a] - o3[a]) / d3[a];
        if (tn > tf) {
            double t = tn;
            tn = tf;
            tf = t;
        }
        if (tn > lo)
            lo = tn;
        if (tf < hi)
            hi = tf;
        if (!(lo <= hi))
            return false;
    }
    *t0 = lo;
    *t1 = hi;
    return true;
}
