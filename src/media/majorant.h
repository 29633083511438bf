/* The majorant grid of a grid medium: a coarse grid over the density's
 * support, in the density grid's index space, holding per cell an upper and a
 * lower bound of the trilinear density anywhere in the cell. Built once from
 * the NanoVDB tree's node statistics (leaf min/max, tile values, the
 * background: grid_blocks, the tree walked once per brick), never from the
 * voxels themselves.
 *
 * Two levels, so that memory follows the data and not its bounding box:
 * bricks of MAJORANT_BRICK^3 cells cover the support (at most
 * MAJORANT_MAX_BRICKS of them), and only a brick whose cells differ (one that
 * holds the edge or the inside of the medium) stores its cells, and of those
 * only the occupied ones (majorant_cellmap); a brick whose every cell has the
 * same bounds (empty space, a constant tile) is one pair of floats.
 *
 * The build bounds every brick and, where the cells would fit their cap
 * whatever they hold, leaves the cells of a brick that is not uniform to
 * the first walk that enters it (or asks its bounds): loading then costs
 * one bound per brick, and a render builds the bricks its rays reach, each
 * once (on whichever thread comes first: the result is the same bits as a
 * build at loading, so images do not depend on the order). A coarse walk
 * (majorant_walk_coarsen) builds none: it reads bricks whole, and their
 * bounds are known without their cells.
 *
 * Cells are cubes of `cell` voxels (8, a leaf, or a power-of-two
 * multiple of it when the support is large or densely active), aligned to
 * multiples of `cell` in index space, like the tree's nodes; bricks to
 * multiples of MAJORANT_BRICK * cell. A cell [a, a + cell) reads voxels
 * a .. a + cell + 1 through trilinear lookups; its bounds come from voxels
 * a - 1 .. a + cell + 1 (a point rounded just out of its cell is still
 * bounded), dilated further by `pad` voxels per axis (the largest
 * displacement of a velocity field over the shutter).
 *
 * A ray crosses the grid with a two-level 3D DDA (Amanatides & Woo):
 * majorant_walk returns, in order, one t interval per uniform brick crossed
 * and one per cell of the other bricks (per brick, for a consumer that
 * marches at half a brick or coarser: majorant_walk_coarsen), with its
 * bounds, except that a run of empty ones (no density, no emission) is one
 * interval. Intervals whose upper bound is 0 hold no medium: estimators
 * skip them without a single density lookup. */
#ifndef HAZE_MEDIA_MAJORANT_H
#define HAZE_MEDIA_MAJORANT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/transform.h"
#include "core/vec.h"
#include "media/grid.h"

/* Cells per brick edge. */
#define MAJORANT_BRICK 8
#define MAJORANT_BRICK_CELLS (MAJORANT_BRICK * MAJORANT_BRICK * MAJORANT_BRICK)
/* At most this many bricks (64^3: 4 MiB, a support of 4096^3 voxels in cells
 * of 8); beyond, cells grow. Cells are stored only where they hold something
 * (see majorant_cellmap): at most MAJORANT_MIN_STORED_CELLS of them (48 MiB
 * with their boxes), or one per 16 active voxels of the grid when that is
 * more; beyond, cells grow. */
#define MAJORANT_MAX_BRICKS (1u << 18)
#define MAJORANT_MIN_STORED_CELLS (1u << 22)

typedef struct {
    float max, min; /* of the density */
    float emit;     /* upper bound of the emission grid (0 without one) */
} majorant_bounds;

/* A grid of free emission (a medium's "emissionname") the cells also bound:
 * where the density is 0 but the emission is not, a cell is not empty. */
typedef struct {
    const grid *grid;
    bool aligned;                /* the density grid's index space */
    transform eindex_from_index; /* its index from the density's index */
} majorant_emission;

/* A brick's `cells`: its map in majorant_grid.maps (>= 0), uniform (-1), or
 * not built yet (<= MAJORANT_BRICK_LAZY: slot MAJORANT_BRICK_LAZY - cells
 * of the lazy bricks). */
#define MAJORANT_BRICK_UNIFORM (-1)
#define MAJORANT_BRICK_LAZY (-2)
typedef struct {
    /* of the whole brick: every cell's when uniform, else their union (not
     * built yet: a looser bound of the brick's voxels) */
    majorant_bounds bounds;
    int32_t cells;
} majorant_brick;

/* Where in a stored cell the density may be non-zero: [lo, hi] per axis in
 * 64ths of the cell from its first voxel, rounded outward (lo > hi: nowhere).
 * Walks report the rest of the cell as empty. */
#define MAJORANT_BOX_UNITS 64
typedef struct {
    uint8_t lo[3], hi[3];
} majorant_box;

/* Which cells of a brick that stores its cells hold something (bounds other
 * than all 0: density or emission), one bit per cell, x fastest; only those
 * are stored, in cell order, so that memory follows the occupied cells and a
 * walk crosses the empty ones reading this map alone. */
#define MAJORANT_MAP_WORDS (MAJORANT_BRICK_CELLS / 64)
typedef struct {
    uint64_t occupied[MAJORANT_MAP_WORDS];
    uint16_t before[MAJORANT_MAP_WORDS]; /* its cells stored before word w */
    const majorant_bounds *cells;        /* its occupied cells, in cell order */
    const majorant_box *boxes;           /* one per stored cell; NULL: none */
} majorant_cellmap;

struct majorant_lazy; /* the bricks not built yet, and what builds them */

typedef struct {
    int32_t res[3];          /* bricks per axis */
    int32_t origin[3];       /* index coordinate of brick (0,0,0)'s first voxel */
    int32_t cell;            /* edge of a cell in voxels */
    bool boxed;              /* stored cells have boxes (zero backgrounds) */
    /* a brick not built yet has the bounds it will have (the union of its
     * cells' is the range over the same voxels: all but an emission grid
     * in another index space): coarse walks, which read bricks whole, then
     * never build one */
    bool brick_bounds_exact;
    majorant_brick *bricks;  /* res[0]*res[1]*res[2], x fastest */
    /* the bricks built at loading that store their cells */
    majorant_cellmap *maps;  /* one per such brick */
    majorant_bounds *cells;  /* their occupied cells, brick by brick (maps point in) */
    majorant_box *boxes;     /* one per stored cell; NULL when not boxed */
    size_t stored_bricks;    /* maps */
    size_t stored_cells;     /* cells */
    struct majorant_lazy *lazy; /* NULL: every brick built */
} majorant_grid;

/* Builds the grid covering the index box [lo, hi] (the support; lo > hi: an
 * empty grid with no bricks). `pad` (>= 0, per axis) widens every cell's box
 * of voxels read. `em` (NULL: none) adds the emission bounds. Fails only when
 * out of memory. */
hz_status majorant_grid_build(const grid *g, const majorant_emission *em, vec3 lo, vec3 hi,
                              const int32_t pad[3], majorant_grid *out, hz_error *err);
/* The same grid, bit for bit, from one tree query per brick and per cell
 * (grid_region_range, grid_region_support) instead of one walk of the tree
 * per brick: many times slower, kept as the reference the tests compare
 * majorant_grid_build with. */
hz_status majorant_grid_build_by_queries(const grid *g, const majorant_emission *em, vec3 lo,
                                         vec3 hi, const int32_t pad[3], majorant_grid *out,
                                         hz_error *err);
void majorant_grid_free(majorant_grid *mg);
/* What the grid holds now (lazy bricks once built). */
size_t majorant_grid_bytes(const majorant_grid *mg);
/* Brick `index` (majorant_brick_index) as walks see it: its bounds into
 * *bounds, and its map when it stores its cells (NULL: uniform). Builds it
 * when it was left to the first use. */
const majorant_cellmap *majorant_grid_brick(const majorant_grid *mg, size_t index,
                                            majorant_bounds *bounds);
/* The bricks built at their first use so far, and the time that took on
 * the threads that built them (seconds summed over threads). */
typedef struct {
    size_t bricks;
    double seconds;
} majorant_work;
majorant_work majorant_grid_work(const majorant_grid *mg);
/* Builds every brick not built yet (on every core) and counts the bricks
 * that store their cells and the cells stored. */
void majorant_grid_count(const majorant_grid *mg, size_t *bricks, size_t *cells);
/* The bounds of the cell holding the index-space point p; false outside the
 * grid. */
bool majorant_grid_bounds_at(const majorant_grid *mg, vec3 p, majorant_bounds *out);

/* A ray's walk through the grid: o + t d in index space (same t as the
 * caller's ray), over [t0, t1]. */
typedef struct {
    const majorant_grid *mg;
    double t, t_end;
    double u0[3], du[3]; /* the ray in cell units: u = u0 + t du */
    int32_t step[3];
    /* brick level */
    int32_t brick[3];
    double brick_next[3], brick_delta[3];
    /* cell level, while inside a brick that stores its cells */
    const majorant_cellmap *map;  /* the brick's map; NULL at brick level */
    int32_t ci;                   /* the current cell's index in the brick */
    int32_t cell_ijk[3];          /* its place in the brick: 0 .. MAJORANT_BRICK - 1 */
    int32_t cell_stride[3];       /* step[a] x the cell's stride along a */
    double cell_next[3], cell_delta[3];
    double brick_exit;
    /* where the current cell's box lies on the ray (boxes only) */
    const majorant_bounds *clip_cell; /* the cell clip_t0/clip_t1 belong to */
    double clip_t0, clip_t1;
    bool coarse; /* report bricks whole (majorant_walk_coarsen) */
    bool done;
} majorant_walk;

/* One interval crossed: [t0, t1] and the density bounds in it (and the
 * emission's upper bound). */
typedef struct {
    double t0, t1;
    double max, min;
    double emit;
} majorant_segment;

/* Starts a walk over [t0, t1] (finite). False when the ray misses the grid. */
bool majorant_walk_start(majorant_walk *w, const majorant_grid *mg, vec3 o, vec3 d, double t0,
                         double t1);
/* Tells a walk, before its first step, that its consumer samples the ray no
 * finer than every `voxels` voxels and reads of the bounds only whether they
 * are 0 (marching): when that is at least half a brick's edge, every brick
 * comes as one interval with the brick's bounds, so the walk costs a step
 * per brick, not per cell. Empty runs are still merged and skipped; what is
 * lost is only the cells' finer empty space, which such a consumer crosses
 * in one or two samples, each a lookup that finds 0: the values are the
 * same. (On sphere-100 at steps of 40 and 80 voxels, half a brick against a
 * whole one: 157 steps a pixel against 279, 0.8% more lookups, 5% less
 * time.) */
static inline void majorant_walk_coarsen(majorant_walk *w, double voxels)
{
    w->coarse = voxels >= 0.5 * MAJORANT_BRICK * w->mg->cell;
}

/* ---- the walk's steps, inline: they run once per cell crossed ---- */

static inline size_t majorant_brick_index(const majorant_grid *mg, const int32_t b[3])
{
    return ((size_t)b[2] * (size_t)mg->res[1] + (size_t)b[1]) * (size_t)mg->res[0] +
           (size_t)b[0];
}

static inline bool majorant_box_full(const majorant_box *bx)
{
    return (bx->lo[0] | bx->lo[1] | bx->lo[2]) == 0 &&
           (bx->hi[0] & bx->hi[1] & bx->hi[2]) == MAJORANT_BOX_UNITS;
}

/* Starts the cell level in a brick that stores its cells (map), at w->t. */
void majorant_walk_enter_brick(majorant_walk *w, const majorant_cellmap *map, double exit);
/* Sets clip_t0/clip_t1 to the box of stored cell k (the current one) along
 * the ray. */
void majorant_walk_clip(majorant_walk *w, size_t k);

static inline bool majorant_cell_occupied(const majorant_cellmap *m, int32_t i)
{
    return (m->occupied[i >> 6] >> (i & 63)) & 1u;
}

/* Bits set in v (SWAR: without -mpopcnt the builtin is a library call). */
static inline uint32_t majorant_popcount(uint64_t v)
{
    v -= (v >> 1) & UINT64_C(0x5555555555555555);
    v = (v & UINT64_C(0x3333333333333333)) + ((v >> 2) & UINT64_C(0x3333333333333333));
    v = (v + (v >> 4)) & UINT64_C(0x0f0f0f0f0f0f0f0f);
    return (uint32_t)((v * UINT64_C(0x0101010101010101)) >> 56);
}

/* Where occupied cell i of the brick is stored: its index in m->cells. */
static inline size_t majorant_cell_slot(const majorant_cellmap *m, int32_t i)
{
    uint64_t below = m->occupied[i >> 6] & ((UINT64_C(1) << (i & 63)) - 1u);
    return (size_t)m->before[i >> 6] + majorant_popcount(below);
}

static inline bool majorant_bounds_empty(majorant_bounds b)
{
    return !(b.max > 0.0f) && !(b.emit > 0.0f);
}

static inline int majorant_nearest_axis(const double t[3])
{
    return t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
}

/* Reports [w->t, t1] with bounds b and moves on to t1. */
static inline void majorant_walk_emit(majorant_walk *w, majorant_segment *seg, double t1,
                                      majorant_bounds b)
{
    seg->t0 = w->t;
    seg->t1 = t1 > w->t ? t1 : w->t;
    seg->max = b.max;
    seg->min = b.min;
    seg->emit = b.emit;
    w->t = seg->t1;
}

/* Steps the brick level past the current brick (whose exit is on axis a). */
static inline void majorant_walk_next_brick(majorant_walk *w, int a)
{
    if (!(w->brick_next[a] < w->t_end)) {
        w->done = true;
        return;
    }
    w->brick[a] += w->step[a];
    w->brick_next[a] += w->brick_delta[a];
    if (w->brick[a] < 0 || w->brick[a] >= w->mg->res[a])
        w->done = true; /* rounding left the box a little early: the rest is outside */
}

/* The current cell's next piece (cell level): its end *t1 and bounds;
 * *whole: the piece ends the cell (else a box splits it and the cell goes
 * on). */
static inline majorant_bounds majorant_walk_piece(majorant_walk *w, double *t1, bool *whole)
{
    const majorant_bounds zero = {0.0f, 0.0f, 0.0f};
    *whole = true;
    if (!majorant_cell_occupied(w->map, w->ci))
        return zero;
    size_t k = majorant_cell_slot(w->map, w->ci);
    majorant_bounds b = w->map->cells[k];
    if (w->map->boxes && b.max > 0.0f && !majorant_box_full(&w->map->boxes[k])) {
        /* up to three pieces: before the box, in it, after it */
        if (w->clip_cell != &w->map->cells[k])
            majorant_walk_clip(w, k);
        bool inside = !(w->t < w->clip_t0) && w->t < w->clip_t1;
        double change = w->t < w->clip_t0 ? w->clip_t0 : w->clip_t1;
        if (!inside)
            b = zero;
        if (change > w->t && change < *t1) {
            *t1 = change;
            *whole = false;
        }
    }
    return b;
}

/* The next interval, or false at the end of [t0, t1]. Segments are
 * contiguous and cover the part of [t0, t1] inside the grid. Consecutive
 * empty cells and bricks (no density, no emission) come as one interval:
 * the DDA still crosses them one by one (so every boundary is the same
 * number whatever was merged before it), but reads only the bricks' bounds
 * and cell maps there. */
static inline bool majorant_walk_next(majorant_walk *w, majorant_segment *seg)
{
    bool run = false; /* empty pieces since run_t0, not reported yet */
    double run_t0 = 0.0;
    while (!w->done) {
        majorant_bounds b;
        bool empty;
        if (w->map) {
            int a = majorant_nearest_axis(w->cell_next);
            int32_t c = w->cell_ijk[a] + w->step[a];
            bool leave = !(w->cell_next[a] < w->brick_exit) || (uint32_t)c >= MAJORANT_BRICK;
            double t1 = leave ? w->brick_exit : w->cell_next[a];
            bool whole;
            b = majorant_walk_piece(w, &t1, &whole);
            empty = majorant_bounds_empty(b);
            if (!empty && run)
                break;
            if (empty && !run) {
                run = true;
                run_t0 = w->t;
            }
            majorant_walk_emit(w, seg, t1, b);
            if (whole && leave) {
                w->map = NULL;
                majorant_walk_next_brick(w, majorant_nearest_axis(w->brick_next));
            } else if (whole) {
                w->cell_ijk[a] = c;
                w->ci += w->cell_stride[a];
                w->cell_next[a] += w->cell_delta[a];
            }
        } else {
            int a = majorant_nearest_axis(w->brick_next);
            double exit = w->brick_next[a] < w->t_end ? w->brick_next[a] : w->t_end;
            size_t bi = majorant_brick_index(w->mg, w->brick);
            const majorant_brick *br = &w->mg->bricks[bi];
            const majorant_cellmap *map = NULL;
            b = br->bounds;
            if (br->cells >= 0)
                map = &w->mg->maps[br->cells];
            else if (br->cells <= MAJORANT_BRICK_LAZY && !(w->coarse && w->mg->brick_bounds_exact))
                map = majorant_grid_brick(w->mg, bi, &b);
            if (map && !w->coarse) {
                majorant_walk_enter_brick(w, map, exit);
                continue;
            }
            empty = majorant_bounds_empty(b);
            if (!empty && run)
                break;
            if (empty && !run) {
                run = true;
                run_t0 = w->t;
            }
            majorant_walk_emit(w, seg, exit, b);
            majorant_walk_next_brick(w, a);
        }
        if (!empty)
            return true;
    }
    if (!run)
        return false;
    seg->t0 = run_t0;
    seg->t1 = w->t;
    seg->max = seg->min = seg->emit = 0.0;
    return true;
}

#endif
