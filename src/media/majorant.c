#define _POSIX_C_SOURCE 200809L
#include "media/majorant.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/clock.h"
#include "core/parallel.h"

#define B MAJORANT_BRICK
#define CELLS_PER_BRICK (B * B * B)
/* A brick of the largest cells is 2^30 voxels: at most 5 per axis of the
 * int32 index space, so the layout always fits. */
#define MAX_CELL (1 << 27)
/* The most 8^3 blocks a worker reads a brick's box into (12 MiB): bricks of
 * leaf-sized cells take 10^3, of 64-voxel cells 66^3; larger cells or pads
 * ask the tree per cell instead. */
#define WINDOW_MAX_BLOCKS ((size_t)1 << 19)

/* floor(v / c) for a positive c, in 64 bits. */
static int64_t floor_div(int64_t v, int64_t c) { return v >= 0 ? v / c : -((-v + c - 1) / c); }

/* What the majorant reads: the grid and the box of its active voxels
 * (outside it, every voxel is the background). */
typedef struct {
    const grid *g;
    grid_ibox active;
    bool empty;
    const int32_t *pad;
    const majorant_emission *em; /* NULL: none */
    grid_ibox em_active;
    bool em_empty;
    transform index_from_eindex; /* em not aligned: back from its index space */
    bool boxes;                  /* cells get boxes (zero backgrounds) */
    bool by_queries;             /* no windows: one tree query per box */
} source;

/* One grid's 8^3 blocks over a brick's box, read from the tree the first
 * time a box of the brick asks (grid_blocks): every cell's bounds and box
 * then take a few reads of it, and the tree is walked once per brick, not
 * once per cell (a cell's box reads 27 leaves). Not filled (too large, no
 * memory, or by_queries): boxes ask the tree. */
typedef struct {
    const grid *g;
    grid_block *blocks;
    size_t cap;
    grid_ibox at; /* the window, in blocks */
    int64_t n[3];
    bool pending, filled;
} window;

/* A worker's view of the source: its windows over the current brick. */
typedef struct {
    const source *src;
    window dens, emis; /* emis: an aligned emission grid's */
    float *scratch;    /* brick_ranges' passes */
    size_t scratch_cap;
} reader;

static void window_free(window *w)
{
    free(w->blocks);
    w->blocks = NULL;
    w->cap = 0;
}

/* The window will cover voxel box `box`, once asked. */
static void window_aim(window *w, grid_ibox box)
{
    for (int a = 0; a < 3; ++a) {
        w->at.min[a] = (int32_t)floor_div(box.min[a], 8);
        w->at.max[a] = (int32_t)floor_div(box.max[a], 8);
        w->n[a] = (int64_t)w->at.max[a] - w->at.min[a] + 1;
    }
    w->pending = true;
    w->filled = false;
}

/* The window ready for a box it was aimed at: false when it cannot be. */
static bool window_ready(window *w)
{
    if (w->pending) {
        w->pending = false;
        size_t total = 1;
        for (int a = 0; a < 3; ++a) {
            if ((uint64_t)w->n[a] > WINDOW_MAX_BLOCKS || total * (size_t)w->n[a] > WINDOW_MAX_BLOCKS)
                return false;
            total *= (size_t)w->n[a];
        }
        if (total > w->cap) {
            window_free(w);
            w->blocks = malloc(total * sizeof *w->blocks);
            if (!w->blocks)
                return false;
            w->cap = total;
        }
        grid_blocks(w->g, w->at, w->blocks);
        w->filled = true;
    }
    return w->filled;
}

/* The blocks a voxel box touches, per axis, relative to the window. */
static void window_span(const window *w, grid_ibox box, int64_t lo[3], int64_t hi[3])
{
    for (int a = 0; a < 3; ++a) {
        lo[a] = floor_div(box.min[a], 8) - w->at.min[a];
        hi[a] = floor_div(box.max[a], 8) - w->at.min[a];
    }
}

/* grid_region_range from the window: the blocks a box touches are the
 * nodes and tiles it overlaps, and those no root tile covers hold the
 * background. */
static void window_range(const window *w, grid_ibox box, float *vmin, float *vmax)
{
    int64_t lo[3], hi[3];
    window_span(w, box, lo, hi);
    float l = INFINITY, h = -INFINITY;
    for (int64_t z = lo[2]; z <= hi[2]; ++z)
        for (int64_t y = lo[1]; y <= hi[1]; ++y) {
            const grid_block *row = w->blocks + (size_t)((z * w->n[1] + y) * w->n[0]);
            for (int64_t x = lo[0]; x <= hi[0]; ++x) {
                l = row[x].min < l ? row[x].min : l;
                h = row[x].max > h ? row[x].max : h;
            }
        }
    *vmin = l;
    *vmax = h;
}

/* Whether the support found so far reaches `enough` on every side (the
 * cell's box is then whole whatever else the region holds: more support
 * only widens it). */
static bool saturated(bool any, const grid_ibox *acc, const grid_ibox *enough)
{
    if (!enough || !any)
        return false;
    for (int a = 0; a < 3; ++a)
        if (acc->min[a] > enough->min[a] || acc->max[a] < enough->max[a])
            return false;
    return true;
}

/* Adds the support of the window's blocks in [lo, hi] (window-relative),
 * skipping those in [skip_lo, skip_hi]; true once saturated. */
static bool blocks_support(const window *w, grid_ibox box, const int64_t lo[3], const int64_t hi[3],
                           const int64_t skip_lo[3], const int64_t skip_hi[3],
                           const grid_ibox *enough, grid_ibox *out, bool *any)
{
    for (int64_t z = lo[2]; z <= hi[2]; ++z)
        for (int64_t y = lo[1]; y <= hi[1]; ++y) {
            const grid_block *row = w->blocks + (size_t)((z * w->n[1] + y) * w->n[0]);
            bool skip_row = y >= skip_lo[1] && y <= skip_hi[1] && z >= skip_lo[2] && z <= skip_hi[2];
            for (int64_t x = lo[0]; x <= hi[0]; ++x) {
                if (row[x].support == GRID_BLOCK_ZERO ||
                    (skip_row && x >= skip_lo[0] && x <= skip_hi[0]))
                    continue;
                const int32_t origin[3] = {(int32_t)((w->at.min[0] + x) * 8),
                                           (int32_t)((w->at.min[1] + y) * 8),
                                           (int32_t)((w->at.min[2] + z) * 8)};
                grid_block_support_add(w->g, &row[x], origin, box, out, any);
                if (saturated(*any, out, enough))
                    return true;
            }
        }
    return false;
}

/* grid_region_support from the window; or, once the support found reaches
 * `enough` (NULL: never), that part of it: the blocks of `core` (inside
 * `box`) first, where it most likely does. */
static bool window_support(const window *w, grid_ibox box, const grid_ibox *core,
                           const grid_ibox *enough, grid_ibox *out)
{
    if (grid_background(w->g) != 0.0f) {
        *out = box;
        return true;
    }
    int64_t lo[3], hi[3], clo[3], chi[3];
    window_span(w, box, lo, hi);
    window_span(w, *core, clo, chi);
    const int64_t none[3] = {1, 1, 1}, nothing[3] = {0, 0, 0};
    bool any = false;
    if (!blocks_support(w, box, clo, chi, none, nothing, enough, out, &any))
        blocks_support(w, box, lo, hi, clo, chi, enough, out, &any);
    return any;
}

/* The range of `g` over `box` (its index space); the background alone when
 * the box misses the active voxels (no need to ask the tree). `w`: its
 * window, when the box lies in it (NULL: ask the tree). */
static void range_over(const grid *g, const grid_ibox *active, bool empty, window *w,
                       grid_ibox box, float *vmin, float *vmax)
{
    bool apart = empty;
    for (int a = 0; a < 3; ++a)
        apart = apart || box.max[a] < active->min[a] || box.min[a] > active->max[a];
    if (apart)
        *vmin = *vmax = grid_background(g);
    else if (w && window_ready(w))
        window_range(w, box, vmin, vmax);
    else
        grid_region_range(g, box, vmin, vmax);
}

/* Where in `box` `g` may be non-zero (grid_region_support), from its window
 * when it has one (and then only up to `enough`, see window_support). */
static bool support_over(const grid *g, bool empty, window *w, grid_ibox box,
                         const grid_ibox *core, const grid_ibox *enough, grid_ibox *out)
{
    if (empty)
        return false;
    if (w && window_ready(w))
        return window_support(w, box, core, enough, out);
    return grid_region_support(g, box, out);
}

static int32_t clamp_index(double v)
{
    return v <= (double)INT32_MIN ? INT32_MIN : v >= (double)INT32_MAX ? INT32_MAX : (int32_t)v;
}

/* A box of voxels in another index space (to = t from): its corners mapped,
 * rounded out by a voxel (trilinear lookups read the next one). */
static grid_ibox map_box(const transform *t, grid_ibox box)
{
    vec3 lo, hi;
    transform_box(t, v3(box.min[0], box.min[1], box.min[2]), v3(box.max[0], box.max[1], box.max[2]),
                  &lo, &hi);
    const double lo3[3] = {lo.x, lo.y, lo.z}, hi3[3] = {hi.x, hi.y, hi.z};
    grid_ibox out;
    for (int a = 0; a < 3; ++a) {
        out.min[a] = clamp_index(floor(lo3[a]) - 1.0);
        out.max[a] = clamp_index(ceil(hi3[a]) + 1.0);
    }
    return out;
}

/* A bound of at least 0: any zero (or NaN) is +0, so that bounds of the
 * same values are the same bits in whatever order they were gathered. */
static float nonnegative(float v) { return v > 0.0f ? v : 0.0f; }

/* The emission grid's upper bound over a box of density voxels: the box's
 * corners mapped into its index space, rounded out by a voxel (its
 * trilinear lookups read the next one). */
static float emission_bound(reader *r, grid_ibox box)
{
    const source *src = r->src;
    const majorant_emission *em = src->em;
    grid_ibox ebox = em->aligned ? box : map_box(&em->eindex_from_index, box);
    float vmin, vmax;
    range_over(em->grid, &src->em_active, src->em_empty, em->aligned ? &r->emis : NULL, ebox,
               &vmin, &vmax);
    return nonnegative(vmax);
}

/* The voxels a span of `n` cells from voxel `first` reads, per axis:
 * first - 1 .. first + n + 1, widened by `pad`. */
static grid_ibox span_box(const source *src, const int64_t first[3], int64_t n)
{
    grid_ibox box;
    for (int a = 0; a < 3; ++a) {
        int64_t v0 = first[a] - 1 - src->pad[a], v1 = first[a] + n + 1 + src->pad[a];
        box.min[a] = (int32_t)(v0 < INT32_MIN ? INT32_MIN : v0);
        box.max[a] = (int32_t)(v1 > INT32_MAX ? INT32_MAX : v1);
    }
    return box;
}

/* The density bounds of a box whose voxels range over [vmin, vmax]. */
static majorant_bounds bounds_of_range(float vmin, float vmax)
{
    majorant_bounds b = {nonnegative(vmax), 0.0f, 0.0f};
    b.min = vmin > 0.0f ? fminf(vmin, b.max) : 0.0f;
    return b;
}

/* The bounds of the trilinear density over `n` cells starting at voxel
 * `first` per axis: over span_box's voxels. */
static majorant_bounds span_bounds(reader *r, const int64_t first[3], int64_t n)
{
    const source *src = r->src;
    grid_ibox box = span_box(src, first, n);
    float vmin, vmax;
    range_over(src->g, &src->active, src->empty, &r->dens, box, &vmin, &vmax);
    majorant_bounds b = bounds_of_range(vmin, vmax);
    if (src->em)
        b.emit = emission_bound(r, box);
    return b;
}

/* The next brick's box: the windows aim at it. */
static void reader_aim(reader *r, const int64_t first[3], int64_t n)
{
    if (r->src->by_queries)
        return;
    grid_ibox box = span_box(r->src, first, n);
    window_aim(&r->dens, box);
    if (r->src->em && r->src->em->aligned)
        window_aim(&r->emis, box);
}

static reader reader_start(const source *src)
{
    reader r = {src, {.g = src->g}, {.g = src->em ? src->em->grid : NULL}, NULL, 0};
    return r;
}

static void reader_end(reader *r)
{
    window_free(&r->dens);
    window_free(&r->emis);
    free(r->scratch);
}

/* Where the emission grid may be non-zero in `region` of density voxels:
 * its non-zero voxels, dilated by its own voxel of reach when its voxels
 * are not the density's, mapped back. */
static bool emission_support(reader *r, grid_ibox region, const grid_ibox *core,
                             const grid_ibox *enough, grid_ibox *enz)
{
    const source *src = r->src;
    const majorant_emission *em = src->em;
    if (em->aligned)
        return support_over(em->grid, src->em_empty, &r->emis, region, core, enough, enz);
    if (!support_over(em->grid, src->em_empty, NULL, map_box(&em->eindex_from_index, region), NULL,
                      NULL, enz))
        return false;
    for (int a = 0; a < 3; ++a) {
        enz->min[a] = clamp_index((double)enz->min[a] - 1.0);
        enz->max[a] = clamp_index((double)enz->max[a] + 1.0);
    }
    *enz = map_box(&src->index_from_eindex, *enz);
    return true;
}

/* The box of a cell (voxels first .. first + cell - 1 per axis, bounds b)
 * where the trilinear density (or an aligned emission grid) may be non-zero:
 * a point p reads voxels floor(p) and floor(p) + 1, moved by up to `pad`, so
 * only points within 1 + pad voxels of a non-zero voxel can be non-zero; one
 * voxel more absorbs rounding, as in span_bounds. */
static majorant_box cell_box(reader *r, const int64_t first[3], int32_t cell, majorant_bounds b)
{
    const source *src = r->src;
    const majorant_box full = {{0, 0, 0},
                               {MAJORANT_BOX_UNITS, MAJORANT_BOX_UNITS, MAJORANT_BOX_UNITS}};
    majorant_box box = full;
    if (!(b.max > 0.0f))
        return full; /* walks take a cell without density whole */
    grid_ibox region = span_box(src, first, cell), nz, enz;
    /* The cell's own voxels, and how far the support must reach for the
     * box below to come out whole: a support past `enough` on every side
     * gives lo < cell / 4 and hi > 3 cell / 4 on every axis, a box that cuts
     * less than a quarter off every side, which the cell does not keep
     * (`worth`). The windows stop there: more support only widens it. */
    grid_ibox core, enough;
    for (int a = 0; a < 3; ++a) {
        int64_t reach = 1 + (int64_t)src->pad[a];
        core.min[a] = (int32_t)first[a];
        core.max[a] = clamp_index((double)(first[a] + cell - 1));
        enough.min[a] = clamp_index((double)(first[a] + reach + 1 + (cell - 1) / 4));
        enough.max[a] = clamp_index((double)(first[a] + 3 * (int64_t)cell / 4 - reach));
    }
    bool any = support_over(src->g, src->empty, &r->dens, region, &core, &enough, &nz);
    if (src->em && emission_support(r, region, &core, &enough, &enz)) {
        for (int a = 0; a < 3; ++a) {
            nz.min[a] = !any || enz.min[a] < nz.min[a] ? enz.min[a] : nz.min[a];
            nz.max[a] = !any || enz.max[a] > nz.max[a] ? enz.max[a] : nz.max[a];
        }
        any = true;
    }
    if (!any) {
        box.lo[0] = box.lo[1] = box.lo[2] = MAJORANT_BOX_UNITS;
        box.hi[0] = box.hi[1] = box.hi[2] = 0;
        return box;
    }
    for (int a = 0; a < 3; ++a) {
        int64_t reach = 1 + (int64_t)src->pad[a];
        int64_t lo = (int64_t)nz.min[a] - reach - 1 - first[a];
        int64_t hi = (int64_t)nz.max[a] + reach + 1 - first[a];
        lo = lo < 0 ? 0 : lo > cell ? cell : lo;
        hi = hi < 0 ? 0 : hi > cell ? cell : hi;
        box.lo[a] = (uint8_t)(lo * MAJORANT_BOX_UNITS / cell); /* floor */
        box.hi[a] = (uint8_t)((hi * MAJORANT_BOX_UNITS + cell - 1) / cell); /* ceil */
    }
    /* A box that cuts less than a quarter of the cell off every side saves
     * fewer lookups than its extra intervals cost: the whole cell. */
    bool worth = false;
    for (int a = 0; a < 3; ++a)
        worth = worth || box.lo[a] > box.hi[a] || box.lo[a] >= MAJORANT_BOX_UNITS / 4 ||
                box.hi[a] <= MAJORANT_BOX_UNITS * 3 / 4;
    return worth ? box : full;
}

/* A brick whose bounds are one value holds that value in every cell (the
 * density's min = max, and no emission or none that could vary). */
static bool uniform_bounds(majorant_bounds b) { return b.max == b.min && b.emit == 0.0f; }

static bool same_bounds(majorant_bounds a, majorant_bounds b)
{
    return a.max == b.max && a.min == b.min && a.emit == b.emit;
}

/* Bricks per axis for cells of `cell` voxels over [l3, h3]; the count in
 * checked arithmetic, saturated above MAJORANT_MAX_BRICKS. */
static uint64_t layout(const double l3[3], const double h3[3], int32_t cell, int64_t first[3],
                       int64_t res[3])
{
    int64_t edge = (int64_t)cell * B;
    uint64_t count = 1;
    for (int a = 0; a < 3; ++a) {
        first[a] = floor_div((int64_t)floor(l3[a]), edge);
        res[a] = floor_div((int64_t)floor(h3[a]), edge) - first[a] + 1;
        count = (uint64_t)res[a] > MAJORANT_MAX_BRICKS || count > MAJORANT_MAX_BRICKS
                    ? (uint64_t)MAJORANT_MAX_BRICKS + 1
                    : count * (uint64_t)res[a];
    }
    return count;
}

/* The cells of one brick that is not uniform, until they are stored (or,
 * built at first use, for good): its occupied ones only (cellmap_pack), so
 * that the build's memory follows them too. */
typedef struct {
    bool differ;            /* its cells differ: the brick keeps them */
    majorant_bounds whole;  /* the union of its cells' bounds */
    majorant_cellmap map;   /* pointing at cells and boxes below */
    size_t n;               /* occupied cells */
    majorant_bounds *cells; /* n of them, then n boxes when boxed */
    majorant_box *boxes;
} brick_cells;

/* The bricks' bounds and the non-uniform bricks' cells are independent: both
 * run on every core, over chunks of bricks handed out in order, each worker
 * reading the tree through its own windows and writing only its bricks. */
typedef struct {
    const source *src;
    majorant_grid *mg;
    size_t count;         /* bricks, or non-uniform bricks for the cells */
    atomic_size_t next;
    const size_t *brick;  /* the cells: the brick of each non-uniform one */
    brick_cells **cells;  /* per brick: its cells once bounded (NULL: not yet) */
    bool with_cells;      /* the bricks' pass bounds the cells too */
    atomic_bool no_memory;
} brick_job;

enum { BRICK_CHUNK = 4 };

static int threads_for(size_t bricks) { return bricks < 64 ? 1 : 0; }

static void brick_xyz(const majorant_grid *mg, size_t i, int32_t b3[3])
{
    b3[0] = (int32_t)(i % (size_t)mg->res[0]);
    b3[1] = (int32_t)(i / (size_t)mg->res[0] % (size_t)mg->res[1]);
    b3[2] = (int32_t)(i / ((size_t)mg->res[0] * (size_t)mg->res[1]));
}

static void brick_first(const majorant_grid *mg, const int32_t b3[3], int64_t first[3])
{
    for (int a = 0; a < 3; ++a)
        first[a] = mg->origin[a] + b3[a] * (int64_t)mg->cell * B;
}

/* The occupied ones of a brick's cells `cells` (and `boxes`, NULL: none)
 * into out->map and its own arrays; false when out of memory. */
static bool cellmap_pack(const majorant_bounds *cells, const majorant_box *boxes, brick_cells *out)
{
    memset(&out->map, 0, sizeof out->map);
    out->n = 0;
    for (int32_t i = 0; i < CELLS_PER_BRICK; ++i)
        if (!majorant_bounds_empty(cells[i])) {
            out->map.occupied[i >> 6] |= UINT64_C(1) << (i & 63);
            ++out->n;
        }
    for (int w = 0, before = 0; w < MAJORANT_MAP_WORDS; ++w) {
        out->map.before[w] = (uint16_t)before;
        before += (int)majorant_popcount(out->map.occupied[w]);
    }
    size_t each = sizeof *out->cells + (boxes ? sizeof *out->boxes : 0);
    out->cells = out->n ? malloc(out->n * each) : NULL;
    out->boxes = out->cells && boxes ? (majorant_box *)(out->cells + out->n) : NULL;
    if (out->n && !out->cells)
        return false;
    for (int32_t i = 0, k = 0; i < CELLS_PER_BRICK; ++i)
        if (majorant_cell_occupied(&out->map, i)) {
            out->cells[k] = cells[i];
            if (boxes)
                out->boxes[k] = boxes[i];
            ++k;
        }
    out->map.cells = out->cells;
    out->map.boxes = out->boxes;
    return true;
}

static void brick_cells_free(brick_cells *bc)
{
    if (bc)
        free(bc->cells);
    free(bc);
}

/* Min and max over blocks [lo, hi] of a run whose blocks are `stride`
 * apart, folded into *l and *h as window_range folds them. */
static void fold_run(const float *mins, const float *maxs, size_t stride, int64_t lo, int64_t hi,
                     float *l, float *h)
{
    for (int64_t k = lo; k <= hi; ++k) {
        float a = mins[(size_t)k * stride], b = maxs[(size_t)k * stride];
        *l = a < *l ? a : *l;
        *h = b > *h ? b : *h;
    }
}

/* The density's range over every cell's span box of brick b3 at once (what
 * range_over gives each, x fastest): a cell's box touches a run of the
 * window's blocks along each axis, the same length for every cell, and its
 * range is their min and max (window_range), so three passes, one per axis,
 * give all B^3 cells from about 3 reads a block and cell instead of 27 a
 * cell. False when the window is not filled or out of memory: span_bounds
 * per cell then. */
static bool brick_ranges(reader *r, const majorant_grid *mg, const int32_t b3[3], float *vmin,
                         float *vmax)
{
    const source *src = r->src;
    window *w = &r->dens;
    if (src->by_queries || src->empty || !window_ready(w))
        return false;
    int64_t lo[3][B], hi[3][B];
    bool apart[3][B];
    for (int32_t c = 0; c < B; ++c) {
        int64_t first[3];
        for (int a = 0; a < 3; ++a)
            first[a] = mg->origin[a] + ((int64_t)b3[a] * B + c) * mg->cell;
        grid_ibox box = span_box(src, first, mg->cell);
        int64_t l3[3], h3[3];
        window_span(w, box, l3, h3);
        for (int a = 0; a < 3; ++a) {
            lo[a][c] = l3[a];
            hi[a][c] = h3[a];
            apart[a][c] = box.max[a] < src->active.min[a] || box.min[a] > src->active.max[a];
        }
    }
    const size_t n0 = (size_t)w->n[0], n1 = (size_t)w->n[1], n2 = (size_t)w->n[2];
    size_t s1 = n2 * n1 * B, s2 = n2 * B * B, need = 2 * (s1 + s2);
    if (need > r->scratch_cap) {
        free(r->scratch);
        r->scratch = malloc(need * sizeof *r->scratch);
        r->scratch_cap = r->scratch ? need : 0;
        if (!r->scratch)
            return false;
    }
    float *min1 = r->scratch, *max1 = min1 + s1, *min2 = max1 + s1, *max2 = min2 + s2;
    /* along x: per row of blocks (z, y), each cell's run */
    for (size_t zy = 0; zy < n2 * n1; ++zy) {
        const grid_block *row = w->blocks + zy * n0;
        for (int32_t c = 0; c < B; ++c) {
            float l = INFINITY, h = -INFINITY;
            for (int64_t x = lo[0][c]; x <= hi[0][c]; ++x) {
                l = row[x].min < l ? row[x].min : l;
                h = row[x].max > h ? row[x].max : h;
            }
            min1[zy * B + (size_t)c] = l;
            max1[zy * B + (size_t)c] = h;
        }
    }
    /* along y, then z */
    for (size_t z = 0; z < n2; ++z)
        for (int32_t cy = 0; cy < B; ++cy)
            for (int32_t cx = 0; cx < B; ++cx) {
                float l = INFINITY, h = -INFINITY;
                size_t at = z * n1 * B + (size_t)cx;
                fold_run(min1 + at, max1 + at, B, lo[1][cy], hi[1][cy], &l, &h);
                min2[(z * B + (size_t)cy) * B + (size_t)cx] = l;
                max2[(z * B + (size_t)cy) * B + (size_t)cx] = h;
            }
    float bg = grid_background(src->g);
    for (int32_t cz = 0, i = 0; cz < B; ++cz)
        for (int32_t cy = 0; cy < B; ++cy)
            for (int32_t cx = 0; cx < B; ++cx, ++i) {
                if (apart[0][cx] || apart[1][cy] || apart[2][cz]) {
                    vmin[i] = vmax[i] = bg;
                    continue;
                }
                float l = INFINITY, h = -INFINITY;
                size_t at = (size_t)cy * B + (size_t)cx;
                fold_run(min2 + at, max2 + at, (size_t)B * B, lo[2][cz], hi[2][cz], &l, &h);
                vmin[i] = l;
                vmax[i] = h;
            }
    return true;
}

/* The cells of brick b3 into `out` (its windows aimed at the brick);
 * differ: whether they differ (the brick must keep them); whole: the union
 * of their bounds, tighter than the brick's own query (when all are equal,
 * every cell's).
 * False when out of memory. */
static bool bound_cells(reader *r, const majorant_grid *mg, const int32_t b3[3], brick_cells *out)
{
    majorant_bounds cells[CELLS_PER_BRICK];
    majorant_box boxes[CELLS_PER_BRICK];
    float vmin[CELLS_PER_BRICK], vmax[CELLS_PER_BRICK];
    bool ranged = !r->src->em && brick_ranges(r, mg, b3, vmin, vmax);
    size_t i = 0;
    bool differ = false;
    for (int32_t z = 0; z < B; ++z)
        for (int32_t y = 0; y < B; ++y)
            for (int32_t x = 0; x < B; ++x, ++i) {
                const int32_t c3[3] = {x, y, z};
                int64_t first[3];
                for (int a = 0; a < 3; ++a)
                    first[a] = mg->origin[a] + ((int64_t)b3[a] * B + c3[a]) * mg->cell;
                cells[i] = ranged ? bounds_of_range(vmin[i], vmax[i])
                                  : span_bounds(r, first, mg->cell);
                if (r->src->boxes)
                    boxes[i] = cell_box(r, first, mg->cell, cells[i]);
                differ = differ || !same_bounds(cells[i], cells[0]);
                if (i == 0)
                    out->whole = cells[0];
                out->whole.max = fmaxf(out->whole.max, cells[i].max);
                out->whole.min = fminf(out->whole.min, cells[i].min);
                out->whole.emit = fmaxf(out->whole.emit, cells[i].emit);
            }
    out->differ = differ;
    out->cells = NULL;
    out->boxes = NULL;
    out->n = 0;
    memset(&out->map, 0, sizeof out->map);
    return !differ || cellmap_pack(cells, r->src->boxes ? boxes : NULL, out);
}

/* The cells of brick i, r's windows aimed at it; NULL when out of memory. */
static brick_cells *cells_of_brick(reader *r, const majorant_grid *mg, size_t i)
{
    int32_t b3[3];
    int64_t first[3];
    brick_xyz(mg, i, b3);
    brick_first(mg, b3, first);
    brick_cells *bc = malloc(sizeof *bc);
    if (!bc)
        return NULL;
    reader_aim(r, first, (int64_t)mg->cell * B);
    if (!bound_cells(r, mg, b3, bc)) {
        free(bc);
        return NULL;
    }
    return bc;
}

/* The cells of brick i into job->cells[i]; false when out of memory. */
static bool brick_cells_of(brick_job *job, reader *r, size_t i)
{
    job->cells[i] = cells_of_brick(r, job->mg, i);
    return job->cells[i] != NULL;
}

static void *bound_bricks_worker(void *ctx)
{
    brick_job *job = ctx;
    majorant_grid *mg = job->mg;
    reader r = reader_start(job->src);
    for (;;) {
        size_t i = atomic_fetch_add(&job->next, BRICK_CHUNK);
        if (i >= job->count)
            break;
        size_t end = i + BRICK_CHUNK < job->count ? i + BRICK_CHUNK : job->count;
        for (; i < end; ++i) {
            int32_t b3[3];
            int64_t first[3];
            brick_xyz(mg, i, b3);
            brick_first(mg, b3, first);
            reader_aim(&r, first, (int64_t)mg->cell * B);
            majorant_brick *br = &mg->bricks[i];
            br->bounds = span_bounds(&r, first, (int64_t)mg->cell * B);
            br->cells = MAJORANT_BRICK_UNIFORM;
            /* the same windows: the brick's cells cost no second walk */
            if (job->with_cells && !uniform_bounds(br->bounds)) {
                brick_cells *bc = malloc(sizeof *bc);
                if (bc && !bound_cells(&r, mg, b3, bc)) {
                    free(bc);
                    bc = NULL;
                }
                job->cells[i] = bc; /* NULL: store_cells tries again */
            }
        }
    }
    reader_end(&r);
    return NULL;
}

/* The bricks' bounds from one visit of the tree (grid_visit_active_blocks)
 * rather than a window of blocks per brick: each leaf or active tile folds
 * into the bricks whose windows (the blocks of the brick's span_box, as
 * reader_aim aims them) it covers, and a window that some block of is not
 * covered also holds the background; a span box apart from the active
 * voxels holds the background alone (range_over). The same bits as
 * span_bounds of every brick (test_media_majorant compares them with a
 * build by queries). The visit runs on up to FOLD_SLABS cores, each over a
 * slab of the blocks into its own bounds, merged after. */
enum { FOLD_SLABS = 4 };
/* The most blocks along the three axes that get a table of their windows. */
#define FOLD_TABLE_MAX ((size_t)1 << 20)

typedef struct {
    const majorant_grid *mg;
    int64_t *wlo[3], *whi[3]; /* per axis, per brick coordinate: its window's blocks */
    int64_t reach;            /* bricks a window reaches back past its own */
    /* Per axis, per block k of `all` (from all_min): the first brick whose
     * window holds it (res when none), and the count that do. NULL: too
     * many blocks; first_window_search then. */
    int32_t *first[3], *count[3];
    int64_t all_min[3], all_n[3];
} brick_windows;

/* One slab's bounds and covered blocks (per brick of its windows). */
typedef struct {
    const brick_windows *w;
    float *vmin, *vmax;
    int64_t *covered;
} brick_fold;

/* The first brick coordinate along axis a whose window ends at block k or
 * later (windows are in order along each axis, and reach at most `reach`
 * bricks before the one holding the block). */
static int32_t first_window_search(const brick_windows *w, int a, int64_t k)
{
    const majorant_grid *mg = w->mg;
    int64_t c = floor_div(k * 8 - mg->origin[a], (int64_t)mg->cell * B) - w->reach;
    if (c < 0)
        c = 0;
    while (c < mg->res[a] && w->whi[a][c] < k)
        ++c;
    return (int32_t)c;
}

/* The bricks along axis a whose windows hold some of blocks lo .. hi:
 * [*b0, *b1); false when none do. */
static bool windows_over(const brick_windows *w, int a, int64_t lo, int64_t hi, int32_t *b0,
                         int32_t *b1)
{
    const majorant_grid *mg = w->mg;
    int64_t k = lo - w->all_min[a];
    if (w->first[a] && lo == hi && k >= 0 && k < w->all_n[a]) {
        *b0 = w->first[a][k];
        *b1 = *b0 + w->count[a][k];
        return *b1 > *b0;
    }
    *b0 = first_window_search(w, a, lo);
    *b1 = *b0;
    while (*b1 < mg->res[a] && w->wlo[a][*b1] <= hi)
        ++*b1;
    return *b1 > *b0;
}

static void fold_into_bricks(void *ctx, const int64_t lo[3], const int64_t hi[3], grid_block b)
{
    brick_fold *f = ctx;
    const brick_windows *w = f->w;
    const majorant_grid *mg = w->mg;
    int32_t b0[3], b1[3];
    for (int a = 0; a < 3; ++a)
        if (!windows_over(w, a, lo[a], hi[a], &b0[a], &b1[a]))
            return;
    for (int32_t z = b0[2]; z < b1[2]; ++z)
        for (int32_t y = b0[1]; y < b1[1]; ++y)
            for (int32_t x = b0[0]; x < b1[0]; ++x) {
                const int32_t c[3] = {x, y, z};
                int64_t n = 1;
                for (int a = 0; a < 3; ++a) {
                    int64_t l = lo[a] > w->wlo[a][c[a]] ? lo[a] : w->wlo[a][c[a]];
                    int64_t h = hi[a] < w->whi[a][c[a]] ? hi[a] : w->whi[a][c[a]];
                    n *= h - l + 1;
                }
                size_t i = ((size_t)z * (size_t)mg->res[1] + (size_t)y) * (size_t)mg->res[0] +
                           (size_t)x;
                f->vmin[i] = b.min < f->vmin[i] ? b.min : f->vmin[i];
                f->vmax[i] = b.max > f->vmax[i] ? b.max : f->vmax[i];
                f->covered[i] += n;
            }
}

typedef struct {
    const grid *g;
    grid_ibox all; /* every window's blocks */
    int axis, slabs;
    brick_fold *fold; /* one per slab */
    atomic_int next;
} fold_job;

/* Slabs of `all` along its longest axis, one at a time. */
static void *fold_worker(void *ctx)
{
    fold_job *job = ctx;
    for (;;) {
        int s = atomic_fetch_add(&job->next, 1);
        if (s >= job->slabs)
            break;
        grid_ibox part = job->all;
        int a = job->axis;
        int64_t first = job->all.min[a], n = (int64_t)job->all.max[a] - first + 1;
        part.min[a] = (int32_t)(first + n * s / job->slabs);
        part.max[a] = (int32_t)(first + n * (s + 1) / job->slabs - 1);
        if (part.max[a] >= part.min[a])
            grid_visit_active_blocks(job->g, part, fold_into_bricks, &job->fold[s]);
    }
    return NULL;
}

/* Every brick's bounds by one visit of the tree; false (nothing set) when
 * it does not apply: emission bounds, a build by queries, windows larger
 * than WINDOW_MAX_BLOCKS (span_bounds asks the tree then), or no memory. */
static bool bound_bricks_by_visit(const source *src, majorant_grid *mg)
{
    if (src->em || src->by_queries)
        return false;
    size_t count = (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2];
    size_t axes = (size_t)mg->res[0] + (size_t)mg->res[1] + (size_t)mg->res[2];
    int cores = hz_core_count(), slabs = cores < FOLD_SLABS ? (cores > 1 ? cores : 1) : FOLD_SLABS;
    brick_windows w = {.mg = mg};
    brick_fold fold[FOLD_SLABS];
    int64_t *ends = malloc(2 * axes * sizeof *ends);
    float *vals = malloc(2 * (size_t)slabs * count * sizeof *vals);
    int64_t *covered = calloc((size_t)slabs * count, sizeof *covered);
    bool ok = ends && vals && covered;
    int64_t edge = (int64_t)mg->cell * B, span[3] = {0, 0, 0};
    grid_ibox all = {{0, 0, 0}, {0, 0, 0}};
    for (int a = 0, at = 0; ok && a < 3; at += mg->res[a], ++a) {
        w.wlo[a] = ends + at;
        w.whi[a] = ends + axes + at;
        for (int32_t c = 0; c < mg->res[a]; ++c) {
            int64_t first[3] = {0, 0, 0};
            first[a] = mg->origin[a] + c * edge;
            grid_ibox box = span_box(src, first, edge);
            w.wlo[a][c] = floor_div(box.min[a], 8);
            w.whi[a][c] = floor_div(box.max[a], 8);
            int64_t n = w.whi[a][c] - w.wlo[a][c] + 1;
            span[a] = n > span[a] ? n : span[a];
        }
        all.min[a] = (int32_t)w.wlo[a][0];
        all.max[a] = (int32_t)w.whi[a][mg->res[a] - 1];
    }
    /* a window starts 1 + pad voxels before its brick, rounded down to a block */
    int32_t pad = src->pad[0] > src->pad[1] ? src->pad[0] : src->pad[1];
    pad = pad > src->pad[2] ? pad : src->pad[2];
    w.reach = 1 + ((int64_t)pad + 9) / edge;
    /* each block's windows, looked up rather than searched for every leaf */
    size_t table = 0;
    for (int a = 0; ok && a < 3; ++a) {
        w.all_min[a] = all.min[a];
        w.all_n[a] = (int64_t)all.max[a] - all.min[a] + 1;
        table += (size_t)w.all_n[a];
    }
    int32_t *lookup = ok && table <= FOLD_TABLE_MAX ? malloc(2 * table * sizeof *lookup) : NULL;
    for (int a = 0, at = 0; lookup && a < 3; at += (int)w.all_n[a], ++a) {
        w.first[a] = lookup + at;
        w.count[a] = lookup + table + at;
        for (int64_t k = 0; k < w.all_n[a]; ++k) {
            int32_t c0 = first_window_search(&w, a, w.all_min[a] + k), c1 = c0;
            while (c1 < mg->res[a] && w.wlo[a][c1] <= w.all_min[a] + k)
                ++c1;
            w.first[a][k] = c0;
            w.count[a][k] = c1 - c0;
        }
    }
    ok = ok && (uint64_t)span[0] * (uint64_t)span[1] <= WINDOW_MAX_BLOCKS &&
         (uint64_t)span[0] * (uint64_t)span[1] * (uint64_t)span[2] <= WINDOW_MAX_BLOCKS;
    if (ok) {
        for (int s = 0; s < slabs; ++s) {
            fold[s] = (brick_fold){&w, vals + 2 * (size_t)s * count,
                                   vals + (2 * (size_t)s + 1) * count, covered + (size_t)s * count};
            for (size_t i = 0; i < count; ++i) {
                fold[s].vmin[i] = INFINITY;
                fold[s].vmax[i] = -INFINITY;
            }
        }
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            axis = (int64_t)all.max[a] - all.min[a] > (int64_t)all.max[axis] - all.min[axis] ? a : axis;
        fold_job job = {.g = src->g, .all = all, .axis = axis, .slabs = slabs, .fold = fold};
        atomic_init(&job.next, 0);
        if (!src->empty)
            hz_parallel_run(count < 64 ? 1 : slabs, fold_worker, &job);
        float bg = grid_background(src->g);
        for (size_t i = 0; i < count; ++i) {
            int32_t b3[3];
            int64_t first[3];
            brick_xyz(mg, i, b3);
            brick_first(mg, b3, first);
            grid_ibox box = span_box(src, first, edge);
            bool apart = src->empty;
            int64_t blocks = 1, seen = 0;
            for (int a = 0; a < 3; ++a) {
                apart = apart || box.max[a] < src->active.min[a] || box.min[a] > src->active.max[a];
                blocks *= w.whi[a][b3[a]] - w.wlo[a][b3[a]] + 1;
            }
            float l = INFINITY, h = -INFINITY;
            for (int s = 0; s < slabs; ++s) {
                l = fold[s].vmin[i] < l ? fold[s].vmin[i] : l;
                h = fold[s].vmax[i] > h ? fold[s].vmax[i] : h;
                seen += fold[s].covered[i];
            }
            if (apart) {
                l = h = bg;
            } else if (seen < blocks) {
                l = bg < l ? bg : l;
                h = bg > h ? bg : h;
            }
            mg->bricks[i].bounds = bounds_of_range(l, h);
            mg->bricks[i].cells = MAJORANT_BRICK_UNIFORM;
        }
    }
    free(ends);
    free(vals);
    free(covered);
    free(lookup);
    return ok;
}

/* Every brick's bounds (and, with_cells, the cells of those not uniform);
 * returns how many bricks are not uniform (their cells may differ). */
static size_t bound_bricks(const source *src, majorant_grid *mg, brick_cells **cells)
{
    size_t count = (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2], varied = 0;
    brick_job job = {.src = src, .mg = mg, .count = count, .cells = cells, .with_cells = cells != NULL};
    atomic_init(&job.next, 0);
    atomic_init(&job.no_memory, false);
    if (cells || !bound_bricks_by_visit(src, mg))
        hz_parallel_run(threads_for(count), bound_bricks_worker, &job);
    for (size_t i = 0; i < count; ++i)
        varied += !uniform_bounds(mg->bricks[i].bounds);
    return varied;
}

static void free_cells(brick_cells **cells, size_t count)
{
    for (size_t i = 0; cells && i < count; ++i)
        brick_cells_free(cells[i]);
    free(cells);
}

/* The most cells a grid stores: memory follows the active voxels. */
static size_t stored_cells_cap(const source *src)
{
    uint64_t per_active = src->empty ? 0 : grid_active_voxel_count(src->g) / 16;
    return per_active > MAJORANT_MIN_STORED_CELLS ? (size_t)per_active : MAJORANT_MIN_STORED_CELLS;
}

/* The cells the bricks would store (a brick whose cells were not bounded
 * counts as all of them). */
static size_t cells_to_store(const majorant_grid *mg, brick_cells *const *cells)
{
    size_t count = (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2], n = 0;
    for (size_t i = 0; i < count; ++i)
        if (!uniform_bounds(mg->bricks[i].bounds))
            n += !cells[i] ? CELLS_PER_BRICK : cells[i]->differ ? cells[i]->n : 0;
    return n;
}

/* The smallest cell whose bricks fit MAJORANT_MAX_BRICKS and whose occupied
 * cells fit stored_cells_cap: lays out out's bricks and bounds them, and the
 * cells of those not uniform into *cells (one per brick, NULL where not).
 * *varied: the bricks whose cells may differ. *lazy (and *cells NULL): the
 * cells of every brick that is not uniform fit the cap whatever they hold,
 * so they wait for their first use (the same cell size: the occupied ones
 * fit too). */
static hz_status choose_layout(const source *src, const double l3[3], const double h3[3],
                               majorant_grid *out, size_t *varied, brick_cells ***cells,
                               bool *lazy, hz_error *err)
{
    *lazy = false;
    for (;;) {
        int64_t first[3], res[3];
        uint64_t count = layout(l3, h3, out->cell, first, res);
        if (count > MAJORANT_MAX_BRICKS && out->cell < MAX_CELL) {
            out->cell *= 2;
            continue;
        }
        for (int a = 0; a < 3; ++a) {
            out->res[a] = (int32_t)res[a];
            out->origin[a] = (int32_t)(first[a] * out->cell * B);
        }
        out->bricks = malloc((size_t)count * sizeof *out->bricks);
        if (out->bricks && !src->by_queries) {
            *varied = bound_bricks(src, out, NULL);
            if (*varied <= stored_cells_cap(src) / CELLS_PER_BRICK) {
                *lazy = true;
                *cells = NULL;
                return HZ_OK;
            }
        }
        *cells = calloc((size_t)count, sizeof **cells);
        if (!out->bricks || !*cells) {
            free(*cells);
            *cells = NULL;
            majorant_grid_free(out);
            return hz_fail(err, "out of memory for a majorant grid of %zu bricks", (size_t)count);
        }
        *varied = bound_bricks(src, out, *cells);
        if (out->cell >= MAX_CELL || cells_to_store(out, *cells) <= stored_cells_cap(src))
            return HZ_OK;
        free_cells(*cells, (size_t)count);
        *cells = NULL;
        free(out->bricks);
        out->bricks = NULL;
        out->cell *= 2;
    }
}

static void *store_cells_worker(void *ctx)
{
    brick_job *job = ctx;
    reader r = reader_start(job->src);
    for (;;) {
        size_t k = atomic_fetch_add(&job->next, 1);
        if (k >= job->count)
            break;
        if (!job->cells[job->brick[k]] && !brick_cells_of(job, &r, job->brick[k]))
            atomic_store(&job->no_memory, true);
    }
    reader_end(&r);
    return NULL;
}

/* Bounds the cells of every brick that is not uniform (`varied` of them)
 * that the bricks' pass could not, then keeps those whose cells differ, in
 * brick order: their maps, and their occupied cells. */
static hz_status store_cells(const source *src, majorant_grid *out, size_t varied,
                             brick_cells **cells, hz_error *err)
{
    size_t count = (size_t)out->res[0] * (size_t)out->res[1] * (size_t)out->res[2];
    brick_job job = {.src = src, .mg = out, .count = varied, .cells = cells};
    atomic_init(&job.next, 0);
    atomic_init(&job.no_memory, false);
    size_t *brick = malloc(varied * sizeof *brick);
    if (brick) {
        for (size_t i = 0, k = 0; i < count; ++i)
            if (!uniform_bounds(out->bricks[i].bounds))
                brick[k++] = i;
        job.brick = brick;
        hz_parallel_run(threads_for(varied), store_cells_worker, &job);
    }
    size_t maps = 0, stored = 0;
    for (size_t k = 0; brick && !atomic_load(&job.no_memory) && k < varied; ++k)
        if (cells[brick[k]]->differ) {
            ++maps;
            stored += cells[brick[k]]->n;
        }
    out->maps = maps ? malloc(maps * sizeof *out->maps) : NULL;
    out->cells = stored ? malloc(stored * sizeof *out->cells) : NULL;
    out->boxes = stored && src->boxes ? malloc(stored * sizeof *out->boxes) : NULL;
    if (!brick || atomic_load(&job.no_memory) || (maps && !out->maps) || (stored && !out->cells) ||
        (stored && src->boxes && !out->boxes)) {
        free(brick);
        return hz_fail(err, "out of memory for a majorant grid of %zu cells",
                       varied * CELLS_PER_BRICK);
    }
    for (size_t k = 0; k < varied; ++k) {
        const brick_cells *bc = cells[brick[k]];
        majorant_brick *br = &out->bricks[brick[k]];
        br->bounds = bc->whole;
        if (!bc->differ)
            continue;
        majorant_cellmap *map = &out->maps[out->stored_bricks];
        *map = bc->map;
        map->cells = out->cells + out->stored_cells;
        map->boxes = out->boxes ? out->boxes + out->stored_cells : NULL;
        memcpy(out->cells + out->stored_cells, bc->cells, bc->n * sizeof *bc->cells);
        if (out->boxes)
            memcpy(out->boxes + out->stored_cells, bc->boxes, bc->n * sizeof *bc->boxes);
        out->stored_cells += bc->n;
        br->cells = (int32_t)out->stored_bricks++;
    }
    free(brick);
    return HZ_OK;
}

/* ---- bricks built at their first use ---- */

/* A brick built at its first use keeps its cells as bound_cells gives them
 * (a brick_cells: its map points at its own cells and boxes). */
struct majorant_lazy {
    source src; /* pointing at pad and em below */
    int32_t pad[3];
    majorant_emission em;
    size_t count;                  /* slots: the bricks left to their first use */
    _Atomic(brick_cells *) *built; /* per slot, NULL until built */
    /* The builds so far (a loser's of a race too) and their time on the
     * threads that made them: majorant_grid_work. */
    atomic_size_t builds;
    atomic_uint_fast64_t build_ns;
};

/* Every brick not uniform gets a slot, in brick order. */
static hz_status lazy_start(const source *src, const int32_t pad[3], const majorant_emission *em,
                            majorant_grid *out, size_t varied, hz_error *err)
{
    struct majorant_lazy *lz = malloc(sizeof *lz);
    _Atomic(brick_cells *) *built = malloc(varied * sizeof *built);
    if (!lz || !built) {
        free(lz);
        free(built);
        majorant_grid_free(out);
        return hz_fail(err, "out of memory for a majorant grid of %zu bricks", varied);
    }
    lz->src = *src;
    memcpy(lz->pad, pad, sizeof lz->pad);
    lz->src.pad = lz->pad;
    if (em) {
        lz->em = *em;
        lz->src.em = &lz->em;
    }
    lz->count = varied;
    lz->built = built;
    atomic_init(&lz->builds, 0);
    atomic_init(&lz->build_ns, 0);
    for (size_t k = 0; k < varied; ++k)
        atomic_init(&built[k], NULL);
    size_t count = (size_t)out->res[0] * (size_t)out->res[1] * (size_t)out->res[2];
    for (size_t i = 0, k = 0; i < count; ++i)
        if (!uniform_bounds(out->bricks[i].bounds))
            out->bricks[i].cells = MAJORANT_BRICK_LAZY - (int32_t)k++;
    out->lazy = lz;
    return HZ_OK;
}

/* Brick i's cells, as a build at loading bounds them; NULL when out of
 * memory. */
static brick_cells *lazy_build(const majorant_grid *mg, size_t i)
{
    reader r = reader_start(&mg->lazy->src);
    brick_cells *bc = cells_of_brick(&r, mg, i);
    reader_end(&r);
    return bc;
}

const majorant_cellmap *majorant_grid_brick(const majorant_grid *mg, size_t index,
                                            majorant_bounds *bounds)
{
    const majorant_brick *br = &mg->bricks[index];
    *bounds = br->bounds;
    if (br->cells >= 0)
        return &mg->maps[br->cells];
    if (br->cells == MAJORANT_BRICK_UNIFORM)
        return NULL;
    _Atomic(brick_cells *) *slot = &mg->lazy->built[MAJORANT_BRICK_LAZY - br->cells];
    brick_cells *lb = atomic_load_explicit(slot, memory_order_acquire);
    if (!lb) {
        uint64_t t0 = hz_clock_ns();
        brick_cells *mine = lazy_build(mg, index);
        atomic_fetch_add_explicit(&mg->lazy->build_ns, hz_clock_ns() - t0, memory_order_relaxed);
        atomic_fetch_add_explicit(&mg->lazy->builds, 1, memory_order_relaxed);
        /* Out of memory: the brick's own bounds, looser but still bounds
         * (this walk then differs from one after a build). */
        if (!mine)
            return NULL;
        brick_cells *none = NULL;
        if (atomic_compare_exchange_strong_explicit(slot, &none, mine, memory_order_acq_rel,
                                                    memory_order_acquire)) {
            lb = mine;
        } else { /* another thread built the same bits first */
            brick_cells_free(mine);
            lb = none;
        }
    }
    *bounds = lb->whole;
    return lb->differ ? &lb->map : NULL;
}

typedef struct {
    const majorant_grid *mg;
    size_t count;
    atomic_size_t next;
} resolve_job;

static void *resolve_worker(void *ctx)
{
    resolve_job *job = ctx;
    for (;;) {
        size_t i = atomic_fetch_add(&job->next, BRICK_CHUNK);
        if (i >= job->count)
            break;
        size_t end = i + BRICK_CHUNK < job->count ? i + BRICK_CHUNK : job->count;
        for (majorant_bounds b; i < end; ++i)
            if (job->mg->bricks[i].cells <= MAJORANT_BRICK_LAZY)
                majorant_grid_brick(job->mg, i, &b);
    }
    return NULL;
}

void majorant_grid_count(const majorant_grid *mg, size_t *bricks, size_t *cells)
{
    size_t count = (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2];
    *bricks = mg->stored_bricks;
    *cells = mg->stored_cells;
    if (!mg->lazy || !mg->bricks)
        return;
    resolve_job job = {.mg = mg, .count = count};
    atomic_init(&job.next, 0);
    hz_parallel_run(threads_for(mg->lazy->count), resolve_worker, &job);
    for (size_t k = 0; k < mg->lazy->count; ++k) {
        const brick_cells *lb = atomic_load(&mg->lazy->built[k]);
        if (lb && lb->differ) {
            ++*bricks;
            *cells += lb->n;
        }
    }
}

majorant_work majorant_grid_work(const majorant_grid *mg)
{
    if (!mg->lazy)
        return (majorant_work){0, 0.0};
    return (majorant_work){atomic_load(&mg->lazy->builds),
                           (double)atomic_load(&mg->lazy->build_ns) * 1e-9};
}

static hz_status build(const grid *g, const majorant_emission *em, vec3 lo, vec3 hi,
                       const int32_t pad[3], bool by_queries, majorant_grid *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    out->cell = 8;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
        return HZ_OK; /* empty: no bricks, every walk misses */
    double l3[3] = {lo.x, lo.y, lo.z}, h3[3] = {hi.x, hi.y, hi.z};
    for (int a = 0; a < 3; ++a) { /* index space is int32: so is the support */
        l3[a] = fmin(fmax(l3[a], (double)INT32_MIN), (double)INT32_MAX);
        h3[a] = fmin(fmax(h3[a], (double)INT32_MIN), (double)INT32_MAX);
    }
    source src = {.g = g, .pad = pad, .em = em, .em_empty = true, .by_queries = by_queries};
    src.empty = !grid_index_bounds(g, &src.active);
    if (em) {
        src.em_empty = !grid_index_bounds(em->grid, &src.em_active);
        if (!em->aligned)
            src.index_from_eindex = transform_inverse(em->eindex_from_index);
    }
    /* Boxes need zero backgrounds (an emission grid's always is). */
    src.boxes = grid_background(g) == 0.0f && (!em || grid_background(em->grid) == 0.0f);
    out->boxed = src.boxes;
    out->brick_bounds_exact = !em || em->aligned;
    size_t varied = 0;
    brick_cells **cells = NULL;
    bool lazy = false;
    if (choose_layout(&src, l3, h3, out, &varied, &cells, &lazy, err) != HZ_OK)
        return HZ_ERROR;
    size_t count = (size_t)out->res[0] * (size_t)out->res[1] * (size_t)out->res[2];
    if (varied == 0) {
        free_cells(cells, count);
        return HZ_OK;
    }
    if (lazy)
        return lazy_start(&src, pad, em, out, varied, err);
    if (!cells)
        cells = calloc(count, sizeof *cells);
    hz_status st = cells ? store_cells(&src, out, varied, cells, err)
                         : hz_fail(err, "out of memory for a majorant grid of %zu cells",
                                   varied * CELLS_PER_BRICK);
    free_cells(cells, count);
    if (st != HZ_OK)
        majorant_grid_free(out);
    return st;
}

hz_status majorant_grid_build(const grid *g, const majorant_emission *em, vec3 lo, vec3 hi,
                              const int32_t pad[3], majorant_grid *out, hz_error *err)
{
    return build(g, em, lo, hi, pad, false, out, err);
}

hz_status majorant_grid_build_by_queries(const grid *g, const majorant_emission *em, vec3 lo,
                                         vec3 hi, const int32_t pad[3], majorant_grid *out,
                                         hz_error *err)
{
    return build(g, em, lo, hi, pad, true, out, err);
}

void majorant_grid_free(majorant_grid *mg)
{
    if (mg->lazy) {
        for (size_t k = 0; k < mg->lazy->count; ++k)
            brick_cells_free(atomic_load(&mg->lazy->built[k]));
        free(mg->lazy->built);
        free(mg->lazy);
        mg->lazy = NULL;
    }
    free(mg->bricks);
    free(mg->maps);
    free(mg->cells);
    free(mg->boxes);
    mg->bricks = NULL;
    mg->maps = NULL;
    mg->cells = NULL;
    mg->boxes = NULL;
    mg->stored_bricks = 0;
    mg->stored_cells = 0;
    mg->res[0] = mg->res[1] = mg->res[2] = 0;
}

size_t majorant_grid_bytes(const majorant_grid *mg)
{
    size_t cell_bytes = sizeof(majorant_bounds) + (mg->boxed ? sizeof(majorant_box) : 0);
    size_t n = (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2] * sizeof *mg->bricks +
               mg->stored_bricks * sizeof *mg->maps + mg->stored_cells * cell_bytes;
    if (mg->lazy) {
        n += sizeof *mg->lazy + mg->lazy->count * sizeof *mg->lazy->built;
        for (size_t k = 0; k < mg->lazy->count; ++k) {
            const brick_cells *lb = atomic_load(&mg->lazy->built[k]);
            n += lb ? sizeof *lb + lb->n * cell_bytes : 0;
        }
    }
    return n;
}


static size_t cell_index(const int32_t c[3]) { return ((size_t)c[2] * B + c[1]) * B + c[0]; }


bool majorant_grid_bounds_at(const majorant_grid *mg, vec3 p, majorant_bounds *out)
{
    const double p3[3] = {p.x, p.y, p.z};
    int32_t b[3], c[3];
    for (int a = 0; a < 3; ++a) {
        double u = floor((p3[a] - mg->origin[a]) / mg->cell);
        if (!(u >= 0.0 && u < (double)mg->res[a] * B))
            return false;
        b[a] = (int32_t)u / B;
        c[a] = (int32_t)u % B;
    }
    const majorant_cellmap *map = majorant_grid_brick(mg, majorant_brick_index(mg, b), out);
    if (!map)
        return true;
    int32_t i = (int32_t)cell_index(c);
    *out = majorant_cell_occupied(map, i) ? map->cells[majorant_cell_slot(map, i)]
                                          : (majorant_bounds){0.0f, 0.0f, 0.0f};
    return true;
}

/* Narrows [*t0, *t1] to where u0 + t du lies in [lo, hi] (one axis of a slab
 * test); false when the ray runs parallel to the slab outside it.
 * Comparisons, not fmax/fmin (library calls on this hot path); NaN cannot
 * occur: du is finite. */
static inline bool slab_clip(double u0, double du, double lo, double hi, double *t0, double *t1)
{
    if (du == 0.0)
        return u0 >= lo && u0 <= hi;
    double ta = (lo - u0) / du, tb = (hi - u0) / du;
    if (ta > tb) {
        double t = ta;
        ta = tb;
        tb = t;
    }
    *t0 = ta > *t0 ? ta : *t0;
    *t1 = tb < *t1 ? tb : *t1;
    return true;
}

/* floor(u) clamped to [0, n - 1], without a libm call (u is finite). */
static inline int32_t clamped_floor(double u, int32_t n)
{
    if (!(u > 0.0))
        return 0;
    if (u >= (double)n)
        return n - 1;
    return (int32_t)u; /* truncation is floor for u > 0 */
}

bool majorant_walk_start(majorant_walk *w, const majorant_grid *mg, vec3 o, vec3 d, double t0,
                         double t1)
{
    w->mg = mg;
    w->done = true;
    w->map = NULL;
    w->clip_cell = NULL;
    w->coarse = false;
    if (!mg->bricks || !(t0 <= t1))
        return false;
    const double o3[3] = {o.x, o.y, o.z}, d3[3] = {d.x, d.y, d.z};
    /* Clip [t0, t1] to the grid's box (slab test), in cell coordinates
     * u = (p - origin) / cell in [0, B res]. */
    for (int a = 0; a < 3; ++a) {
        w->u0[a] = (o3[a] - mg->origin[a]) / mg->cell;
        w->du[a] = d3[a] / mg->cell;
        if (!slab_clip(w->u0[a], w->du[a], 0.0, (double)mg->res[a] * B, &t0, &t1))
            return false;
    }
    if (!(t0 < t1))
        return false;
    /* The brick of t0, clamped: robust against the entry point rounding
     * onto a face. */
    const int32_t stride[3] = {1, B, B * B};
    for (int a = 0; a < 3; ++a) {
        int32_t c = clamped_floor((w->u0[a] + t0 * w->du[a]) / B, mg->res[a]);
        w->brick[a] = c;
        if (w->du[a] > 0.0) {
            w->step[a] = 1;
            w->brick_next[a] = ((c + 1.0) * B - w->u0[a]) / w->du[a];
            w->brick_delta[a] = B / w->du[a];
            w->cell_delta[a] = 1.0 / w->du[a];
        } else if (w->du[a] < 0.0) {
            w->step[a] = -1;
            w->brick_next[a] = ((double)c * B - w->u0[a]) / w->du[a];
            w->brick_delta[a] = -B / w->du[a];
            w->cell_delta[a] = -1.0 / w->du[a];
        } else {
            w->step[a] = 0;
            w->brick_next[a] = w->brick_delta[a] = w->cell_delta[a] = INFINITY;
        }
        w->cell_stride[a] = w->step[a] * stride[a];
    }
    w->t = t0;
    w->t_end = t1;
    w->done = false;
    return true;
}

/* Starts the cell level in a brick that stores its cells, at w->t. */
void majorant_walk_enter_brick(majorant_walk *w, const majorant_cellmap *map, double exit)
{
    w->brick_exit = exit;
    for (int a = 0; a < 3; ++a) {
        double first = (double)w->brick[a] * B;
        int32_t c = clamped_floor(w->u0[a] + w->t * w->du[a] - first, B);
        w->cell_ijk[a] = c;
        w->cell_next[a] = w->step[a] > 0   ? (first + c + 1.0 - w->u0[a]) / w->du[a]
                          : w->step[a] < 0 ? (first + c - w->u0[a]) / w->du[a]
                                           : INFINITY;
    }
    w->map = map;
    w->ci = (int32_t)cell_index(w->cell_ijk);
}

void majorant_walk_clip(majorant_walk *w, size_t k)
{
    const majorant_box *bx = &w->map->boxes[k];
    double t0 = -INFINITY, t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
        double c = (double)w->brick[a] * B + w->cell_ijk[a];
        /* A side on the cell's face is no plane: the DDA ends the cell there
         * (computing the same place another way would leave slivers) */
        double lo = bx->lo[a] == 0 ? -INFINITY : c + bx->lo[a] * (1.0 / MAJORANT_BOX_UNITS);
        double hi = bx->hi[a] == MAJORANT_BOX_UNITS ? INFINITY
                                                    : c + bx->hi[a] * (1.0 / MAJORANT_BOX_UNITS);
        if (bx->lo[a] > bx->hi[a]) { /* nowhere */
            t0 = INFINITY;
            break;
        }
        if (!slab_clip(w->u0[a], w->du[a], lo, hi, &t0, &t1)) {
            t0 = INFINITY;
            break;
        }
    }
    w->clip_cell = &w->map->cells[k];
    w->clip_t0 = t0;
    w->clip_t1 = t1;
}
