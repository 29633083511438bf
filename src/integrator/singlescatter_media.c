#include "integrator/singlescatter_media.h"

#include <math.h>
#include <string.h>

#include "core/ray.h"
#include "core/phase.h"
#include "integrator/singlescatter_grid.h"
#include "integrator/singlescatter_light.h"

/* ---- homogeneous media: distance sampling ---- */

/* Exponential distance sampling on [0, len) (len may be INFINITY), one channel
 * picked uniformly among those that attenuate; the pdf is the mixture over them. */
typedef struct {
    rgb sigma_t;
    double len;
    int active[3], n_active;
} exp_sampler;

static exp_sampler exp_sampler_make(rgb sigma_t, double len)
{
    exp_sampler e = {sigma_t, len, {0, 0, 0}, 0};
    for (int c = 0; c < 3; ++c)
        if (rgb_ch(sigma_t, c) > 0.0)
            e.active[e.n_active++] = c;
    return e;
}

static double exp_channel_pdf(double sigma, double len, double s)
{
    if (isinf(len))
        return sigma * exp(-sigma * s);
    double mass = -expm1(-sigma * len); /* 1 - e^{-sigma len} */
    if (mass < 1e-12)
        return 1.0 / len; /* vanishing optical depth: uniform */
    return sigma * exp(-sigma * s) / mass;
}

static double exp_pdf(const exp_sampler *e, double s)
{
    if (e->n_active == 0)
        return 0.0;
    double p = 0.0;
    for (int k = 0; k < e->n_active; ++k)
        p += exp_channel_pdf(rgb_ch(e->sigma_t, e->active[k]), e->len, s);
    return p / e->n_active;
}

static double exp_sample(const exp_sampler *e, double u)
{
    int k = (int)(u * e->n_active);
    if (k >= e->n_active)
        k = e->n_active - 1;
    u = u * e->n_active - k;
    double sigma = rgb_ch(e->sigma_t, e->active[k]);
    double s;
    if (isinf(e->len)) {
        s = -log1p(-u) / sigma;
    } else {
        double mass = -expm1(-sigma * e->len);
        s = mass < 1e-12 ? u * e->len : -log1p(-u * mass) / sigma;
    }
    return fmin(s, nextafter(e->len, 0.0));
}

/* Equiangular sampling (Kulla & Fajardo 2012) of s in [lo, hi) on the ray
 * o + s w for a light at c: pdf ∝ 1 / |x(s) - c|² there, 0 elsewhere. */
typedef struct {
    double lo, hi, delta, D, theta_a, theta_b;
    bool valid;
} equiangular;

static equiangular equiangular_make(vec3 o, vec3 w, double lo, double hi, vec3 c)
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

static double equiangular_sample(const equiangular *e, double u)
{
    double theta = e->theta_a + u * (e->theta_b - e->theta_a);
    return e->delta + e->D * tan(theta);
}

static double equiangular_pdf(const equiangular *e, double s)
{
    if (!e->valid || s < e->lo || s > e->hi)
        return 0.0;
    double x = s - e->delta;
    return e->D / ((e->theta_b - e->theta_a) * (e->D * e->D + x * x));
}

/* Equiangular sampling toward a light with a position (point, spot), over the
 * part of [0, len) the light can reach; invalid for other lights. */
static equiangular light_equiangular(const light *l, vec3 o, vec3 w, double len)
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

/* Light of one lamp scattered toward wo at distance s (T(0, s) σ_s applied). */
static rgb scatter_at(const singlescatter_scene *vs, int mi, const light *l, vec3 o, vec3 w,
                      double s, sampler_state *u, media_walk *walk)
{
    medium copy;
    const medium *m = walk_medium(&vs->in, mi, walk, &copy);
    rgb Ls = singlescatter_light_inscattered(vs, mi, l, v3_add(o, v3_scale(w, s)), v3_neg(w), u,
                                             walk);
    return rgb_mul(rgb_mul(m->sigma_s, rgb_exp_neg(medium_sigma_t(m), s)), Ls);
}

/* Emission gathered over a homogeneous segment of length len, exactly:
 * the integral of T(s) sigma_a Le over [0, len] = sigma_a Le (1 - e^{-sigma_t len}) / sigma_t
 * per channel (a channel that does not attenuate does not absorb: 0). */
static rgb homogeneous_emission(const medium *m, rgb sigma_t, double len)
{
    double e[3];
    for (int c = 0; c < 3; ++c) {
        double st = rgb_ch(sigma_t, c), sa = rgb_ch(m->sigma_a, c);
        e[c] = st > 0.0 ? sa * rgb_ch(m->Le, c) * -expm1(-st * len) / st : 0.0;
    }
    return rgb_make(e[0], e[1], e[2]);
}

static void homogeneous_segment(const singlescatter_scene *vs, int mi, vec3 o, vec3 w, double t0,
                                double t1, rgb *beta, rgb *L, sampler_state *u,
                                media_walk *walk)
{
    medium copy;
    const medium *m = walk_medium(&vs->in, mi, walk, &copy);
    rgb sigma_t = medium_sigma_t(m);
    double len = t1 - t0;
    vec3 a = v3_add(o, v3_scale(w, t0)); /* the segment starts at s = 0 */
    if (!rgb_is_black(m->sigma_s) && len > 0.0) {
        exp_sampler es = exp_sampler_make(sigma_t, len);
        rgb Lseg = rgb_grey(0.0);
        for (size_t i = 0; i < vs->in.light_count; ++i) {
            const light *l = &vs->in.lights[i];
            equiangular eq = light_equiangular(l, a, w, len);
            /* One sample per strategy, combined with the balance heuristic:
             * f / (p_exp + p_eq) for each. */
            if (es.n_active > 0) {
                double s = exp_sample(&es, sampler_1d(u));
                double p = exp_pdf(&es, s) + equiangular_pdf(&eq, s);
                if (p > 0.0)
                    Lseg =
                        rgb_add(Lseg, rgb_scale(scatter_at(vs, mi, l, a, w, s, u, walk), 1.0 / p));
            }
            if (eq.valid) {
                double s = equiangular_sample(&eq, sampler_1d(u));
                if (s >= eq.lo && s < eq.hi && s < len) {
                    double p = exp_pdf(&es, s) + equiangular_pdf(&eq, s);
                    if (p > 0.0 && isfinite(p))
                        Lseg = rgb_add(Lseg,
                                       rgb_scale(scatter_at(vs, mi, l, a, w, s, u, walk), 1.0 / p));
                }
            }
        }
        *L = rgb_add(*L, rgb_mul(*beta, Lseg));
    }
    if (m->emissive && len > 0.0)
        *L = rgb_add(*L, rgb_mul(*beta, homogeneous_emission(m, sigma_t, len)));
    *beta = rgb_mul(*beta, rgb_exp_neg(sigma_t, len));
}

void singlescatter_segment(const singlescatter_scene *vs, int m, vec3 o, vec3 w, double t0,
                           double t1, rgb *beta, rgb *L, sampler_state *u, media_walk *walk)
{
    if (!(t1 > t0))
        return;
    /* The scene build refused media that are neither (volpath's only). */
    if (medium_is_homogeneous(&vs->in.media[m]))
        homogeneous_segment(vs, m, o, w, t0, t1, beta, L, u, walk);
    else
        singlescatter_grid_segment(vs, m, o, w, t0, t1, beta, L, u, walk);
}
