/* pbrt-v4's projective cameras (perspective, orthographic) with the thin lens,
 * its spherical camera, ray differentials, shutter and film exposure. Rays come out in render space:
 * world translated so the camera at the middle of TransformTimes sits at the origin
 * (render_from_world is a pure translation), which keeps precision far from
 * the world origin. */
#ifndef HAZE_CAMERA_CAMERA_H
#define HAZE_CAMERA_CAMERA_H

#include <stdbool.h>

#include "core/animated_transform.h"
#include "core/error.h"
#include "core/ray.h"
#include "core/transform.h"
#include "camera/realistic.h"
#include "film/film.h"
#include "scene/scene_desc.h"

/* pbrt-v4's spherical camera: every direction around the camera, the film
 * mapped to the sphere by the equal-area octahedral map or latitude and
 * longitude (equirectangular). */
typedef enum {
    CAMERA_PERSPECTIVE,
    CAMERA_ORTHOGRAPHIC,
    CAMERA_SPHERICAL,
    CAMERA_REALISTIC /* pbrt-v4's lens system (camera/realistic.h) */
} camera_kind;

typedef struct {
    vec2 p_film;         /* raster position, continuous (pixel (x,y) covers [x,x+1)x[y,y+1)) */
    vec2 p_lens;         /* [0,1)^2 */
    double time;         /* [0,1): mapped onto [shutteropen, shutterclose] */
    double filter_weight;
} camera_sample;

typedef struct camera_s {
    camera_kind kind;
    transform render_from_camera; /* at the start time when the camera moves */
    transform world_from_render;  /* a translation */
    bool motion;                  /* the camera moves: rays use render_from_camera_motion */
    animated_transform render_from_camera_motion;
    double shutter_open, shutter_close;
    int medium;                   /* -1 = vacuum; set by the scene builder */

    /* projective */
    transform screen_from_camera, camera_from_raster, raster_from_camera;
    double screen_window[4];      /* xmin xmax ymin ymax */
    double lens_radius, focal_distance;
    double fov;                   /* degrees, perspective only */
    int blades;                   /* 0 = round aperture */
    double blade_rotation;        /* radians */
    vec3 dx_camera, dy_camera;    /* one-pixel steps in camera space (differentials) */
    int xres, yres;               /* full film resolution */
    bool equirect;                /* spherical: "equirectangular" mapping, else "equalarea" */
    /* A static perspective camera without a lens, in one step
     * (camera_generate_ray): the render-space direction through film point
     * (x, y) is normalize(pinhole_from_film * (x, y, 1)), from pinhole_o;
     * camera_from_raster's homogeneous divide and the two transforms folded
     * into one 3x3 matrix (the same ray to rounding). */
    bool pinhole;
    double pinhole_from_film[3][3];
    vec3 pinhole_o;
    realistic_lens realistic;     /* CAMERA_REALISTIC: focused, exit pupil bounded */
    /* pbrt-v4's smallest one-pixel differentials over the film's diagonal
     * (camera/footprint.h; zero until camera_find_min_differentials): origin
     * offsets in camera space, direction offsets in the frame of each ray
     * (z along it). */
    vec3 min_pos_dx, min_pos_dy, min_dir_dx, min_dir_dy;
} camera;

/* Everything camera_create reads from the scene, already interpreted: the
 * inner constructor's input, so the camera can be built (and tested) without
 * a parsed scene. Physical-lens parameters (focallength, fstop) are resolved
 * into fov and lens_radius by camera_create (see camera/lens.h). */
typedef struct {
    camera_kind kind;
    transform camera_from_world;
    /* A moving camera (pbrt-v4's animated camera transform): camera_from_world
     * at transform_start_time, camera_from_world_end at transform_end_time,
     * interpolated as pbrt's AnimatedTransform. Ignored unless `motion`. */
    bool motion;
    transform camera_from_world_end;
    double transform_start_time, transform_end_time;
    double shutter_open, shutter_close;
    double screen_window[4];      /* xmin xmax ymin ymax */
    double lens_radius, focal_distance;
    double fov;                   /* degrees, perspective: spans the window's shorter extent */
    int blades;                   /* 0 = round aperture, >= 3 = regular polygon */
    double blade_rotation;        /* degrees */
    int xres, yres;
    bool equirect;                /* spherical: "mapping" "equirectangular" */
    const realistic_lens *realistic; /* CAMERA_REALISTIC: the lens system, copied */
} camera_config;

/* pbrt-v4's defaults for a film of xres x yres: identity transform, shutter
 * [0, 1], fov 90, no lens, focal distance 1e6, screen window from the aspect
 * ratio (see camera_screen_window_from_frame). */
camera_config camera_config_default(camera_kind kind, int xres, int yres);
/* pbrt-v4's default screen window for frame aspect ratio `frame` (x over y):
 * [-frame, frame] x [-1, 1] when frame > 1, else [-1, 1] x [-1/frame, 1/frame]. */
void camera_screen_window_from_frame(double frame, double out[4]);
/* Checks a configuration. On failure fills err (no location) and returns the
 * name of the scene parameter at fault ("fov", "screenwindow", ...), so a
 * caller holding the parameter list can point at its place; NULL when valid. */
const char *camera_config_check(const camera_config *cfg, hz_error *err);
/* The inner constructor: validates cfg (camera_config_check) and builds the
 * transforms. out->medium is -1. */
hz_status camera_init(const camera_config *cfg, camera *out, hz_error *err);

/* Reads the Camera's parameters (see docs/cameras.md), with the film's
 * resolution for the screen window. */
hz_status camera_create(camera_entity *e, const film_params *film, camera *out, hz_error *err);

/* Frees what a camera from camera_create owns (a realistic camera's aperture
 * image); a zeroed camera is fine too. */
void camera_free(camera *c);

/* pbrt-v4's imaging ratio: (shutterclose - shutteropen) * iso / 100. */
double camera_imaging_ratio(const camera *c, const film_params *film);

/* Returns false when the sample makes no ray. Rays are normalised and in render space. */
bool camera_generate_ray(const camera *c, camera_sample s, ray *out);
/* The same with pbrt-v4's CameraRay weight, which scales the ray's radiance:
 * 1 for every camera but the realistic one; 0 when the sample makes no ray
 * (a realistic camera's vignetted sample: it adds black to its pixel). */
double camera_generate_ray_weighted(const camera *c, camera_sample s, ray *out);
double camera_generate_ray_differential_weighted(const camera *c, camera_sample s,
                                                 ray_differential *out);
/* For a static perspective or orthographic camera without a lens: a raster
 * rectangle out = {x0, x1, y0, y1} outside which no camera ray meets the
 * render-space box [lo, hi] (the bounds of its corners' images). False when
 * there is none: another camera, or a corner at or behind a perspective
 * camera's eye plane. */
bool camera_raster_bounds(const camera *c, vec3 lo, vec3 hi, double out[4]);
/* Whether rays depend on camera_sample.p_lens (a thin lens). */
static inline bool camera_has_lens(const camera *c)
{
    return c->lens_radius > 0.0 || c->kind == CAMERA_REALISTIC;
}
bool camera_generate_ray_differential(const camera *c, camera_sample s, ray_differential *out);

#endif
