/* The images of lights (envmap.c): an image infinite light's map of
 * directions, and the images of goniometric, projection and image area
 * lights; read from EXR, looked up, sampled and summed. */
#ifndef HAZE_LIGHTS_ENVMAP_H
#define HAZE_LIGHTS_ENVMAP_H

#include <stdbool.h>

#include "core/error.h"
#include "core/vec.h"

/* The image of an image infinite light (envmap.c): pbrt-v4's equal-area
 * octahedral square map of directions in the light's space, looked up at the
 * nearest texel, sampled by the piecewise-constant density of its texels'
 * channel average. */
typedef struct light_image light_image;
/* An EXR with R, G, B (or only Y) channels, square when `square`; non-finite
 * texels refused, negative ones read as 0. */
hz_status light_image_from_exr(const char *path, bool square, light_image **out, hz_error *err);
/* The texels that had a negative channel (read as 0), for a warning. */
size_t light_image_negative_texels(const light_image *m);
/* A 1x1 map of 1: a constant sky as an image light (for a portal). */
hz_status light_image_white(light_image **out, hz_error *err);
void light_image_destroy(light_image *m);
void light_image_size(const light_image *m, int *w, int *h);
rgb light_image_lookup(const light_image *m, vec2 uv);
/* Bilinear between texel centres, clamped at the edges (pbrt-v4's Bilerp). */
rgb light_image_bilerp(const light_image *m, vec2 uv);
/* Density over the unit square (1 everywhere for an all-black map). */
double light_image_pdf(const light_image *m, vec2 uv);
/* u in [0,1)^2 -> a point of the square with *pdf = light_image_pdf there. */
vec2 light_image_sample(const light_image *m, vec2 u, double *pdf);
/* The channel average at uv (a goniometric light's relative intensity),
 * and its mean over the texels. */
double light_image_value(const light_image *m, vec2 uv);
double light_image_mean(const light_image *m);
/* Mean luminance (linear sRGB weights) of the texels: pbrt-v4's k_e of an
 * image area light's "power". */
double light_image_luminance(const light_image *m);
/* Mean RGB of the texels, and pbrt-v4's "illuminance" of the map. */
rgb light_image_average(const light_image *m);
double light_image_illuminance(const light_image *m);

#endif
