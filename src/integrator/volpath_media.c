#include "integrator/volpath_media.h"

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
} tracker;

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
        double tn = t + rng_exp1(&tr->walk->r) / rate;
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
                  media_walk *walk, volpath_event_fn fn, void *ctx)
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
