/* The walk of a ray through surfaces and medium interfaces (walk.h): its
 * step past a hit, out of line (once a crossing, beside an Embree query). */
#include "integrator/walk.h"

bool walk_pass(ray_walk *w, bool cross)
{
    /* Bounds the work of pathological nested boundaries; the ray is dropped,
     * not cut short, so that the loss is counted and reported. */
    if (++w->crossings > WALK_MAX_CROSSINGS) {
        w->next = WALK_LOST;
        return false;
    }
    if (cross)
        w->medium = geometry_medium_after(w->hit, w->d, w->medium);
    /* The query goes on along the same line, from just past the surface:
     * what lies behind stays exactly where it would be without it. */
    w->tmin = geometry_step_past(w->hit, w->o, w->d);
    /* A hit stepped over is no crossing: it tells nothing of the convex
     * meshes the ray is in or has left. */
    w->past = cross ? geometry_past(w->hit, w->d) : (geom_past){NULL, NULL};
    return true;
}
