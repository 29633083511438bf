#include "integrator/volpath_media.h"

#include <assert.h>
#include <math.h>

#include "integrator/strata.h"

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

/* The walk of a grey medium over [t0, t1]: tentative collisions at rate
 * sigma_t * bound in each majorant cell, the optical distance to the next one
 * (Exp(1)) carried across cells; at each, `at` gets its place, the density
 * there and the cell's bound, and returns whether to go on. GREY_END: the
 * walk reached t1 (or missed the density); GREY_STOPPED: `at` ended it;
 * GREY_OVER: past VOLPATH_MAX_COLLISIONS. Inline, with `at` a constant at
 * each call, so the loop's state stays in registers. */
typedef enum { GREY_END, GREY_STOPPED, GREY_OVER } grey_end;

static inline __attribute__((always_inline)) grey_end
grey_walk(const medium *m, vec3 o, vec3 w, double t0, double t1, double u, media_walk *walk,
          bool (*at)(void *ctx, double x, double density, double bound), void *ctx)
{
    medium_ray r;
    if (!(t1 > t0) || !medium_ray_start(m, o, w, walk->time, &t0, &t1, &r))
        return GREY_END;
    assert(r.plain);
    const double sigma_t = medium_sigma_t(m).r; /* every lane's */
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
                return GREY_OVER;
            ++walk->lookups;
            double d = grid_density_index(r.lookup, &r.acc.density,
                                          v3_add(r.at.grid.o, v3_scale(r.at.grid.d, x)));
            tau = rng_exp1(&walk->r);
            if (!at(ctx, x, d, seg.max))
                return GREY_STOPPED;
        }
    }
    return GREY_END;
}

/* Delta tracking: a collision is real with probability density / bound. */
typedef struct {
    rng *r;
    double t, density;
} flight_state;

static inline bool flight_at(void *ctx, double x, double density, double bound)
{
    flight_state *f = ctx;
    if (!(rng_uniform(f->r) * bound < density))
        return true;
    f->t = x;
    f->density = density;
    return false;
}

volpath_flight volpath_grey_flight(const medium *m, vec3 o, vec3 w, double t0, double t1,
                                   double u, media_walk *walk, double *t, double *density)
{
    flight_state f = {&walk->r, 0.0, 0.0};
    switch (grey_walk(m, o, w, t0, t1, u, walk, flight_at, &f)) {
    case GREY_END:
        break;
    case GREY_STOPPED:
        *t = f.t;
        *density = f.density;
        return VOLPATH_REAL;
    case GREY_OVER:
        return VOLPATH_OPAQUE;
    }
    return VOLPATH_PASSED;
}

/* Ratio tracking: T and r_u times sigma_n / sigma_maj, then the roulette. */
typedef struct {
    rng *r;
    double t_max, rl_avg, ru_avg;
    double T, r_u; /* the factors so far */
} ratio_state;

static inline bool ratio_at(void *ctx, double x, double density, double bound)
{
    (void)x;
    ratio_state *s = ctx;
    /* sigma_n / sigma_maj, at least 0 (the bound rounds up) */
    double f = 1.0 - density / bound;
    f = f > 0.0 ? f : 0.0;
    s->T *= f;
    s->r_u *= f;
    s->T *= volpath_shadow_roulette(s->t_max * s->T / (s->rl_avg + s->ru_avg * s->r_u), s->r);
    return s->T > 0.0;
}

bool volpath_grey_ratio(const medium *m, vec3 o, vec3 w, double t0, double t1, media_walk *walk,
                        double t_max, double rl_avg, double ru_avg, double *T, double *r_u)
{
    ratio_state s = {&walk->r, t_max, rl_avg, ru_avg, 1.0, 1.0};
    grey_end e = grey_walk(m, o, w, t0, t1, -1.0, walk, ratio_at, &s);
    *T = s.T;
    *r_u = s.r_u;
    return e == GREY_END;
}

bool volpath_marches(const medium *m)
{
    return medium_is_density_grid(m) && !m->coloured && !m->emissive && !m->free_emission &&
           !medium_moves(m);
}

volpath_flight volpath_march(const medium *m, vec3 o, vec3 w, double t0, double t1, double step,
                             double stop, media_walk *walk, double *D, double *t, double *density)
{
    *D = 0.0;
    medium_ray r;
    if (!(t1 > t0) || !medium_ray_start(m, o, w, walk->time, &t0, &t1, &r))
        return VOLPATH_PASSED;
    strata s;
    strata_make(&s, &r, t0, t1, step, rng_uniform(&walk->r), &walk->r);
    medium_ray_coarsen(&r, step);
    double sum = 0.0;
    bool skip = false; /* strata to skip up to seg.t0 (empty cells before it) */
    majorant_segment seg;
    while (medium_ray_next(&r, &seg, &walk->majorant_steps)) {
        if (!strata_enter(&s, seg.t0, seg.max > 0.0, &skip))
            continue;
        for (; strata_before(&s, seg.t1); strata_next(&s)) {
            double d = medium_ray_density(&r, s.t, &walk->lookups);
            double piece = d * s.dt;
            if (sum + piece > stop) {
                *t = s.t0 + s.i * s.dt + (stop - sum) / d;
                *density = d;
                *D = stop;
                return VOLPATH_REAL;
            }
            sum += piece;
        }
    }
    *D = sum;
    return VOLPATH_PASSED;
}
