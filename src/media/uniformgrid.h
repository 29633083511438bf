/* pbrt-v4's "uniformgrid" medium: dense arrays of samples in a box, made into
 * NanoVDB grids so that every estimator, the majorant grid and empty-space
 * skipping work on it unchanged. pbrt-v4's SampledGrid places sample (i, j, k)
 * of an nx x ny x nz array at the centre of cell (i, j, k) of the box p0..p1,
 * interpolates trilinearly with 0 beyond the samples, and clips at the box:
 * the same here (a voxel per sample, cell-centred, the support clipped to the
 * box). Private to the media module (medium.c builds the medium). */
#ifndef HAZE_MEDIA_UNIFORMGRID_H
#define HAZE_MEDIA_UNIFORMGRID_H

#include <stddef.h>

#include "core/error.h"
#include "core/vec.h"
#include "media/grid.h"
#include "scene/params.h"

typedef struct {
    int n[3];                 /* "integer nx", "ny", "nz" (default 1) */
    vec3 p0, p1;              /* "point3 p0", "p1": the box, medium space (0 0 0, 1 1 1) */
    const double *density;    /* "float density": n[0] n[1] n[2] values */
    const double *temperature; /* "float temperature": as many, or NULL */
    const double *Le_scale;   /* "float Lescale": as many, or NULL (then one sample of 1) */
} uniformgrid_params;

/* Reads the grid's parameters; problems (counts, a degenerate box) are
 * recorded in pl for params_finish. */
void uniformgrid_read(param_list *pl, uniformgrid_params *u);

/* pbrt-v4's "rgbgrid": the same box and counts, and "rgb sigma_a",
 * "rgb sigma_s" (at least one; an absent one is 1 everywhere) and "rgb Le"
 * (needs sigma_a) arrays of nx ny nz triples. */
typedef struct {
    uniformgrid_params box;
    const double *sigma_a, *sigma_s, *Le; /* triples, or NULL */
} rgbgrid_params;
void rgbgrid_read(param_list *pl, rgbgrid_params *r);

/* Channel c of an array of triples, as a float grid (uniformgrid_make). */
hz_status uniformgrid_make_channel(const uniformgrid_params *u, const double *triples, int c,
                                   const char *what, grid **out, hz_error *err);

/* A float grid of `values` (count: the grid's, or 1 for a single sample
 * spanning the whole box, as pbrt-v4's default Lescale), placed in medium
 * space. Negative or non-finite values are errors naming `what`. */
hz_status uniformgrid_make(const uniformgrid_params *u, const double *values, size_t count,
                           const char *what, grid **out, hz_error *err);

/* The box p0..p1 in the index space of a grid uniformgrid_make made from
 * n[0] n[1] n[2] values: [-1/2, n - 1/2] per axis. */
void uniformgrid_support(const uniformgrid_params *u, vec3 *lo, vec3 *hi);

#endif
