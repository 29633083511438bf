/* Textures: pbrt-v4's `Texture "name" "float"|"spectrum" "class" params`, a
 * closed set of classes evaluated at a surface point. A spectrum texture
 * gives rgb; a float texture gives its value in all three channels.
 * Classes: "constant", "scale", "mix", "directionmix", "checkerboard" (2D,
 * box-filtered as pbrt-v4), "bilerp", "dots" and "imagemap" (EXR or PNG)
 * with pbrt-v4's "uv" mapping; "fbm", "wrinkled", "windy" (float) and
 * "marble" (spectrum) on the point in the texture's space (the transform at
 * the Texture directive). docs/scene-format.md lists what is refused. */
#ifndef HAZE_TEXTURES_TEXTURE_H
#define HAZE_TEXTURES_TEXTURE_H

#include <stdbool.h>

#include "core/error.h"
#include "core/transform.h"
#include "core/vec.h"
#include "scene/scene_desc.h"

/* Where a texture is evaluated: surface (u, v), their screen-space
 * derivatives (0 = no footprint: no filtering) and the render-space point. */
typedef struct {
    double u, v;
    double dudx, dudy, dvdx, dvdy;
    vec3 p;
    vec3 dpdx, dpdy; /* the point's change per pixel (0: no footprint) */
    vec3 n;          /* geometric normal (directionmix), render space */
} texture_ctx;

typedef struct texture texture;
typedef struct texture_set texture_set;

/* Builds every texture of `sd` in file order; a texture may name only
 * textures defined before it. An error with a place (a texture's) is
 * collected in `errs` and that texture becomes a constant 0; one without
 * (memory) ends the build in `err`. */
hz_status texture_set_create(scene_desc *sd, transform render_from_world, hz_errors *errs,
                             texture_set **out, hz_error *err);
void texture_set_destroy(texture_set *s);

/* The texture of that name and value type, or NULL. */
const texture *texture_set_find(const texture_set *s, const char *name, bool spectrum);
/* The image a material's "string normalmap" names (read by
 * texture_set_create, linear RGB, bilinear at (u, 1 - v), repeated), as an
 * RGB texture; NULL when it could not be read (that error was reported). */
const texture *texture_set_normal_map(const texture_set *s, const char *name);

/* The value at c: rgb for spectrum textures, grey for float ones. */
rgb texture_eval(const texture *t, const texture_ctx *c);
double texture_eval_float(const texture *t, const texture_ctx *c);
/* True when every value t gives is grey (r = g = b): float textures, and
 * spectrum textures whose inputs and image are all grey. */
bool texture_is_grey(const texture *t);

#endif
