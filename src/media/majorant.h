/* The majorant grid of a grid medium: a coarse box grid over the density's
 * support, in the density grid's index space, holding per cell an upper and a
 * lower bound of the trilinear density anywhere in the cell. Built once from
 * the NanoVDB tree's node statistics (grid_region_range: leaf min/max, tile
 * values, the background), never from the voxels themselves.
 *
 * Cells are cubes of `cell` voxels (8, a leaf, or a power-of-two multiple of it
 * when the support is large, so that there are at most MAJORANT_MAX_CELLS),
 * aligned to multiples of `cell` in index space, like the tree's nodes. A cell
 * [a, a + cell) reads voxels a .. a + cell + 1 through trilinear lookups; its
 * bounds come from voxels a - 1 .. a + cell + 1 (a point rounded just out of
 * its cell is still bounded), dilated further by `pad` voxels per axis (the
 * largest displacement of a velocity field over the shutter).
 *
 * A ray crosses the grid with a 3D DDA (Amanatides & Woo): majorant_walk
 * returns the cells the ray passes through, in order, as t intervals with the
 * cell's bounds. Cells whose upper bound is 0 hold no medium: estimators skip
 * them without a single density lookup. */
#ifndef HAZE_MEDIA_MAJORANT_H
#define HAZE_MEDIA_MAJORANT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/vec.h"
#include "media/grid.h"

/* At most this many cells (64^3): a few MiB, and a DDA of at most ~200 steps
 * across the grid. */
#define MAJORANT_MAX_CELLS (1u << 18)

typedef struct {
    int32_t res[3];    /* cells per axis */
    int32_t origin[3]; /* index coordinate of cell (0,0,0)'s first voxel */
    int32_t cell;      /* edge of a cell in voxels */
    float *max;        /* res[0]*res[1]*res[2] upper bounds, x fastest */
    float *min;        /* lower bounds (0 unless a cell is covered by stored values) */
} majorant_grid;

/* Builds the grid covering the index box [lo, hi] (the support; lo > hi: an
 * empty grid with no cells). `pad` (>= 0, per axis) widens every cell's box of
 * voxels read. Fails only when out of memory. */
hz_status majorant_grid_build(const grid *g, vec3 lo, vec3 hi, const int32_t pad[3],
                              majorant_grid *out, hz_error *err);
void majorant_grid_free(majorant_grid *mg);
size_t majorant_grid_bytes(const majorant_grid *mg);

/* A ray's walk through the cells: o + t d in index space (same t as the
 * caller's ray), over [t0, t1]. */
typedef struct {
    const majorant_grid *mg;
    double t, t_end;
    int32_t ijk[3];
    int32_t step[3];
    double t_next[3], t_delta[3];
    bool done;
} majorant_walk;

/* One cell crossed: the interval [t0, t1] and the density bounds in it. */
typedef struct {
    double t0, t1;
    double max, min;
} majorant_segment;

/* Starts a walk over [t0, t1] (finite). False when the ray misses the grid. */
bool majorant_walk_start(majorant_walk *w, const majorant_grid *mg, vec3 o, vec3 d, double t0,
                         double t1);
/* The next cell, or false at the end of [t0, t1]. Segments are contiguous and
 * cover the part of [t0, t1] inside the grid. */
bool majorant_walk_next(majorant_walk *w, majorant_segment *seg);

#endif
