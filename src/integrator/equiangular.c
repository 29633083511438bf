/* Equiangular sampling toward lights with a position (Kulla & Fajardo
 * 2012), shared by singlescatter's homogeneous segments and volpath's. */
#include "integrator/equiangular.h"

#include <math.h>

equiangular equiangular_make(vec3 o, vec3 w, double lo, double hi, vec3 c)
{
    equiangular e;
    vec3 oc = v3_sub(c, o);
    e.lo = lo;
    e.hi = hi;
    e.delta = v3_dot(oc, w);
    e.D = v3_length(v3_sub(oc, v3_scale(w, e.delta)));
    e.theta_a = atan2(lo - e.delta, e.D);
    e.theta_b = isinf(hi) ? HZ_PI / 2 : atan2(hi - e.delta, e.D);
    e.valid = e.D > 0.0 && e.theta_b > e.theta_a;
    return e;
}

/* The part [*lo, *hi] of the ray o + s w that lies inside a spot light's cone
 * (apex p, unit axis a, cos of the half-angle cos_max > 0, where the cone is
 * convex): outside it the light sends nothing, so equiangular samples are not
 * wasted there. False when the ray misses the cone. */
static bool clip_to_cone(vec3 o, vec3 w, vec3 p, vec3 a, double cos_max, double *lo, double *hi)
{
    vec3 v = v3_sub(o, p);
    double va = v3_dot(v, a), wa = v3_dot(w, a), c2 = cos_max * cos_max;
    /* inside: g(s) = (va + s wa)^2 - c2 |v + s w|^2 >= 0 and va + s wa >= 0 */
    double A = wa * wa - c2, B = 2.0 * (va * wa - c2 * v3_dot(v, w)),
           C = va * va - c2 * v3_dot(v, v);
    double cuts[4] = {*lo, *lo, *hi, *hi};
    int n = 2;
    double disc = B * B - 4.0 * A * C;
    if (A != 0.0 && disc > 0.0) {
        double q = -0.5 * (B + copysign(sqrt(disc), B));
        double r1 = q / A, r2 = q != 0.0 ? C / q : r1;
        if (r1 > r2) {
            double t = r1;
            r1 = r2;
            r2 = t;
        }
        cuts[1] = fmin(fmax(r1, *lo), *hi);
        cuts[2] = fmin(fmax(r2, *lo), *hi);
        n = 4;
    } else if (A == 0.0 && B != 0.0) {
        cuts[1] = cuts[2] = fmin(fmax(-C / B, *lo), *hi);
        n = 4;
    }
    /* The cone is convex: the inside is one interval, the hull of the pieces
     * (between consecutive cuts) whose midpoints are inside. */
    double new_lo = INFINITY, new_hi = -INFINITY;
    for (int i = 0; i + 1 < 4; i += (n == 2 ? 3 : 1)) {
        double s0 = cuts[i], s1 = n == 2 ? cuts[3] : cuts[i + 1];
        if (!(s1 > s0))
            continue;
        double m = isinf(s1) ? s0 + 1.0 + fabs(s0) : 0.5 * (s0 + s1);
        vec3 x = v3_add(v, v3_scale(w, m));
        double xa = v3_dot(x, a);
        if (xa >= 0.0 && xa * xa >= c2 * v3_dot(x, x)) {
            new_lo = fmin(new_lo, s0);
            new_hi = fmax(new_hi, s1);
        }
    }
    if (!(new_hi > new_lo))
        return false;
    *lo = new_lo;
    *hi = new_hi;
    return true;
}

double equiangular_sample(const equiangular *e, double u)
{
    double theta = e->theta_a + u * (e->theta_b - e->theta_a);
    return e->delta + e->D * tan(theta);
}

double equiangular_pdf(const equiangular *e, double s)
{
    if (!e->valid || s < e->lo || s > e->hi)
        return 0.0;
    double x = s - e->delta;
    return e->D / ((e->theta_b - e->theta_a) * (e->D * e->D + x * x));
}

/* Equiangular sampling toward a light with a position (point, spot), over the
 * part of [0, len) the light can reach; invalid for other lights. */
equiangular light_equiangular(const light *l, vec3 o, vec3 w, double len)
{
    equiangular none = {0};
    switch (l->kind) {
    case LIGHT_POINT:
        return equiangular_make(o, w, 0.0, len, l->point.p);
    case LIGHT_SPOT: {
        double lo = 0.0, hi = len;
        if (l->spot.cos_falloff_end > 0.0) {
            transform render_from_light = transform_inverse(l->spot.light_from_render);
            vec3 axis = v3_normalize(transform_vector(&render_from_light, v3(0.0, 0.0, 1.0)));
            if (!clip_to_cone(o, w, l->spot.p, axis, l->spot.cos_falloff_end, &lo, &hi))
                return none;
        }
        return equiangular_make(o, w, lo, hi, l->spot.p);
    }
    case LIGHT_DISTANT:
    case LIGHT_INFINITE:
    case LIGHT_AREA:
        return none;
    }
    return none;
}
