/* The walk of a ray through surfaces and medium interfaces, the one every
 * integrator's rays take (pbrt-v4's SkipIntersection, Mitsuba's
 * target_medium): the ray o + t d is cut at its surface hits into segments,
 * each in one medium (-1: vacuum), yielded in order. The walk steps past
 * interfaces into the medium on their far side, bounds the crossings and
 * backs the next query off past the surface. What an opaque hit means is the
 * caller's: a camera ray stops there, a shadow ray is blocked or steps over
 * it (walk_step_over), a shadow cache column notes it and goes on as through
 * an interface. */
#ifndef HAZE_INTEGRATOR_WALK_H
#define HAZE_INTEGRATOR_WALK_H

#include <stdbool.h>

#include "core/ray.h"
#include "core/vec.h"
#include "geometry/geometry.h"

/* Interfaces one ray may cross before it is dropped (black, and counted in
 * render_stats.lost_paths: haze warns): bounds the work of pathological nested
 * boundaries. walk_pass is the only place that applies it. */
#define WALK_MAX_CROSSINGS 64

/* Options of walk_start: each walk's rules, reproduced exactly. */
enum {
    /* Segments end where the ray's line crosses the hit surface
     * (geometry_crossing_t), never before they begin, so that a medium
     * denser than float rounding is bounded where its surface is. Without
     * it a segment ends at the hit's own t: scenes without media fill no
     * segment and skip the correction's cost. */
    WALK_EXACT_ENDS = 1u << 0,
    /* The first query starts inside the convex mesh that the start medium
     * most likely fills (geometry_convex_around; the guess is checked), so
     * that shadow rays from points in a medium find its exit without Embree. */
    WALK_CONVEX_START = 1u << 1,
    /* Hits before t_fill lie behind the medium point the ray leaves (the
     * path's rays): the walk steps over them without a segment, interfaces
     * switching the medium. Without it they are yielded as any other, and
     * the segment that ends at an interface there is empty or nearly so (the
     * shadow walks' rule, whose estimators see those segments). */
    WALK_PASS_BEHIND = 1u << 2,
};

/* What walk_next does before its query. */
typedef enum {
    WALK_QUERY,     /* nothing: the walk starts */
    WALK_CROSS,     /* step past the last hit into its far side's medium */
    WALK_STEP_OVER, /* step past the last hit, keeping medium and segment start */
    WALK_DONE,      /* the last segment left the scene */
    WALK_LOST,      /* the crossing limit was reached */
} walk_step;

typedef struct {
    const geometry *geom;
    vec3 o, d;
    double tmin;          /* the next query searches (tmin, tmax) */
    double t_fill, tmax, time;
    double t_start;       /* where the next segment begins */
    double t_end;         /* where the last one ended */
    int medium;           /* the last segment's medium, until walk_next crosses */
    unsigned flags;
    int crossings;        /* hits stepped past */
    geom_past past;       /* what the last crossing tells (geometry_past) */
    walk_step next;
    const geom_hit *hit;  /* the hit the last segment ended at, in that segment */
} ray_walk;

typedef struct {
    double t0, t1; /* along d */
    int medium;    /* -1: vacuum */
    bool hit;      /* it ends at hit h; else the ray leaves the scene there */
    bool opaque;   /* that hit is no interface */
    geom_hit h;
} walk_segment;

/* Starts the walk of o + t d in `medium`: surfaces are searched in
 * (tmin, tmax), the first segment begins at t_fill. */
static inline void walk_start(ray_walk *w, const geometry *geom, vec3 o, vec3 d, double tmin,
                              double t_fill, double tmax, double time, int medium, unsigned flags)
{
    w->geom = geom;
    w->o = o;
    w->d = d;
    w->tmin = tmin;
    w->t_fill = t_fill;
    w->tmax = tmax;
    w->time = time;
    w->t_start = w->t_end = t_fill;
    w->medium = medium;
    w->flags = flags;
    w->crossings = 0;
    w->past = (geom_past){NULL, flags & WALK_CONVEX_START ? geometry_convex_around(geom, medium)
                                                          : NULL};
    w->next = WALK_QUERY;
}

/* Steps past hit w->hit (`cross`: into the medium on its far side); false when
 * that is one crossing too many (the walk is lost). For walk_next. */
bool walk_pass(ray_walk *w, bool cross);

/* The next segment, or false when the walk is over: after the segment that
 * left the scene, or lost (walk_lost). A segment that ends at a hit is
 * followed by the one past it, whatever the hit; walk_step_over changes that
 * for an opaque one. The next call steps past the hit where this one put it
 * (seg->h, not copied: hot paths keep one segment), so *seg must live until
 * then. */
static inline bool walk_next(ray_walk *w, walk_segment *seg)
{
    switch (w->next) {
    case WALK_QUERY:
        break;
    case WALK_CROSS:
        if (!walk_pass(w, true))
            return false;
        w->t_start = w->t_end;
        break;
    case WALK_STEP_OVER:
        if (!walk_pass(w, false))
            return false;
        break;
    case WALK_DONE:
    case WALK_LOST:
        return false;
    }
    w->hit = &seg->h;
    for (;;) {
        bool hit = geometry_intersect_past(w->geom, w->past, w->o, w->d, w->tmin, w->tmax,
                                           w->time, &seg->h);
        bool opaque = hit && seg->h.shape->material->kind != MATERIAL_INTERFACE;
        if (hit && (w->flags & WALK_PASS_BEHIND) && seg->h.t < w->t_fill) {
            if (!walk_pass(w, !opaque))
                return false;
            continue;
        }
        /* A ray that leaves the scene inside a medium ends at HZ_FAR_COORD
         * (core/ray.h): no medium point beyond it is traced. */
        double t_end = !hit ? (w->medium >= 0 ? hz_fmin(w->tmax, ray_far_t(w->o, w->d)) : w->tmax)
                       : w->flags & WALK_EXACT_ENDS
                           ? hz_fmax(geometry_crossing_t(&seg->h, w->o, w->d), w->t_start)
                           : seg->h.t;
        w->t_end = t_end;
        w->next = hit ? WALK_CROSS : WALK_DONE;
        seg->t0 = w->t_start;
        seg->t1 = t_end;
        seg->medium = w->medium;
        seg->hit = hit;
        seg->opaque = opaque;
        return true;
    }
}

/* The walk goes on past the hit the last segment ended at (an opaque one
 * behind the point a shadow ray starts from) as if it were not there: same
 * medium, and the next segment begins where that one did. */
static inline void walk_step_over(ray_walk *w) { w->next = WALK_STEP_OVER; }

/* True when the walk ended at the crossing limit: the ray is dropped
 * (black), and counted as lost. */
static inline bool walk_lost(const ray_walk *w) { return w->next == WALK_LOST; }

#endif
