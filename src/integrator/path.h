/* What every integrator's paths share: the per-path state of media walks, the
 * per-thread counters the renderer sums, and the shadow-ray origin rule. */
#ifndef HAZE_INTEGRATOR_PATH_H
#define HAZE_INTEGRATOR_PATH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/rng.h"
#include "core/vec.h"
#include "geometry/geometry.h"
#include "lights/lights.h"
#include "media/medium.h"

/* What every integrator reads of the built scene (borrowed). */
typedef struct {
    const geometry *geom;
    const light *lights;
    size_t light_count;
    const medium *media;
    size_t medium_count;
    /* Footprints of hits whose ray carries no differentials (volpath after a
     * diffuse bounce): estimated from this camera (camera_approximate_dpdxy)
     * at this scale, the camera rays' differential scale (pbrt-v4's
     * max(1/8, 1/sqrt(spp))). NULL or 0: none, textures are then looked up
     * without a footprint there. */
    const struct camera_s *camera;
    double footprint_scale;
} integrator_inputs;

/* Per-thread counters, summed by the renderer for the summary. */
typedef struct {
    uint64_t camera_rays, shadow_rays;
    uint64_t density_lookups;
    uint64_t majorant_steps;   /* majorant-grid cells entered by media walks */
    uint64_t lost_paths;       /* rays dropped (black) at the walk's crossing limit (walk.h) */
    /* With `timed` (haze render --stats), the nanoseconds spent in media walks
     * (camera segments and shadow rays through media) and in the film. */
    bool timed;
    uint64_t media_ns, film_ns;
} integrator_counters;

/* Per-walk state: random numbers beyond the sampler's dimensions and counters. */
typedef struct {
    double time;          /* the camera ray's scene time: shadow rays and lookups use it */
    const spectral_ctx *sp; /* spectral rendering: the path's wavelengths; NULL: RGB */
    rng r;
    uint64_t lookups;     /* grid lookups: density, and velocity for moving grids */
    uint64_t shadow_rays;
    uint64_t majorant_steps; /* majorant-grid cells entered */
    uint64_t lost;           /* shadow rays dropped at the crossing limit */
} media_walk;

/* Medium i of `in` as the walk sees it: itself in RGB, a copy at the walk's
 * wavelengths in *copy otherwise (medium_spectral). */
static inline const medium *walk_medium(const integrator_inputs *in, int i, const media_walk *w,
                                        medium *copy)
{
    return w->sp ? medium_spectral(&in->media[i], w->sp, copy) : &in->media[i];
}

/* Shadow rays from scattering points search surfaces from this fraction of
 * the point's largest render-space coordinate behind it (2^-16), so that
 * float rounding of the point cannot hide its medium's boundary. */
#define PATH_SHADOW_BACKOFF 0x1p-16

/* The shadow ray from surface hit h toward light sample ls, as both
 * integrators trace it: from h's point offset off the surface, toward the
 * light's point (lifted off an emitting surface toward the receiver), over
 * t in [0, tmax] along w (not unit: tmax is 1, or just short of an emitter),
 * or along ls->wi to infinity for an infinite light. For geometry_occluded. */
typedef struct {
    vec3 o, w;
    double tmax;
} path_shadow_ray;

path_shadow_ray path_surface_shadow_ray(const geom_hit *h, const light_sample *ls);

/* True when shadow ray r, starting in medium `start` (-1: vacuum), meets no
 * medium that can attenuate it: it stays in vacuum all the way, or every
 * medium it may enter has no density along it (media_clear_along: clear
 * space in a sparse grid, whatever interfaces it crosses). Then
 * geometry_occluded alone decides it, as in a scene without media (no walk
 * through surfaces, no random numbers). *cells counts the majorant cells the
 * second test visits. */
static inline bool path_shadow_ray_unattenuated(const integrator_inputs *in, int start,
                                                const path_shadow_ray *r, double time,
                                                uint64_t *cells)
{
    return start < 0 && (!geometry_may_cross_interface(in->geom, r->o, r->w, r->tmax) ||
                         media_clear_along(in->media, in->medium_count, r->o, r->w, 0.0, r->tmax,
                                           time, cells));
}

/* The same ray for a walk through media: w made unit (tmax a distance), and
 * *back, how far behind o the walk starts: where the ray's line crosses h's
 * tangent plane (at most a few offsets back, for grazing rays), so the medium
 * also fills the bit between the surface and the offset origin; surfaces are
 * still searched from o (t >= *back). False when the light's point is the
 * origin. */
bool path_shadow_ray_for_media(const geom_hit *h, const light_sample *ls, path_shadow_ray *r,
                               double *back);

#endif
