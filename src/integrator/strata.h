/* Strata for marching a medium ray: sample points t0 + (i + offset) dt,
 * i < n, about `step` voxels apart over a segment, at one offset for every
 * stratum (raymarch: 0.5; jittered: one uniform per ray) or a uniform of
 * their own. Shared by singlescatter's marching estimators and volpath's
 * marched flights and shadow rays. */
#ifndef HAZE_INTEGRATOR_STRATA_H
#define HAZE_INTEGRATOR_STRATA_H

#include <math.h>
#include <stdint.h>

#include "core/rng.h"
#include "media/medium.h"

/* A walk never places more strata than this on one segment: it bounds the
 * work of absurd step sizes (the step grows instead). */
#define STRATA_MAX 1000000

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
static inline void strata_load(strata *s)
{
    double u = s->offset;
    if (u < 0.0) {
        rng at = rng_seeded(s->key + (uint64_t)s->i * 0x9e3779b97f4a7c15ull);
        u = rng_uniform(&at);
    }
    s->t = s->i < s->n ? s->t0 + (s->i + u) * s->dt : INFINITY;
}

/* Strata of about `step` voxels over [t0, t1], positioned at stratum 0. */
static inline void strata_make(strata *s, const medium_ray *gr, double t0, double t1, double step,
                        double offset, rng *r)
{
    double n = ceil((t1 - t0) * gr->voxels_per_t / step);
    if (!(n >= 1.0))
        n = 1.0;
    if (n > STRATA_MAX)
        n = STRATA_MAX;
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
static inline void strata_skip_to(strata *s, double b)
{
    while (strata_before(s, b)) {
        double k = floor((b - s->t0) / s->dt); /* strata before k end before b */
        s->i = k > s->i + 1.0 ? (k >= s->n ? s->n : (int)k) : s->i + 1;
        strata_load(s);
    }
}

/* At the next majorant segment of a marched ray, beginning at t0: false when
 * it holds nothing to sample (`holds` false); its strata, and those of the
 * empty segments after it, are skipped when a segment that holds something
 * begins (their samples lie where the density is 0). `*skip` carries that
 * between segments: false at the ray's start. */
static inline bool strata_enter(strata *s, double t0, bool holds, bool *skip)
{
    if (!holds) {
        *skip = true;
        return false;
    }
    if (*skip)
        strata_skip_to(s, t0);
    *skip = false;
    return true;
}

#endif
