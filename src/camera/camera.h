/* pbrt-v4's projective cameras (perspective, orthographic) with the thin lens,
 * ray differentials, shutter and film exposure. Rays come out in render space:
 * world translated so the camera at mid-shutter sits at the origin
 * (render_from_world is a pure translation), which keeps precision far from
 * the world origin. */
#ifndef HAZE_CAMERA_CAMERA_H
#define HAZE_CAMERA_CAMERA_H

#include <stdbool.h>

#include "core/error.h"
#include "core/ray.h"
#include "core/transform.h"
#include "film/film.h"
#include "scene/scene_desc.h"

typedef enum { CAMERA_PERSPECTIVE, CAMERA_ORTHOGRAPHIC } camera_kind;

typedef struct {
    vec2 p_film;         /* raster position, continuous (pixel (x,y) covers [x,x+1)x[y,y+1)) */
    vec2 p_lens;         /* [0,1)^2 */
    double time;         /* [0,1): mapped onto [shutteropen, shutterclose] */
    double filter_weight;
} camera_sample;

typedef struct {
    camera_kind kind;
    transform render_from_camera;
    transform world_from_render;  /* a translation */
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
} camera;

/* Reads the Camera's parameters (see docs/cameras.md), with the film's
 * resolution for the screen window. */
hz_status camera_create(camera_entity *e, const film_params *film, camera *out, hz_error *err);

/* pbrt-v4's imaging ratio: (shutterclose - shutteropen) * iso / 100. */
double camera_imaging_ratio(const camera *c, const film_params *film);

/* Returns false when the sample makes no ray. Rays are normalised and in render space. */
bool camera_generate_ray(const camera *c, camera_sample s, ray *out);
bool camera_generate_ray_differential(const camera *c, camera_sample s, ray_differential *out);

#endif
