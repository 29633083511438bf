/* Single scattering in participating media: the part of haze's integrator that
 * walks a ray through media. Only scenes with media reach this code.
 *
 * Along a ray segment [t0, t1] inside one medium it estimates, jointly,
 *   the transmittance T(t0, t1) and
 *   the in-scattered radiance  ∫ T(t0, t) σ_s(t) Σ_lights p(wo, wi) L_i T_shadow dt.
 *
 * Homogeneous media use closed-form transmittance and sample scattering
 * distances: exponentially (by transmittance), and for point and spot lights
 * also equiangularly around the light (Kulla & Fajardo 2012), the two combined
 * with the balance heuristic. Grid media place in-scattering samples on
 * `stepsize`-voxel strata of the segment and estimate transmittance by
 *   TRANSMITTANCE_RAYMARCH   fixed steps (midpoint; biased, error shrinks with the step),
 *   TRANSMITTANCE_JITTERED   steps with one random offset per ray (banding becomes noise),
 *   TRANSMITTANCE_RATIO      ratio tracking against each majorant-grid cell's bound (unbiased),
 *   TRANSMITTANCE_RESIDUAL   residual ratio tracking: the cell's lower bound as an exact
 *                            control, collisions only for the residual (unbiased).
 * Every estimator walks the medium's majorant grid (media/majorant.h): empty
 * cells cost no density lookup.
 * Shadow rays use the same estimator with `shadowstepsize`. Low transmittance
 * ends a walk by Russian roulette, never by a cutoff. Moving grids (animated
 * placement, velocity grids) are looked up at the walk's time everywhere:
 * camera rays, shadow rays, every estimator. */
#ifndef HAZE_RENDER_VOLUME_H
#define HAZE_RENDER_VOLUME_H

#include <stddef.h>

#include "core/error.h"
#include "core/rng.h"
#include "core/vec.h"
#include "media/medium.h"
#include "render/geometry.h"
#include "render/lights.h"
#include "sampler/sampler.h"
#include "scene/scene_desc.h"

typedef enum {
    TRANSMITTANCE_RAYMARCH,
    TRANSMITTANCE_JITTERED,
    TRANSMITTANCE_RATIO,
    TRANSMITTANCE_RESIDUAL,
} transmittance_mode;

typedef struct {
    transmittance_mode mode;        /* camera rays */
    transmittance_mode shadow_mode; /* shadow rays ("shadowtransmittance"; default: mode) */
    double step;          /* in-scattering sample spacing along camera rays, voxels */
    double shadow_step;   /* marching step of shadow rays, voxels */
    double max_collisions; /* ratio: a segment expecting more tentative collisions
                              (majorant x length) is marched (jittered) instead;
                              0 = never */
    int light_samples;    /* samples of each light per scattering point (delta
                             lights: only with stochastic shadows, else 1) */
} volume_settings;

/* A ray crossing more interfaces than this is treated as lost (black): it
 * bounds the work of pathological nested boundaries. */
#define VOLUME_MAX_CROSSINGS GEOMETRY_MAX_CROSSINGS

/* Shadow rays from scattering points search surfaces from this fraction of
 * the point's largest render-space coordinate behind it (2^-16), so that
 * float rounding of the point cannot hide its medium's boundary. */
#define VOLUME_SHADOW_BACKOFF 0x1p-16

/* Below this largest transmittance component a walk plays Russian roulette. */
#define VOLUME_RR_THRESHOLD 1e-2

/* Defaults, then `Integrator "singlescatter"` parameters ("float stepsize" 1,
 * "float shadowstepsize" 2, "string transmittance" "jittered", "integer
 * lightsamples" 1, "string shadowtransmittance": as transmittance, "float
 * maxcollisions" 65536); errors name the entity's place. Does not call params_finish. */
hz_status volume_settings_from_entity(scene_entity *e, volume_settings *out, hz_error *err);
volume_settings volume_settings_default(void);

/* What a walk needs of the scene (the integrator sees the same). */
typedef struct {
    const geometry *geom;
    const light *lights;
    size_t light_count;
    const medium *media;
    size_t medium_count;
    volume_settings settings;
    /* Shadow transmittance is random (grid media with jittered or ratio
     * estimators): only then do delta lights take more than one sample. */
    bool stochastic_shadows;
} volume_scene;

/* Per-walk state: random numbers beyond the sampler's dimensions and counters. */
typedef struct {
    double time;          /* the camera ray's scene time: shadow rays and lookups use it */
    rng r;
    uint64_t lookups;     /* grid lookups: density, and velocity for moving grids */
    uint64_t shadow_rays;
    uint64_t majorant_steps; /* majorant-grid cells entered */
    uint64_t lost;           /* shadow rays dropped after VOLUME_MAX_CROSSINGS interfaces */
} volume_walk;

/* Where the double-precision ray o + t w crosses the surface of hit `h` (found
 * by Embree from o rounded to float, and h->t rounded to float): h->t moved
 * along w onto the tangent plane at h->p, which lies on the surface. Media
 * segments start and end there, so a medium denser than float rounding is
 * bounded where its surface is. */
double volume_crossing_t(const geom_hit *h, vec3 o, vec3 w);

/* Transmittance from `o` along unit `w` to distance `tmax` (INFINITY: to the end
 * of the scene), starting in `medium` (-1 vacuum): every medium segment
 * attenuates, interfaces switch the medium, any other surface blocks (black).
 * Surfaces are searched from `tmin` on (past the surface `o` lies on, if any);
 * media fill the whole span from 0. */
rgb volume_shadow_transmittance(const volume_scene *vs, vec3 o, vec3 w, double tmin, double tmax,
                                int medium, volume_walk *walk);

/* The segment [t0, t1] (t1 may be INFINITY) of the unit-direction ray o + t w in
 * medium `m`: adds beta × (in-scattered radiance) to *L and multiplies beta by
 * the segment's transmittance (estimated; may become 0 by Russian roulette).
 * `u` supplies the sampler's dimensions for distance sampling. */
void volume_segment(const volume_scene *vs, int m, vec3 o, vec3 w, double t0, double t1,
                    rgb *beta, rgb *L, sampler_state *u, volume_walk *walk);

#endif
