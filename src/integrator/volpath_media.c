#include "integrator/volpath_media.h"

#include <math.h>

/* Where the coefficients come from: constant (homogeneous), a grid's
 * density along an index-space ray, or a cloud's along a medium-space ray. */
typedef struct {
    const medium *m;
    bool grid, cloud;
    medium_accessor acc;
    medium_grid_ray r;
    vec3 om, dm; /* cloud: the ray in medium space, same t */
} density_source;

typedef struct {
    density_source src;
    int hero;
    bool emission;
    media_walk *walk;
    volpath_event_fn fn;
    void *ctx;
    rgb T_maj;
    uint32_t collisions;
} tracker;

/* A grid medium's coefficients and emission at a tentative collision. */
static volpath_event grid_event(tracker *tr, double t)
{
    const medium *m = tr->src.m;
    uint64_t *lookups = &tr->walk->lookups;
    vec3 p = medium_point_at(m, &tr->src.acc, &tr->src.r, t, lookups);
    ++*lookups;
    double d = grid_density_index(m->grid.grid, &tr->src.acc.density, p);
    volpath_event ev = {t, rgb_scale(m->sigma_a, d), rgb_scale(m->sigma_s, d), rgb_grey(0.0),
                        rgb_grey(0.0), rgb_grey(0.0)};
    if (m->coloured && d > 0.0) {
        /* The albedo scaled per channel; what is not scattered is absorbed. */
        rgb C = medium_grid_color(m, &tr->src.acc, p, lookups);
        rgb ss = rgb_mul(m->sigma_s, C);
        ev.sigma_a = rgb_scale(rgb_add(m->sigma_a, rgb_sub(m->sigma_s, ss)), d);
        ev.sigma_s = rgb_scale(ss, d);
    }
    /* Absorbing emission keeps the medium's own sigma_a: the colour tints
     * the scattering, not the fire. */
    if (tr->emission && m->emissive && d > 0.0)
        ev.emission =
            rgb_mul(rgb_scale(m->sigma_a, d), medium_grid_Le(m, &tr->src.acc, p, lookups));
    if (tr->emission && m->free_emission)
        ev.emission = rgb_add(ev.emission, medium_grid_emission(m, &tr->src.acc, p, lookups));
    return ev;
}

/* Collisions over [a, b] at the majorant sigma_t * bound (+ extra, a rate
 * for free emission). False when the callback ended the walk or the
 * collision budget ran out (then T_maj = 0). */
static bool track_span(tracker *tr, double a, double b, double bound, double extra)
{
    const medium *m = tr->src.m;
    rgb sigma_maj = rgb_scale(medium_sigma_t(m), bound);
    if (extra > 0.0)
        sigma_maj = rgb_add(sigma_maj, rgb_grey(extra));
    double rate = rgb_ch(sigma_maj, tr->hero);
    if (!(rate > 0.0)) {
        tr->T_maj = rgb_mul(tr->T_maj, rgb_exp_neg(sigma_maj, b - a));
        return true;
    }
    for (double t = a;;) {
        double tn = t - log1p(-rng_uniform(&tr->walk->r)) / rate;
        if (!(tn < b)) {
            tr->T_maj = rgb_mul(tr->T_maj, rgb_exp_neg(sigma_maj, b - t));
            return true;
        }
        if (++tr->collisions > VOLPATH_MAX_COLLISIONS) {
            tr->T_maj = rgb_grey(0.0);
            return false;
        }
        tr->T_maj = rgb_mul(tr->T_maj, rgb_exp_neg(sigma_maj, tn - t));
        volpath_event ev;
        if (tr->src.grid && m->kind == MEDIUM_RGBGRID) {
            vec3 p = medium_point_at(m, &tr->src.acc, &tr->src.r, tn, &tr->walk->lookups);
            rgb sa, ss, Le;
            medium_rgbgrid_at(m, &tr->src.acc, p, &sa, &ss, &Le, &tr->walk->lookups);
            ev = (volpath_event){tn, sa, ss, sigma_maj, tr->T_maj,
                                 tr->emission ? rgb_mul(sa, Le) : rgb_grey(0.0)};
        } else if (tr->src.grid) {
            ev = grid_event(tr, tn);
            ev.sigma_maj = sigma_maj;
            ev.T_maj = tr->T_maj;
        } else {
            double d = 1.0;
            if (tr->src.cloud) {
                d = cloud_density(&m->cloud.params,
                                  v3_add(tr->src.om, v3_scale(tr->src.dm, tn)));
                ++tr->walk->lookups;
            }
            rgb sa = rgb_scale(m->sigma_a, d);
            ev = (volpath_event){tn, sa, rgb_scale(m->sigma_s, d), sigma_maj, tr->T_maj,
                                 tr->emission ? rgb_mul(sa, m->Le) : rgb_grey(0.0)};
        }
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
     * hundred bytes per segment), which medium_accessor_init sets up as the
     * medium needs. */
    tracker tr;
    tr.src.m = m;
    tr.src.grid = m->kind == MEDIUM_GRID || m->kind == MEDIUM_RGBGRID;
    tr.src.cloud = false;
    tr.hero = hero;
    tr.emission = emission;
    tr.walk = walk;
    tr.fn = fn;
    tr.ctx = ctx;
    tr.T_maj = rgb_grey(1.0);
    tr.collisions = 0;
    switch (m->kind) {
    case MEDIUM_HOMOGENEOUS:
        return track_span(&tr, t0, t1, 1.0, 0.0) || tr.collisions > VOLPATH_MAX_COLLISIONS
                   ? tr.T_maj
                   : rgb_grey(1.0);
    case MEDIUM_CLOUD:
        /* The density is at most 1: sigma_t is the majorant over the box. */
        if (!medium_cloud_clip(m, o, w, &t0, &t1))
            return rgb_grey(1.0);
        tr.src.cloud = true;
        tr.src.om = transform_point(&m->cloud.medium_from_render, o);
        tr.src.dm = transform_vector(&m->cloud.medium_from_render, w);
        return track_span(&tr, t0, t1, 1.0, 0.0) || tr.collisions > VOLPATH_MAX_COLLISIONS
                   ? tr.T_maj
                   : rgb_grey(1.0);
    case MEDIUM_GRID:
    case MEDIUM_RGBGRID: {
        majorant_walk mw;
        if (!medium_grid_ray_make(m, o, w, walk->time, &tr.src.r) ||
            !medium_grid_ray_clip(m, &tr.src.r, &t0, &t1) ||
            !majorant_walk_start(&mw, &m->grid.majorant, tr.src.r.o, tr.src.r.d, t0, t1))
            return rgb_grey(1.0); /* no density anywhere on the segment */
        medium_accessor_init(m, &tr.src.acc);
        majorant_segment seg;
        bool free_emission = emission && m->free_emission;
        while (majorant_walk_next(&mw, &seg)) {
            walk->majorant_steps++;
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
    }
    return rgb_grey(1.0);
}
