#include "integrator/volpath_media.h"

#include <assert.h>
#include <math.h>

typedef struct {
    medium_ray r;
    int hero;
    bool emission;
    media_walk *walk;
    volpath_event_fn fn;
    void *ctx;
    rgb T_maj;
    uint32_t collisions;
    double u; /* the first collision's uniform; < 0: drawn (first_exp) */
} tracker;

/* Exp(1) for the next tentative collision: the first from u when given,
 * the rest from the walk's rng. */
static inline double first_exp(double *u, rng *r)
{
    if (*u < 0.0)
        return rng_exp1(r);
    double e = -log(1.0 - *u);
    *u = -1.0;
    return e;
}

/* Collisions over [a, b] at the majorant sigma_t * bound (+ extra, a rate
 * for free emission). False when the callback ended the walk or the
 * collision budget ran out (then T_maj = 0). */
static bool track_span(tracker *tr, double a, double b, double bound, double extra)
{
    rgb sigma_maj = rgb_scale(medium_sigma_t(tr->r.m), bound);
    if (extra > 0.0)
        sigma_maj = rgb_add(sigma_maj, rgb_grey(extra));
    double rate = rgb_ch(sigma_maj, tr->hero);
    if (!(rate > 0.0)) {
        tr->T_maj = rgb_mul(tr->T_maj, rgb_exp_neg(sigma_maj, b - a));
        return true;
    }
    for (double t = a;;) {
        double tn = t + first_exp(&tr->u, &tr->walk->r) / rate;
        if (!(tn < b)) {
            tr->T_maj = rgb_mul(tr->T_maj, rgb_exp_neg(sigma_maj, b - t));
            return true;
        }
        if (++tr->collisions > VOLPATH_MAX_COLLISIONS) {
            tr->T_maj = rgb_grey(0.0);
            return false;
        }
        tr->T_maj = rgb_mul(tr->T_maj, rgb_exp_neg(sigma_maj, tn - t));
        medium_props mp;
        medium_ray_sample(&tr->r, tn, tr->emission, &mp, &tr->walk->lookups);
        volpath_event ev = {tn, mp.sigma_a, mp.sigma_s, sigma_maj, tr->T_maj, mp.emission};
        if (!tr->fn(tr->ctx, &ev))
            return false;
        tr->T_maj = rgb_grey(1.0);
        t = tn;
    }
}

rgb volpath_track(const medium *m, vec3 o, vec3 w, double t0, double t1, int hero, bool emission,
                  double u, media_walk *walk, volpath_event_fn fn, void *ctx)
{
    if (!(t1 > t0))
        return rgb_grey(1.0);
    /* Field by field: an initialiser would zero the accessors too (several
     * hundred bytes per segment), which medium_ray_start sets up as the
     * medium needs. */
    tracker tr;
    tr.hero = hero;
    tr.emission = emission;
    tr.walk = walk;
    tr.fn = fn;
    tr.ctx = ctx;
    tr.T_maj = rgb_grey(1.0);
    tr.collisions = 0;
    tr.u = u;
    if (!medium_ray_start(m, o, w, walk->time, &t0, &t1, &tr.r))
        return rgb_grey(1.0); /* no density anywhere on the segment */
    majorant_segment seg;
    bool free_emission = emission && m->free_emission;
    while (medium_ray_next(&tr.r, &seg, &walk->majorant_steps)) {
        /* Free emission where the cell glows: two tentative collisions
         * expected across it, whatever the density. */
        double extra = free_emission && seg.emit > 0.0 && seg.t1 > seg.t0
                           ? 2.0 / (seg.t1 - seg.t0)
                           : 0.0;
        if (!(seg.max > 0.0) && !(extra > 0.0))
            continue;
        if (!track_span(&tr, seg.t0, seg.t1, seg.max, extra))
            return tr.collisions > VOLPATH_MAX_COLLISIONS ? tr.T_maj : rgb_grey(1.0);
    }
    return tr.T_maj;
}

static inline bool lanes_equal(rgb a) { return a.r == a.g && a.g == a.b && a.b == a.w; }

bool volpath_grey(const medium *m)
{
    return medium_is_density_grid(m) && !m->coloured && !m->emissive && !m->free_emission &&
           lanes_equal(m->sigma_a) && lanes_equal(m->sigma_s) && !medium_moves(m);
}

/* The density at o + t w of a grey medium's ray (plain: an inline lookup). */
static inline double grey_density(medium_ray *r, double t, media_walk *walk)
{
    ++walk->lookups;
    return grid_density_index(r->lookup, &r->acc.density,
                              v3_add(r->at.grid.o, v3_scale(r->at.grid.d, t)));
}

/* Both walks draw tentative collisions at rate sigma_t * bound per cell, the
 * optical distance to the next one (Exp(1)) carried across cells. */
volpath_flight volpath_grey_flight(const medium *m, vec3 o, vec3 w, double t0, double t1,
                                   double u, media_walk *walk, double *t, double *density)
{
    medium_ray r;
    if (!(t1 > t0) || !medium_ray_start(m, o, w, walk->time, &t0, &t1, &r))
        return VOLPATH_PASSED;
    assert(r.plain);
    const double sigma_t = m->sigma_a.r + m->sigma_s.r;
    uint32_t collisions = 0;
    double tau = first_exp(&u, &walk->r);
    majorant_segment seg;
    while (medium_ray_next(&r, &seg, &walk->majorant_steps)) {
        double rate = sigma_t * seg.max;
        if (!(rate > 0.0))
            continue;
        for (double x = seg.t0;;) {
            double dx = tau / rate;
            if (!(x + dx < seg.t1)) {
                tau -= rate * (seg.t1 - x);
                break;
            }
            x += dx;
            if (++collisions > VOLPATH_MAX_COLLISIONS)
                return VOLPATH_OPAQUE;
            double d = grey_density(&r, x, walk);
            tau = rng_exp1(&walk->r);
            if (rng_uniform(&walk->r) * seg.max < d) {
                *t = x;
                *density = d;
                return VOLPATH_REAL;
            }
        }
    }
    return VOLPATH_PASSED;
}

bool volpath_grey_ratio(const medium *m, vec3 o, vec3 w, double t0, double t1, media_walk *walk,
                        double t_max, double rl_avg, double ru_avg, double *T, double *r_u)
{
    *T = *r_u = 1.0;
    medium_ray r;
    if (!(t1 > t0) || !medium_ray_start(m, o, w, walk->time, &t0, &t1, &r))
        return true;
    assert(r.plain);
    const double sigma_t = m->sigma_a.r + m->sigma_s.r;
    uint32_t collisions = 0;
    double ft = 1.0, fu = 1.0; /* the factors of T and of r_u */
    double tau = rng_exp1(&walk->r);
    majorant_segment seg;
    while (medium_ray_next(&r, &seg, &walk->majorant_steps)) {
        double rate = sigma_t * seg.max;
        if (!(rate > 0.0))
            continue;
        const double inv = 1.0 / seg.max;
        for (double x = seg.t0;;) {
            double dx = tau / rate;
            if (!(x + dx < seg.t1)) {
                tau -= rate * (seg.t1 - x);
                break;
            }
            x += dx;
            if (++collisions > VOLPATH_MAX_COLLISIONS)
                return false;
            /* sigma_n / sigma_maj, at least 0 (the bound rounds up) */
            double f = 1.0 - grey_density(&r, x, walk) * inv;
            f = f > 0.0 ? f : 0.0;
            ft *= f;
            fu *= f;
            ft *= volpath_shadow_roulette(t_max * ft / (rl_avg + ru_avg * fu), &walk->r);
            if (!(ft > 0.0))
                return false;
            tau = rng_exp1(&walk->r);
        }
    }
    *T = ft;
    *r_u = fu;
    return true;
}
