/* The renderable scene: everything the factories built from a scene_desc
 * (camera, film, sampler, filter, Embree geometry, lights, materials), in
 * render space, plus the integrator that computes radiance along a camera ray. */
#ifndef HAZE_RENDER_RENDER_SCENE_H
#define HAZE_RENDER_RENDER_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "camera/camera.h"
#include "core/error.h"
#include "core/ray.h"
#include "film/film.h"
#include "film/filter.h"
#include "geometry/geometry.h"
#include "integrator/integrator.h"
#include "lights/lights.h"
#include "sampler/sampler.h"
#include "scene/scene_desc.h"

/* How colour is carried along paths (docs/spectral.md): in RGB, or
 * spectrally (four wavelengths per camera sample, color/wavelengths.h;
 * either integrator). AUTO: as render/color_choice.h decides. */
typedef enum { RENDER_COLOR_AUTO = 0, RENDER_COLOR_RGB, RENDER_COLOR_SPECTRAL } render_color;

typedef struct {
    uint64_t seed;             /* default for the Sampler's "integer seed" (--seed) */
    bool seed_given;           /* --seed was given: it wins over Option "seed" */
    int spp;                   /* > 0 overrides the sampler's count (--spp) */
    const char *output;        /* non-NULL overrides the Film's filename (-o) */
    film_region region;        /* replaces the Film's cropwindow/pixelbounds unless NONE
                                * (--pixelbounds, --cropwindow) */
    bool statistics;           /* the film keeps (and writes) variance and sample
                                * counts whatever the Film says (--target-error) */
    bool portable_isa;         /* Embree at SSE4.2 on every machine (--portable-isa) */
    render_color color;        /* --color: RGB or spectral rendering */
} render_options;

typedef struct render_scene render_scene;

/* pbrt-v4's Option directives haze honours: "integer seed" (as --seed, when
 * --seed is not given; a Sampler's "integer seed" still wins), "bool
 * disablepixeljitter" (as --disable-pixel-jitter), "bool forcediffuse" (volpath
 * replaces each BSDF by a diffuse one of its albedo, as pbrt-v4),
 * "string rendercoordsys" (haze renders in camera-world space whatever the
 * value: "camera", "cameraworld" and "world" differ only in float rounding).
 * Any other Option is refused at its place. */
typedef struct {
    bool disable_pixel_jitter;
    bool force_diffuse; /* "forcediffuse": every BSDF replaced by a diffuse one (volpath) */
} scene_options;
scene_options render_scene_options(const render_scene *rs);

/* Runs every factory; errors name the file:line:column of the offending entity.
 * Warnings (e.g. an unsupported sampler replaced by sobol) are written to `warn`
 * (one per line) when it is not NULL. */
hz_status render_scene_create(scene_desc *sd, const render_options *opt, FILE *warn,
                              render_scene **out, hz_error *err);
void render_scene_destroy(render_scene *rs);
/* For a scene whose parse found errors (scene_parse_file_all): runs the
 * factories on what parsed only to find its other problems, adds them to
 * `errs` (no warnings) and reports the lot, in file order, in `err`. Returns
 * HZ_OK only when `errs` stayed empty. */
hz_status render_scene_check(scene_desc *sd, const render_options *opt, hz_errors *errs,
                             hz_error *err);

const camera *render_scene_camera(const render_scene *rs);
/* The scene has textures, or its film is a gbuffer (whose depth slopes
 * need them): camera rays should carry differentials. */
bool render_scene_has_textures(const render_scene *rs);
/* The camera rays' differential scale, which footprints estimated later on a
 * path use too (integrator_inputs.footprint_scale); 0 (the default): none. */
void render_scene_set_footprint_scale(render_scene *rs, double scale);
film *render_scene_film(render_scene *rs);
const sampler *render_scene_sampler(const render_scene *rs);
const filter *render_scene_filter(const render_scene *rs);
/* The scene's surfaces and lights (for bench/embree_loop.c). */
const geometry *render_scene_geometry(const render_scene *rs);
/* A raster rectangle out = {x0, x1, y0, y1} (empty when x0 > x1) outside
 * which a camera ray's radiance is black and nothing is hit: the camera in
 * vacuum, no infinite light, and no shape outside the image of the box
 * around the static shapes (camera_raster_bounds). False when it cannot
 * be told. */
bool render_scene_black_outside(const render_scene *rs, double out[4]);
size_t render_scene_light_count(const render_scene *rs);
const light *render_scene_lights(const render_scene *rs);

/* What moves during the shutter: a scene pays for motion only where it has
 * some (static Embree scene, no time steps, no per-ray grid transforms). */
typedef struct {
    bool camera;   /* animated camera transform */
    bool surfaces; /* animated shapes or instances (Embree motion blur) */
    size_t media;  /* grid media that move (animated transform or velocity grid) */
} render_motion;

render_motion render_scene_motion(const render_scene *rs);

/* What the scene holds in memory, in bytes: NanoVDB buffers (density and
 * velocity grids, majorant grids), the film, Embree's peak and the shadow
 * caches. */
typedef struct {
    double grids, majorants, film, embree, shadow_caches;
} render_memory;
render_memory render_scene_memory(const render_scene *rs);
/* The work the scene's media did on demand so far, summed over them. */
medium_work render_scene_media_work(const render_scene *rs);

/* The singlescatter integrator's shadow caches (integrator/shadow_cache.h);
 * NULL when it has none. */
const shadow_caches *render_scene_shadow_caches(const render_scene *rs);

/* The marching of a singlescatter scene with grid media (estimators and
 * steps, voxels): false (m untouched) for other integrators, scenes without
 * grid media, and tracking estimators, which have no marching bias. */
typedef struct {
    transmittance_mode mode, shadow_mode;
    double step, shadow_step;
    double shadow_cache;       /* the shadow cache's spacing, voxels (0: none) */
    bool shadow_cache_possible; /* static, a grid medium rays enter, a distant light */
    /* transmittance "auto" (the default): the least factor by which it
     * scales the steps in the scene's grid media
     * (singlescatter_auto_step_scale); 1 without */
    bool auto_steps;
    double auto_scale;
} render_marching;
bool render_scene_marching(const render_scene *rs, render_marching *m);
/* Sets it (on a scene where render_scene_marching is true), building the
 * shadow caches at a new spacing (a few are kept: setting an earlier
 * spacing again reuses them; one that cannot be built means shadow rays).
 * Not while rendering. */
void render_scene_set_marching(render_scene *rs, const render_marching *m);
/* Frees the shadow caches the scene's settings do not use. */
void render_scene_keep_current_cache(render_scene *rs);
#define RENDER_SCENE_CACHES 4

/* Radiance arriving along the camera ray `r`, as linear sRGB (spectral
 * rendering draws the sample's wavelengths and turns their radiance into it).
 * `depth` receives the distance to the first surface hit (INFINITY when
 * none). Thread-safe; allocates nothing. */
rgb render_scene_li(const render_scene *rs, const ray_differential *r, sampler_state *s,
                    double *depth, integrator_counters *counters);
/* The same as the film takes it (film_add_sample), and what the ray saw
 * first for a gbuffer film (integrator_li): under spectral rendering with a
 * camera sensor, the sensor's RGB of the sample's wavelengths
 * (film_take_sensor_rgb). */
rgb render_scene_li_surface(const render_scene *rs, const ray_differential *r, sampler_state *s,
                            double *depth, film_surface *vs, integrator_counters *counters);
/* Whether paths carry wavelengths (render_options.color). */
bool render_scene_spectral(const render_scene *rs);

#endif
