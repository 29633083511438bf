/* Pixel reconstruction filters as pbrt-v4 defines them (box, triangle,
 * gaussian, mitchell) and their importance sampling (pbrt-v4's FilterSampler:
 * exact for box and triangle, tabulated for the rest, weight = f/pdf). */
#ifndef HAZE_FILM_FILTER_H
#define HAZE_FILM_FILTER_H

#include "core/error.h"
#include "core/vec.h"
#include "scene/scene_desc.h"

typedef enum { FILTER_BOX, FILTER_TRIANGLE, FILTER_GAUSSIAN, FILTER_MITCHELL } filter_kind;

typedef struct filter filter;

typedef struct {
    vec2 p;        /* offset from the pixel centre */
    double weight; /* f(p) / pdf(p) */
} filter_sample;

/* PixelFilter "box" (xradius yradius, default 0.5), "triangle" (2), "gaussian"
 * (1.5, sigma 0.5), "mitchell" (2, B 1/3, C 1/3). */
filter *filter_create(scene_entity *e, hz_error *err);
void filter_destroy(filter *f);
filter_kind filter_get_kind(const filter *f);
vec2 filter_radius(const filter *f);
double filter_evaluate(const filter *f, vec2 p);
/* u in [0,1)^2. Deterministic, thread-safe. */
filter_sample filter_sample_offset(const filter *f, vec2 u);

#endif
