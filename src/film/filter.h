/* Pixel reconstruction filters as pbrt-v4 defines them (box, triangle,
 * gaussian, mitchell) and their importance sampling (pbrt-v4's FilterSampler:
 * exact for box and triangle, tabulated for the rest, weight = f/pdf). */
#ifndef HAZE_FILM_FILTER_H
#define HAZE_FILM_FILTER_H

#include "core/error.h"
#include "core/vec.h"
#include "scene/scene_desc.h"

/* FILTER_LANCZOS is pbrt-v4's "sinc" filter (windowed sinc, radius 4, tau 3). */
typedef enum { FILTER_BOX, FILTER_TRIANGLE, FILTER_GAUSSIAN, FILTER_MITCHELL, FILTER_LANCZOS } filter_kind;

typedef struct filter filter;

typedef struct {
    vec2 p;        /* offset from the pixel centre */
    double weight; /* f(p) / pdf(p) */
} filter_sample;

/* PixelFilter "box" (xradius yradius, default 0.5), "triangle" (2), "gaussian"
 * (1.5, sigma 0.5), "mitchell" (2, B 1/3, C 1/3), "sinc" (alias "lanczos":
 * 4, tau 3). Radii must lie in (0, 32]. */
filter *filter_create(scene_entity *e, hz_error *err);
void filter_destroy(filter *f);
filter_kind filter_get_kind(const filter *f);
vec2 filter_radius(const filter *f);
double filter_evaluate(const filter *f, vec2 p);
/* Integral of f over its support (pbrt-v4's Filter::Integral). */
double filter_integral(const filter *f);
/* u in [0,1)^2. Deterministic, thread-safe, no allocation. Box and triangle
 * return weight 1; tabulated filters return f(cell)/pdf, i.e. plus or minus
 * the tabulated integral of |f| (as pbrt-v4). */
filter_sample filter_sample_offset(const filter *f, vec2 u);

#endif
