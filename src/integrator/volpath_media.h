/* Null-scattering tracking through one medium for the volpath integrator
 * (pbrt-v4's SampleT_maj): tentative collisions are sampled along a ray
 * segment at the rate of the majorant sigma_maj in the path's hero channel;
 * at each one the caller decides (absorb, scatter, null) with the medium's
 * coefficients there. Homogeneous media have sigma_maj = sigma_t; grid media
 * walk their majorant grid (media/majorant.h) with sigma_maj = sigma_t times
 * each cell's density bound, so empty cells cost no lookup and no random
 * number. Random numbers come from the walk's rng (thread-count independent). */
#ifndef HAZE_INTEGRATOR_VOLPATH_MEDIA_H
#define HAZE_INTEGRATOR_VOLPATH_MEDIA_H

#include <stdbool.h>

#include "core/vec.h"
#include "media/medium.h"
#include "integrator/path.h"

/* One tentative collision at distance t: the coefficients there, the
 * majorant, the majorant transmittance since the previous collision (or
 * the segment's start), and the emission. */
typedef struct {
    double t;
    rgb sigma_a, sigma_s, sigma_maj, T_maj;
    rgb emission; /* the source term there, per unit length: sigma_a Le (pbrt-v4's
                   * absorbing emission) plus a free emission grid's; 0 when the
                   * walk does not gather emission */
} volpath_event;

/* Returns false to end the walk. */
typedef bool (*volpath_event_fn)(void *ctx, const volpath_event *ev);

/* A walk gives up after this many tentative collisions on one segment: a grid
 * at an absurd density scale (1e12) whose majorant cell covers empty voxels
 * would otherwise take ~1e12 null collisions per unit length (pbrt-v4 hangs
 * there). Such a segment counts as opaque (see docs/media.md); real scenes
 * stay many orders of magnitude below (a few hundred per segment). */
#define VOLPATH_MAX_COLLISIONS (1u << 16)

/* Walks o + t w (unit w) over [t0, t1] (t1 may be INFINITY) in medium m at the
 * walk's time, calling `fn` at each tentative collision. Returns the majorant
 * transmittance from the last collision to t1, (1, 1, 1) when `fn` ended the
 * walk, or (0, 0, 0) past VOLPATH_MAX_COLLISIONS. `hero` in 0..2 is the
 * channel whose majorant sets the rate. With `emission` (a path's segment,
 * not a shadow ray's) the events carry the emission, and cells where a free
 * emission grid glows but there is no density get tentative collisions too
 * (two expected per cell). */
rgb volpath_track(const medium *m, vec3 o, vec3 w, double t0, double t1, int hero, bool emission,
                  media_walk *walk, volpath_event_fn fn, void *ctx);

#endif
