/* Camera-ray segments in density-grid media (integrator/singlescatter_grid.h):
 * in-scattering samples on jittered strata of `stepsize` voxels with every
 * estimator; between them the transmittance is marched (raymarch,
 * jittered: piecewise-constant density per stratum, integrated exactly) or
 * tracked (ratio, residual: collisions against each majorant cell's bounds,
 * the in-scattering at a sample weighted by the tracked transmittance to it).
 * Empty cells cost one step of the majorant walk and no lookup. */
#include <math.h>

#include "integrator/singlescatter_grid.h"
#include "integrator/singlescatter_light.h"
#include "integrator/singlescatter_tracking.h"

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
    /* optical distance left to the next tentative collision, Exp(1) when
     * drawn; carried across cells (each uses up mu times its length of it),
     * so cell boundaries draw no random numbers */
    double tau;
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
    rgb w = rgb_grey(0.0);
    for (int c = 0; c < 4; ++c) { /* every lane: w copies g in RGB */
        double k = rgb_ch(sigma_t, c) * d;
        rgb_set_ch(&w, c, k > 0.0 ? (1.0 - rgb_ch(step_t, c)) / k : dt);
    }
    return rgb_mul(eps, w);
}

/* sig (1 - e^{-sigma_t d dt}) / sigma_t per channel: the share of the
 * stratum's light that sig (sigma_a or sigma_s) takes, exactly for its
 * constant density. */
static inline rgb over_stratum(rgb sig, rgb sigma_t, rgb step_t)
{
    return rgb_div_or_zero(rgb_mul(rgb_sub(rgb_grey(1.0), step_t), sig), sigma_t);
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
            sw->tau = rng_exp1(r);
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
    medium copy;
    sw.vs = vs;
    sw.mi = mi;
    sw.m = walk_medium(&vs->in, mi, walk, &copy);
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
    double step = set->step * singlescatter_auto_step_scale(set, sw.m, sw.gr.voxels_per_t,
                                                            (t1 - t0) * sw.gr.voxels_per_t);
    bool marching = mode == TRANSMITTANCE_RAYMARCH || mode == TRANSMITTANCE_JITTERED;
    double offset = mode == TRANSMITTANCE_JITTERED ? sampler_1d(u)
                    : mode == TRANSMITTANCE_RAYMARCH ? 0.5
                                                     : -1.0;
    strata_make(&sw.s, &sw.gr, t0, t1, step, offset, &walk->r);
    if (mode == TRANSMITTANCE_RAYMARCH)
        sw.cutoff = SINGLESCATTER_MARCH_CUTOFF * rgb_max(*beta);
    if (marching)
        medium_ray_coarsen(&sw.gr, step);
    else
        sw.tau = rng_exp1(&walk->r);
    double sigma_max = rgb_max(sw.sigma_t);
    bool alive = true, skip = false; /* skip: strata up to seg.t0 lie in empty cells */
    majorant_segment seg;
    while (alive && next_cell(&sw.gr, &seg, walk)) {
        /* No density and no free emission: nothing to sample. */
        if (!strata_enter(&sw.s, seg.t0, seg.max > 0.0 || (sw.free_emission && seg.emit > 0.0),
                          &skip))
            continue;
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
