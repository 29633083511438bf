/* What Integrator "singlescatter" is set up with: its settings (the
 * estimators and steps of docs/media.md) and the scene as it sees it. */
#ifndef HAZE_INTEGRATOR_SINGLESCATTER_SCENE_H
#define HAZE_INTEGRATOR_SINGLESCATTER_SCENE_H

#include <stdbool.h>

#include "core/error.h"
#include "integrator/path.h"
#include "integrator/shadow_cache.h"
#include "media/medium.h"
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
    double shadow_cache;  /* node spacing of the shadow cache, voxels
                             (integrator/shadow_cache.h); 0 = none */
    /* Steps "auto" (the default when neither transmittance nor
     * shadowtransmittance is given): the estimators are jittered marching,
     * each medium's steps scaled by singlescatter_auto_step_scale. */
    bool auto_steps;
} singlescatter_settings;

/* "auto": the optical depth of one marching step at the medium's largest
 * density (camera rays; shadow rays keep their ratio of steps), and the
 * fewest steps a ray's crossing of a medium gets. */
#define SINGLESCATTER_AUTO_TAU 0.25
#define SINGLESCATTER_AUTO_MIN_STEPS 16

/* The factor (>= 1) by which "auto" scales set's steps in grid medium m:
 * where a voxel holds less than SINGLESCATTER_AUTO_TAU / set->step of
 * optical depth, the steps grow until one holds that much, so that the
 * marching, and its cost, follow the optical depth and not the voxel
 * count; but no step longer than `chord_voxels` (the ray's span in the
 * medium) over SINGLESCATTER_AUTO_MIN_STEPS. `voxels_per_unit`: voxels per
 * unit length along the ray. 1 without set->auto_steps. */
double singlescatter_auto_step_scale(const singlescatter_settings *set, const medium *m,
                                     double voxels_per_unit, double chord_voxels);

/* Defaults, then `Integrator "singlescatter"` parameters ("float stepsize" 1,
 * "float shadowstepsize" 2, "string transmittance" "jittered", "integer
 * lightsamples" 1, "string shadowtransmittance": as transmittance, "float
 * maxcollisions" 65536, "float shadowcache" 0); errors name the entity's place.
 * Does not call params_finish. */
hz_status singlescatter_settings_from_entity(scene_entity *e, singlescatter_settings *out,
                                             hz_error *err);
singlescatter_settings singlescatter_settings_default(void);

/* What the integrator and its media walks see of the scene. */
typedef struct {
    integrator_inputs in;
    singlescatter_settings settings;
    /* Shadow transmittance is random (grid media with jittered or ratio
     * estimators): only then do delta lights take more than one sample. */
    bool stochastic_shadows;
    /* The shadow caches of distant lights in grid media at
     * settings.shadow_cache (> 0; NULL: none), borrowed: their owner builds
     * them (render/render_scene.c). */
    const shadow_caches *caches;
} singlescatter_scene;

/* The scene as single scattering sees it (borrowed pointers). */
singlescatter_scene singlescatter_scene_make(const integrator_inputs *in,
                                             singlescatter_settings settings);

#endif
