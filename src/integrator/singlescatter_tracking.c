#include "integrator/singlescatter_tracking.h"

bool singlescatter_roulette(rgb *beta, rng *r)
{
    double m = rgb_max(*beta);
    if (m >= SINGLESCATTER_RR_THRESHOLD)
        return true;
    double q = m / SINGLESCATTER_RR_THRESHOLD;
    if (q > 0.0 && rng_uniform(r) < q) {
        *beta = rgb_scale(*beta, 1.0 / q);
        return true;
    }
    *beta = rgb_grey(0.0);
    return false;
}

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

static rgb grid_transmittance(const singlescatter_scene *vs, const medium *m, vec3 o, vec3 w,
                              double t0, double t1, media_walk *walk)
{
    medium_ray gr;
    if (!medium_ray_start(m, o, w, walk->time, &t0, &t1, &gr))
        return rgb_grey(1.0);
    const singlescatter_settings *set = &vs->settings;
    rgb sigma_t = medium_sigma_t(m);
    majorant_segment seg;
    transmittance_mode mode = set->shadow_mode;
    double shadow_step = set->shadow_step * singlescatter_auto_step_scale(set, m, gr.voxels_per_t,
                                                                          (t1 - t0) * gr.voxels_per_t);
    switch (mode) {
    case TRANSMITTANCE_RAYMARCH:
    case TRANSMITTANCE_JITTERED: {
        double offset = mode == TRANSMITTANCE_JITTERED ? rng_uniform(&walk->r) : 0.5;
        strata s;
        strata_make(&s, &gr, t0, t1, shadow_step, offset, &walk->r);
        medium_ray_coarsen(&gr, shadow_step);
        double tau = 0.0;
        bool skip = false; /* strata to skip up to seg.t0 (empty cells before it) */
        while (next_cell(&gr, &seg, walk)) {
            if (!strata_enter(&s, seg.t0, seg.max > 0.0, &skip))
                continue;
            for (; strata_before(&s, seg.t1); strata_next(&s))
                tau += grid_ray_density(&gr, s.t, walk);
        }
        return rgb_exp_neg(sigma_t, tau * s.dt);
    }
    case TRANSMITTANCE_RATIO:
    case TRANSMITTANCE_RESIDUAL: {
        double sigma_max = rgb_max(sigma_t);
        rgb T = rgb_grey(1.0);
        double tau = rng_exp1(&walk->r);
        while (next_cell(&gr, &seg, walk)) {
            if (!(seg.max > 0.0))
                continue;
            cell_rates c = cell_rates_make(set, mode, &seg, sigma_max);
            if (c.march) {
                T = rgb_mul(T, rgb_exp_neg(sigma_t, march_tau(&gr, seg.t0, seg.t1,
                                                              shadow_step, walk)));
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
                    tau = rng_exp1(&walk->r);
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

rgb singlescatter_segment_transmittance(const singlescatter_scene *vs, const medium *m, vec3 o,
                                        vec3 w, double t0, double t1, media_walk *walk)
{
    /* The scene build refused media that are neither (volpath's only). */
    if (medium_is_homogeneous(m))
        return rgb_exp_neg(medium_sigma_t(m), t1 - t0);
    return grid_transmittance(vs, m, o, w, t0, t1, walk);
}
