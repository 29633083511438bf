/* A bilinearly interpolated function on a grid over [0, 1]^2 that can be
 * sampled and its sampling inverted: the "marginal 2D warp" of Dupuy and
 * Jakob 2018 (Mitsuba's Marginal2D, pbrt-v4's PiecewiseLinear2D), which the
 * measured BRDFs (materials/measured.h) are made of.
 *
 * The grid has nx x ny values (x fastest), and may depend on up to
 * WARP2D_MAX_PARAMS parameters, each tabulated at increasing values: a
 * lookup interpolates linearly between the two neighbouring slices of each
 * parameter (clamped at the ends), so the slices are stored with the last
 * parameter fastest, then y, then x.
 *
 * A warp built for sampling has each slice normalised to integrate to 1
 * over [0, 1]^2 and keeps its marginal (over y) and conditional (over x
 * given y) cumulative sums, so that a uniform point maps to a point
 * distributed as the function (warp2d_sample) and back (warp2d_invert). */
#ifndef HAZE_MATERIALS_WARP2D_H
#define HAZE_MATERIALS_WARP2D_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/vec.h"

enum { WARP2D_MAX_PARAMS = 3 };

typedef struct {
    size_t nx, ny; /* >= 2 each */
    int n_params;
    size_t param_size[WARP2D_MAX_PARAMS];
    size_t param_stride[WARP2D_MAX_PARAMS]; /* in slices; 0 for a parameter of one value */
    float *param_values[WARP2D_MAX_PARAMS];
    size_t slices;
    float *data;            /* slices x ny x nx */
    float *marginal_cdf;    /* slices x ny; NULL when not for sampling */
    float *conditional_cdf; /* slices x ny x nx; NULL when not for sampling */
    double scale;           /* what a lookup of data is multiplied by */
} warp2d;

/* Where a lookup stands among the parameters' slices: the slices whose
 * values it blends (those of non-zero weight) and their weights. Warps
 * tabulated at the same parameter values share it. */
typedef struct {
    int n;
    size_t slice[1 << WARP2D_MAX_PARAMS];
    double weight[1 << WARP2D_MAX_PARAMS];
} warp2d_slice;

/* The slice of a warp without parameters. */
static inline warp2d_slice warp2d_slice_none(void)
{
    return (warp2d_slice){.n = 1, .weight = {1.0}};
}

/* Builds a warp of nx x ny values per slice from `data` (slices x ny x nx
 * floats, malloc'ed: the warp takes it over, and frees it on failure too)
 * and the parameters' tabulated values (n_params of them, param_size[i]
 * each, strictly increasing; copied). Values must be finite; for
 * `sampling`, also >= 0 with each slice's integral > 0. The message is the
 * reason only. */
hz_status warp2d_init(warp2d *w, float *data, size_t nx, size_t ny, int n_params,
                      const size_t *param_size, const float *const *param_values, bool sampling,
                      hz_error *err);
void warp2d_free(warp2d *w);

/* The slice position of the parameter values `params` (n_params of them). */
warp2d_slice warp2d_slice_at(const warp2d *w, const double *params);

/* The function at p (clamped to [0, 1]^2): for a sampling warp, the density
 * of warp2d_sample's points. */
double warp2d_eval(const warp2d *w, const warp2d_slice *s, vec2 p);

/* Maps the uniform u to *p, distributed with density *pdf. False when the
 * slice gives no point (a degenerate row). */
bool warp2d_sample(const warp2d *w, const warp2d_slice *s, vec2 u, vec2 *p, double *pdf);

/* The inverse of warp2d_sample: the u that maps to p, and the density there. */
vec2 warp2d_invert(const warp2d *w, const warp2d_slice *s, vec2 p, double *pdf);

#endif
