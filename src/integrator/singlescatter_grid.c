/* Grid media: the estimators of integrator/singlescatter_media.h over the
 * medium's majorant grid. A ray segment is mapped into the grid's index space once, then walked
 * cell by cell (media/majorant.h); cells with no medium cost one DDA step and
 * no density lookup, whatever the estimator.
 *
 *   raymarch, jittered  strata of `stepsize` voxels over the segment, sampled
 *                       at one offset (0.5, or one uniform per ray); strata
 *                       whose sample lies in an empty cell are skipped, which
 *                       changes no result (their density is exactly 0).
 *   ratio               ratio tracking with each cell's own majorant.
 *   residual            residual ratio tracking (Novák et al. 2014): each
 *                       cell's lower bound is a control whose transmittance is
 *                       exact, and tentative collisions at the rate of the
 *                       residual (max - min) correct for the rest. In cells of
 *                       near-constant density this needs few lookups.
 * Ratio and residual tracking are unbiased; a cell that expects more than
 * `maxcollisions` tentative collisions is marched instead (jittered). Camera
 * rays take in-scattering samples on jittered strata with every estimator. */
#include <math.h>

#include "integrator/singlescatter_internal.h"

/* Counts density and velocity lookups alike (media_walk.lookups). */
static inline double grid_ray_density(medium_ray *gr, double t, media_walk *walk)
{
    return medium_ray_density(gr, t, &walk->lookups);
}

static inline bool next_cell(medium_ray *gr, majorant_segment *seg, media_walk *walk)
{
    return medium_ray_next(gr, seg, &walk->majorant_steps);
}

/* ---- strata: sample points t0 + (i + offset) dt, i < n ---- */

typedef struct {
    double t0, dt;
    int n, i;
    double offset; /* < 0: a uniform of its own per stratum */
    uint64_t key;  /* ... the i-th number of the stream that starts at key */
    double t;      /* sample point of stratum i (INFINITY once i == n) */
} strata;

/* Per-stratum offsets are read at random from a counter-based stream, not
 * drawn in turn: skipping strata then draws nothing, so where cell
 * boundaries fall (up to rounding) does not shift any later random number. */
static void strata_load(strata *s)
{
    double u = s->offset;
    if (u < 0.0) {
        rng at = rng_seeded(s->key + (uint64_t)s->i * 0x9e3779b97f4a7c15ull);
        u = rng_uniform(&at);
    }
    s->t = s->i < s->n ? s->t0 + (s->i + u) * s->dt : INFINITY;
}

/* Strata of about `step` voxels over [t0, t1], positioned at stratum 0. */
static void strata_make(strata *s, const medium_ray *gr, double t0, double t1, double step,
                        double offset, rng *r)
{
    double n = ceil((t1 - t0) * gr->voxels_per_t / step);
    if (!(n >= 1.0))
        n = 1.0;
    if (n > SINGLESCATTER_MAX_STRATA)
        n = SINGLESCATTER_MAX_STRATA;
    s->t0 = t0;
    s->n = (int)n;
    s->dt = (t1 - t0) / n;
    s->i = 0;
    s->offset = offset;
    s->key = offset < 0.0 ? rng_bits(r) : 0;
    strata_load(s);
}

static inline bool strata_before(const strata *s, double b) { return s->i < s->n && s->t < b; }

static inline void strata_next(strata *s)
{
    ++s->i;
    strata_load(s);
}

/* Moves past every stratum whose sample lies before b (the end of an empty
 * cell), jumping over those that end before it. */
static void strata_skip_to(strata *s, double b)
{
    while (strata_before(s, b)) {
        double k = floor((b - s->t0) / s->dt); /* strata before k end before b */
        s->i = k > s->i + 1.0 ? (k >= s->n ? s->n : (int)k) : s->i + 1;
        strata_load(s);
    }
}

/* ---- per cell ---- */

/* The rate of tentative collisions in a cell and the density of its control
 * (residual tracking: the cell's lower bound; ratio tracking: none). */
typedef struct {
    double lo;    /* control density */
    double mu;    /* majorant of sigma_t (density - lo), largest channel */
    bool march;   /* more collisions expected than max_collisions: march instead */
} cell_rates;

static cell_rates cell_rates_make(const singlescatter_settings *set, transmittance_mode mode,
                                  const majorant_segment *seg, double sigma_max)
{
    cell_rates c;
    c.lo = mode == TRANSMITTANCE_RESIDUAL ? seg->min : 0.0;
    c.mu = sigma_max * (seg->max - c.lo);
    c.march = set->max_collisions > 0.0 && c.mu * (seg->t1 - seg->t0) > set->max_collisions;
    return c;
}

/* T times 1 - sigma_t (dens - lo) / mu per channel: one tentative collision. */
static inline rgb collide(rgb T, rgb sigma_t, double d, double mu)
{
    return rgb_mul(T, rgb_make(1.0 - sigma_t.r * d / mu, 1.0 - sigma_t.g * d / mu,
                               1.0 - sigma_t.b * d / mu));
}

/* An optical distance to the next tentative collision, Exp(1). It is carried
 * across cells (each cell uses up mu times its length of it), so cell
 * boundaries draw no random numbers: a collision lands at the same place
 * however a ray's cells are cut, up to rounding. */
static inline double exp1(rng *r) { return -log1p(-rng_uniform(r)); }

/* Jittered marching of the density integral over [a, b] (a cell that ratio
 * tracking would need too many collisions for). */
static double march_tau(medium_ray *gr, double a, double b, double step, media_walk *walk)
{
    strata s;
    strata_make(&s, gr, a, b, step, rng_uniform(&walk->r), &walk->r);
    double tau = 0.0;
    for (; s.i < s.n; strata_next(&s))
        tau += grid_ray_density(gr, s.t, walk);
    return tau * s.dt;
}

/* ---- transmittance (shadow rays) ---- */

rgb singlescatter_grid_transmittance(const singlescatter_scene *vs, const medium *m, vec3 o, vec3 w,
                                     double t0, double t1, media_walk *walk)
{
    medium_ray gr;
    if (!medium_ray_start(m, o, w, walk->time, &t0, &t1, &gr))
        return rgb_grey(1.0);
    const singlescatter_settings *set = &vs->settings;
    rgb sigma_t = medium_sigma_t(m);
    majorant_segment seg;
    switch (set->shadow_mode) {
    case TRANSMITTANCE_RAYMARCH:
    case TRANSMITTANCE_JITTERED: {
        double offset =
            set->shadow_mode == TRANSMITTANCE_JITTERED ? rng_uniform(&walk->r) : 0.5;
        strata s;
        strata_make(&s, &gr, t0, t1, set->shadow_step, offset, &walk->r);
        double tau = 0.0;
        bool skip = false; /* strata to skip up to seg.t0 (empty cells before it) */
        while (next_cell(&gr, &seg, walk)) {
            if (!(seg.max > 0.0)) {
                skip = true;
                continue;
            }
            if (skip)
                strata_skip_to(&s, seg.t0);
            skip = false;
            for (; strata_before(&s, seg.t1); strata_next(&s))
                tau += grid_ray_density(&gr, s.t, walk);
        }
        return rgb_exp_neg(sigma_t, tau * s.dt);
    }
    case TRANSMITTANCE_RATIO:
    case TRANSMITTANCE_RESIDUAL: {
        double sigma_max = rgb_max(sigma_t);
        rgb T = rgb_grey(1.0);
        double tau = exp1(&walk->r);
        while (next_cell(&gr, &seg, walk)) {
            if (!(seg.max > 0.0))
                continue;
            cell_rates c = cell_rates_make(set, set->shadow_mode, &seg, sigma_max);
            if (c.march) {
                T = rgb_mul(T, rgb_exp_neg(sigma_t, march_tau(&gr, seg.t0, seg.t1,
                                                              set->shadow_step, walk)));
            } else {
                if (c.lo > 0.0)
                    T = rgb_mul(T, rgb_exp_neg(sigma_t, c.lo * (seg.t1 - seg.t0)));
                for (double pos = seg.t0; c.mu > 0.0;) {
                    double room = c.mu * (seg.t1 - pos);
                    if (!(tau < room)) {
                        tau -= room;
                        break;
                    }
                    pos += tau / c.mu;
                    T = collide(T, sigma_t, grid_ray_density(&gr, pos, walk) - c.lo, c.mu);
                    if (!singlescatter_roulette(&T, &walk->r))
                        return T;
                    tau = exp1(&walk->r);
                }
            }
            if (!singlescatter_roulette(&T, &walk->r))
                return T;
        }
        return T;
    }
    }
    return rgb_grey(1.0);
}

/* ---- camera-ray segments: transmittance and in-scattering ---- */

typedef struct {
    const singlescatter_scene *vs;
    int mi;
    const medium *m;
    vec3 o, w, wo;
    rgb sigma_t;
    bool scatters, emissive;
    bool free_emission, coloured; /* haze's emission and colour grids */
    medium_ray gr;
    strata s;
    rgb T, Lseg;
    double tau; /* optical distance left to the next tentative collision */
    /* raymarch: a deterministic end where T falls below this, instead of
     * roulette, so that a pixel centre's value does not depend on the seed */
    double cutoff;
    sampler_state *u;
    media_walk *walk;
} segment_walk;

/* Light scattered toward the camera at the current stratum's sample. */
static inline rgb inscattered_at(segment_walk *sw, double t)
{
    return singlescatter_inscattered(sw->vs, sw->mi, v3_add(sw->o, v3_scale(sw->w, t)), sw->wo,
                                     sw->u, sw->walk);
}

/* What a camera-ray sample of a medium with emission or colour grids sees
 * (medium_density_point). */
static inline medium_density_point sample_at(segment_walk *sw, double t)
{
    medium_density_point g;
    medium_ray_density_point(&sw->gr, t, &g, &sw->walk->lookups);
    return g;
}

/* sigma_s at a sample with albedo scale C (sigma_t unchanged: what is not
 * scattered is absorbed). */
static inline rgb coloured_sigma_s(const medium *m, rgb C) { return rgb_mul(m->sigma_s, C); }

/* Free emission over a stratum of constant density d and emission eps:
 * eps (1 - e^{-sigma_t d dt}) / (sigma_t d) per channel (eps dt where
 * nothing attenuates). */
static inline rgb free_emission_over(rgb eps, rgb sigma_t, double d, double dt, rgb step_t)
{
    double w[3];
    for (int c = 0; c < 3; ++c) {
        double k = rgb_ch(sigma_t, c) * d;
        w[c] = k > 0.0 ? (1.0 - rgb_ch(step_t, c)) / k : dt;
    }
    return rgb_mul(eps, rgb_make(w[0], w[1], w[2]));
}

/* sig (1 - e^{-sigma_t d dt}) / sigma_t per channel: the share of the
 * stratum's light that sig (sigma_a or sigma_s) takes, exactly for its
 * constant density. */
static inline rgb over_stratum(rgb sig, rgb sigma_t, rgb step_t)
{
    return rgb_make(sigma_t.r > 0.0 ? (1.0 - step_t.r) * sig.r / sigma_t.r : 0.0,
                    sigma_t.g > 0.0 ? (1.0 - step_t.g) * sig.g / sigma_t.g : 0.0,
                    sigma_t.b > 0.0 ? (1.0 - step_t.b) * sig.b / sigma_t.b : 0.0);
}

/* Marching over the strata whose samples lie in [.., b): piecewise-constant
 * density per stratum, integrated exactly inside it (scattering (1 -
 * e^{-sigma_t dt}) sigma_s / sigma_t), sound in dense media. False when the
 * walk ended. */
static bool march_strata(segment_walk *sw, double b)
{
    strata *s = &sw->s;
    const medium *m = sw->m;
    rgb sigma_t = sw->sigma_t;
    for (; strata_before(s, b); strata_next(s)) {
        medium_density_point g = sample_at(sw, s->t);
        if (g.density <= 0.0) {
            if (sw->free_emission) /* a glow where there is no density */
                sw->Lseg = rgb_add(sw->Lseg, rgb_mul(sw->T, rgb_scale(g.eps, s->dt)));
            continue;
        }
        rgb step_t = rgb_exp_neg(sigma_t, g.density * s->dt);
        if (sw->free_emission)
            sw->Lseg = rgb_add(sw->Lseg, rgb_mul(sw->T, free_emission_over(g.eps, sigma_t,
                                                                          g.density, s->dt,
                                                                          step_t)));
        /* Absorbing emission sigma_a Le (the colour tints the scattering,
         * not the emission). */
        if (sw->emissive)
            sw->Lseg = rgb_add(sw->Lseg, rgb_mul(rgb_mul(sw->T, over_stratum(m->sigma_a, sigma_t,
                                                                             step_t)),
                                                 g.Le));
        if (sw->scatters)
            sw->Lseg = rgb_add(sw->Lseg,
                               rgb_mul(rgb_mul(sw->T, over_stratum(coloured_sigma_s(m, g.C),
                                                                   sigma_t, step_t)),
                                       inscattered_at(sw, s->t)));
        sw->T = rgb_mul(sw->T, step_t);
        if (sw->cutoff > 0.0 ? rgb_max(sw->T) < sw->cutoff
                             : !singlescatter_roulette(&sw->T, &sw->walk->r)) {
            strata_next(s);
            return false;
        }
    }
    return true;
}

/* Ratio or residual tracking through one cell, with in-scattering at the
 * strata samples inside it: T at a sample is the product over the collisions
 * before it (and the control's exact transmittance up to it), unbiased since
 * the collisions do not depend on the sample. False when the walk ended. */
static bool track_cell(segment_walk *sw, const majorant_segment *seg, cell_rates c)
{
    strata *s = &sw->s;
    rng *r = &sw->walk->r;
    rgb control = rgb_scale(sw->sigma_t, c.lo);
    double pos = seg->t0;
    for (;;) {
        bool at_sample = strata_before(s, seg->t1);
        double x = at_sample && s->t > pos ? s->t : at_sample ? pos : seg->t1;
        /* Tentative collisions before x. */
        while (c.mu > 0.0 && sw->tau < c.mu * (x - pos)) {
            double tc = pos + sw->tau / c.mu;
            if (c.lo > 0.0)
                sw->T = rgb_mul(sw->T, rgb_exp_neg(control, tc - pos));
            pos = tc;
            double d = grid_ray_density(&sw->gr, tc, sw->walk) - c.lo;
            sw->T = collide(sw->T, sw->sigma_t, d, c.mu);
            if (!singlescatter_roulette(&sw->T, r))
                return false;
            sw->tau = exp1(r);
        }
        if (x > pos) {
            sw->tau = fmax(sw->tau - c.mu * (x - pos), 0.0);
            if (c.lo > 0.0) {
                sw->T = rgb_mul(sw->T, rgb_exp_neg(control, x - pos));
                if (!singlescatter_roulette(&sw->T, r))
                    return false;
            }
            pos = x;
        }
        if (!at_sample)
            return true;
        if (sw->scatters || sw->emissive || sw->free_emission) {
            /* The stratum's sample of in-scattering and emission, weighted by
             * the tracked transmittance to it: unbiased, as the collisions do
             * not depend on the sample. (Emission is gathered here rather
             * than at the collisions: a residual-tracking cell of constant
             * density has none.) */
            medium_density_point g = sample_at(sw, s->t);
            if (sw->free_emission)
                sw->Lseg = rgb_add(sw->Lseg, rgb_mul(sw->T, rgb_scale(g.eps, s->dt)));
            if (g.density > 0.0 && sw->scatters)
                sw->Lseg = rgb_add(sw->Lseg,
                                   rgb_mul(rgb_mul(sw->T, rgb_scale(coloured_sigma_s(sw->m, g.C),
                                                                    g.density * s->dt)),
                                           inscattered_at(sw, s->t)));
            if (g.density > 0.0 && sw->emissive)
                sw->Lseg = rgb_add(sw->Lseg, rgb_mul(rgb_mul(sw->T, rgb_scale(sw->m->sigma_a,
                                                                             g.density * s->dt)),
                                                     g.Le));
        }
        strata_next(s);
    }
}

void singlescatter_grid_segment(const singlescatter_scene *vs, int mi, vec3 o, vec3 w, double t0,
                                double t1, rgb *beta, rgb *L, sampler_state *u, media_walk *walk)
{
    /* Field by field: an initialiser would zero the accessors too (~2 KB
     * per segment), which medium_ray_start sets up as the medium needs. */
    segment_walk sw;
    sw.vs = vs;
    sw.mi = mi;
    sw.m = &vs->in.media[mi];
    sw.o = o;
    sw.w = w;
    sw.wo = v3_neg(w);
    sw.T = *beta;
    sw.Lseg = rgb_grey(0.0);
    sw.tau = 0.0;
    sw.cutoff = 0.0;
    sw.u = u;
    sw.walk = walk;
    if (!medium_ray_start(sw.m, o, w, walk->time, &t0, &t1, &sw.gr))
        return;
    sw.sigma_t = medium_sigma_t(sw.m);
    sw.scatters = !rgb_is_black(sw.m->sigma_s);
    sw.emissive = sw.m->emissive;
    sw.free_emission = sw.m->free_emission;
    sw.coloured = sw.m->coloured;
    const singlescatter_settings *set = &vs->settings;
    transmittance_mode mode = set->mode;
    bool marching = mode == TRANSMITTANCE_RAYMARCH || mode == TRANSMITTANCE_JITTERED;
    double offset = mode == TRANSMITTANCE_JITTERED ? sampler_1d(u)
                    : mode == TRANSMITTANCE_RAYMARCH ? 0.5
                                                     : -1.0;
    strata_make(&sw.s, &sw.gr, t0, t1, set->step, offset, &walk->r);
    if (mode == TRANSMITTANCE_RAYMARCH)
        sw.cutoff = SINGLESCATTER_MARCH_CUTOFF * rgb_max(*beta);
    if (!marching)
        sw.tau = exp1(&walk->r);
    double sigma_max = rgb_max(sw.sigma_t);
    bool alive = true, skip = false; /* skip: strata up to seg.t0 lie in empty cells */
    majorant_segment seg;
    while (alive && next_cell(&sw.gr, &seg, walk)) {
        /* No density and no free emission: nothing to sample (the strata are
         * skipped when the next interval that has something begins). */
        if (!(seg.max > 0.0) && !(sw.free_emission && seg.emit > 0.0)) {
            skip = true;
            continue;
        }
        if (skip)
            strata_skip_to(&sw.s, seg.t0);
        skip = false;
        if (!(seg.max > 0.0)) { /* free emission only, integrated over the strata */
            alive = march_strata(&sw, seg.t1);
            continue;
        }
        if (marching) {
            alive = march_strata(&sw, seg.t1);
            continue;
        }
        cell_rates c = cell_rates_make(set, mode, &seg, sigma_max);
        alive = c.march ? march_strata(&sw, seg.t1) : track_cell(&sw, &seg, c);
    }
    *L = rgb_add(*L, sw.Lseg);
    *beta = alive ? sw.T : rgb_grey(0.0);
}
