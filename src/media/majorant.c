#include "media/majorant.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/parallel.h"

#define B MAJORANT_BRICK
#define CELLS_PER_BRICK (B * B * B)
/* A brick of the largest cells is 2^30 voxels: at most 5 per axis of the
 * int32 index space, so the layout always fits. */
#define MAX_CELL (1 << 27)

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
} source;

/* The range of `g` over `box` (its index space); the background alone when
 * the box misses the active voxels (no need to ask the tree). */
static void range_over(const grid *g, const grid_ibox *active, bool empty, grid_ibox box,
                       float *vmin, float *vmax)
{
    bool apart = empty;
    for (int a = 0; a < 3; ++a)
        apart = apart || box.max[a] < active->min[a] || box.min[a] > active->max[a];
    if (apart)
        *vmin = *vmax = grid_background(g);
    else
        grid_region_range(g, box, vmin, vmax);
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

/* The emission grid's upper bound over a box of density voxels: the box's
 * corners mapped into its index space, rounded out by a voxel (its
 * trilinear lookups read the next one). */
static float emission_bound(const source *src, grid_ibox box)
{
    const majorant_emission *em = src->em;
    grid_ibox ebox = em->aligned ? box : map_box(&em->eindex_from_index, box);
    float vmin, vmax;
    range_over(em->grid, &src->em_active, src->em_empty, ebox, &vmin, &vmax);
    return fmaxf(vmax, 0.0f);
}

/* The bounds of the trilinear density over `n` cells starting at voxel
 * `first` per axis: voxels first - 1 .. first + n + 1, widened by `pad`. */
static majorant_bounds span_bounds(const source *src, const int64_t first[3], int64_t n)
{
    grid_ibox box;
    for (int a = 0; a < 3; ++a) {
        int64_t v0 = first[a] - 1 - src->pad[a], v1 = first[a] + n + 1 + src->pad[a];
        box.min[a] = (int32_t)(v0 < INT32_MIN ? INT32_MIN : v0);
        box.max[a] = (int32_t)(v1 > INT32_MAX ? INT32_MAX : v1);
    }
    float vmin, vmax;
    range_over(src->g, &src->active, src->empty, box, &vmin, &vmax);
    majorant_bounds b = {fmaxf(vmax, 0.0f), 0.0f, 0.0f};
    b.min = fminf(fmaxf(vmin, 0.0f), b.max);
    if (src->em)
        b.emit = emission_bound(src, box);
    return b;
}

/* The box of a cell (voxels first .. first + cell - 1 per axis, bounds b)
 * where the trilinear density (or an aligned emission grid) may be non-zero:
 * a point p reads voxels floor(p) and floor(p) + 1, moved by up to `pad`, so
 * only points within 1 + pad voxels of a non-zero voxel can be non-zero; one
 * voxel more absorbs rounding, as in span_bounds. */
static majorant_box cell_box(const source *src, const int64_t first[3], int32_t cell,
                             majorant_bounds b)
{
    const majorant_box full = {{0, 0, 0},
                               {MAJORANT_BOX_UNITS, MAJORANT_BOX_UNITS, MAJORANT_BOX_UNITS}};
    majorant_box box = full;
    if (!(b.max > 0.0f))
        return full; /* walks take a cell without density whole */
    grid_ibox region, nz;
    int64_t reach[3];
    for (int a = 0; a < 3; ++a) {
        reach[a] = 1 + (int64_t)src->pad[a];
        int64_t v0 = first[a] - reach[a], v1 = first[a] + cell + reach[a];
        region.min[a] = (int32_t)(v0 < INT32_MIN ? INT32_MIN : v0);
        region.max[a] = (int32_t)(v1 > INT32_MAX ? INT32_MAX : v1);
    }
    bool any = !src->empty && grid_region_support(src->g, region, &nz);
    /* and the emission grid, in its index space: its non-zero voxels,
     * dilated by its own voxel of reach, mapped back */
    const majorant_emission *em = src->em;
    grid_ibox enz;
    if (em && !src->em_empty &&
        grid_region_support(em->grid, em->aligned ? region : map_box(&em->eindex_from_index, region),
                            &enz)) {
        if (!em->aligned) {
            for (int a = 0; a < 3; ++a) {
                enz.min[a] = clamp_index((double)enz.min[a] - 1.0);
                enz.max[a] = clamp_index((double)enz.max[a] + 1.0);
            }
            enz = map_box(&src->index_from_eindex, enz);
        }
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
        int64_t lo = (int64_t)nz.min[a] - reach[a] - 1 - first[a];
        int64_t hi = (int64_t)nz.max[a] + reach[a] + 1 - first[a];
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

/* The bricks' bounds and the non-uniform bricks' cells are independent
 * queries of the grid (a production grid's million cells took half a
 * second on one core): both run on every core, over chunks of bricks
 * handed out in order. */
typedef struct {
    const source *src;
    majorant_grid *mg;
    size_t count;         /* bricks, or non-uniform bricks for the cells */
    atomic_size_t next;
    const size_t *brick;  /* the cells: the brick of each non-uniform one */
    bool *differ;         /* ... whether its cells differ */
    majorant_bounds *first; /* ... its first cell's bounds */
} brick_job;

enum { BRICK_CHUNK = 4 };

static int threads_for(size_t bricks) { return bricks < 64 ? 1 : 0; }

static void brick_xyz(const majorant_grid *mg, size_t i, int32_t b3[3])
{
    b3[0] = (int32_t)(i % (size_t)mg->res[0]);
    b3[1] = (int32_t)(i / (size_t)mg->res[0] % (size_t)mg->res[1]);
    b3[2] = (int32_t)(i / ((size_t)mg->res[0] * (size_t)mg->res[1]));
}

static void *bound_bricks_worker(void *ctx)
{
    brick_job *job = ctx;
    const majorant_grid *mg = job->mg;
    int64_t edge = (int64_t)mg->cell * B;
    for (;;) {
        size_t i = atomic_fetch_add(&job->next, BRICK_CHUNK);
        if (i >= job->count)
            return NULL;
        size_t end = i + BRICK_CHUNK < job->count ? i + BRICK_CHUNK : job->count;
        for (; i < end; ++i) {
            int32_t b3[3];
            brick_xyz(mg, i, b3);
            int64_t first[3];
            for (int a = 0; a < 3; ++a)
                first[a] = mg->origin[a] + b3[a] * edge;
            majorant_brick *br = &job->mg->bricks[i];
            br->bounds = span_bounds(job->src, first, edge);
            br->cells = -1;
        }
    }
}

/* Every brick's bounds; returns how many bricks are not uniform (their
 * cells may differ). */
static size_t bound_bricks(const source *src, majorant_grid *mg)
{
    size_t count = (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2], varied = 0;
    brick_job job = {.src = src, .mg = mg, .count = count};
    atomic_init(&job.next, 0);
    hz_parallel_run(threads_for(count), bound_bricks_worker, &job);
    for (size_t i = 0; i < count; ++i)
        varied += !uniform_bounds(mg->bricks[i].bounds);
    return varied;
}

/* The cells of brick (x, y, z) into `cells`; true when they differ (the
 * brick must keep them), false when all are equal (their bounds are then the
 * brick's, tighter than the brick's own query). */
static bool bound_cells(const source *src, majorant_grid *mg, const int32_t brick[3],
                        majorant_bounds *cells, majorant_box *boxes, majorant_bounds *uniform)
{
    size_t i = 0;
    bool differ = false;
    for (int32_t z = 0; z < B; ++z)
        for (int32_t y = 0; y < B; ++y)
            for (int32_t x = 0; x < B; ++x, ++i) {
                const int32_t c3[3] = {x, y, z};
                int64_t first[3];
                for (int a = 0; a < 3; ++a)
                    first[a] = mg->origin[a] + ((int64_t)brick[a] * B + c3[a]) * mg->cell;
                cells[i] = span_bounds(src, first, mg->cell);
                if (boxes)
                    boxes[i] = cell_box(src, first, mg->cell, cells[i]);
                differ = differ || !same_bounds(cells[i], cells[0]);
            }
    *uniform = cells[0];
    return differ;
}

/* The smallest cell whose bricks fit MAJORANT_MAX_BRICKS and whose varied
 * bricks fit MAJORANT_MAX_STORED_CELLS: lays out out's bricks and bounds
 * them. *varied: the bricks whose cells differ. */
static hz_status choose_layout(const source *src, const double l3[3], const double h3[3],
                               majorant_grid *out, size_t *varied, hz_error *err)
{
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
        if (!out->bricks) {
            majorant_grid_free(out);
            return hz_fail(err, "out of memory for a majorant grid of %zu bricks", (size_t)count);
        }
        *varied = bound_bricks(src, out);
        if (*varied <= MAJORANT_MAX_STORED_CELLS / CELLS_PER_BRICK || out->cell >= MAX_CELL)
            return HZ_OK;
        free(out->bricks);
        out->bricks = NULL;
        out->cell *= 2;
    }
}

static void *store_cells_worker(void *ctx)
{
    brick_job *job = ctx;
    majorant_grid *mg = job->mg;
    for (;;) {
        size_t k = atomic_fetch_add(&job->next, 1);
        if (k >= job->count)
            return NULL;
        int32_t b3[3];
        brick_xyz(mg, job->brick[k], b3);
        size_t at = k * CELLS_PER_BRICK;
        job->differ[k] = bound_cells(job->src, mg, b3, mg->cells + at,
                                     mg->boxes ? mg->boxes + at : NULL, &job->first[k]);
    }
}

/* Bounds the cells of every brick that is not uniform (`varied` of them),
 * keeping those whose cells differ, in brick order: each brick's cells
 * land in its own slot, then the kept ones move down over the dropped. */
static hz_status store_cells(const source *src, majorant_grid *out, size_t varied, hz_error *err)
{
    size_t count = (size_t)out->res[0] * (size_t)out->res[1] * (size_t)out->res[2];
    brick_job job = {.src = src, .mg = out, .count = varied};
    atomic_init(&job.next, 0);
    size_t *brick = malloc(varied * sizeof *brick);
    job.differ = malloc(varied * sizeof *job.differ);
    job.first = malloc(varied * sizeof *job.first);
    if (!brick || !job.differ || !job.first) {
        free(brick);
        free(job.differ);
        free(job.first);
        return hz_fail(err, "out of memory for a majorant grid of %zu cells",
                       varied * CELLS_PER_BRICK);
    }
    for (size_t i = 0, k = 0; i < count; ++i)
        if (!uniform_bounds(out->bricks[i].bounds))
            brick[k++] = i;
    job.brick = brick;
    hz_parallel_run(threads_for(varied), store_cells_worker, &job);
    for (size_t k = 0; k < varied; ++k) {
        majorant_brick *br = &out->bricks[brick[k]];
        br->bounds = job.first[k];
        if (!job.differ[k])
            continue;
        size_t from = k * CELLS_PER_BRICK, to = out->stored_bricks * CELLS_PER_BRICK;
        if (from != to) {
            memmove(out->cells + to, out->cells + from, CELLS_PER_BRICK * sizeof *out->cells);
            if (out->boxes)
                memmove(out->boxes + to, out->boxes + from, CELLS_PER_BRICK * sizeof *out->boxes);
        }
        br->cells = (int32_t)out->stored_bricks++;
    }
    free(brick);
    free(job.differ);
    free(job.first);
    return HZ_OK;
}

/* p shrunk to `bytes` (freed for 0); p itself when realloc fails. */
static void *shrink_to(void *p, size_t bytes)
{
    void *kept = bytes ? realloc(p, bytes) : NULL;
    if (kept || !bytes) {
        if (!kept)
            free(p);
        return kept;
    }
    return p;
}

hz_status majorant_grid_build(const grid *g, const majorant_emission *em, vec3 lo, vec3 hi,
                              const int32_t pad[3], majorant_grid *out, hz_error *err)
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
    source src = {.g = g, .pad = pad, .em = em, .em_empty = true};
    src.empty = !grid_index_bounds(g, &src.active);
    if (em) {
        src.em_empty = !grid_index_bounds(em->grid, &src.em_active);
        if (!em->aligned)
            src.index_from_eindex = transform_inverse(em->eindex_from_index);
    }
    size_t varied = 0;
    if (choose_layout(&src, l3, h3, out, &varied, err) != HZ_OK)
        return HZ_ERROR;
    if (varied == 0)
        return HZ_OK;
    out->cells = malloc(varied * CELLS_PER_BRICK * sizeof *out->cells);
    /* Boxes need zero backgrounds (an emission grid's always is). */
    bool boxes = grid_background(g) == 0.0f && (!em || grid_background(em->grid) == 0.0f);
    if (boxes)
        out->boxes = malloc(varied * CELLS_PER_BRICK * sizeof *out->boxes);
    if (!out->cells || (boxes && !out->boxes)) {
        majorant_grid_free(out);
        return hz_fail(err, "out of memory for a majorant grid of %zu cells",
                       varied * CELLS_PER_BRICK);
    }
    if (store_cells(&src, out, varied, err) != HZ_OK) {
        majorant_grid_free(out);
        return HZ_ERROR;
    }
    if (out->stored_bricks < varied) { /* give back what uniform bricks did not keep */
        size_t kept = out->stored_bricks * CELLS_PER_BRICK;
        out->cells = shrink_to(out->cells, kept * sizeof *out->cells);
        if (out->boxes)
            out->boxes = shrink_to(out->boxes, kept * sizeof *out->boxes);
    }
    return HZ_OK;
}

void majorant_grid_free(majorant_grid *mg)
{
    free(mg->bricks);
    free(mg->cells);
    free(mg->boxes);
    mg->bricks = NULL;
    mg->cells = NULL;
    mg->boxes = NULL;
    mg->stored_bricks = 0;
    mg->res[0] = mg->res[1] = mg->res[2] = 0;
}

size_t majorant_grid_bytes(const majorant_grid *mg)
{
    return (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2] * sizeof *mg->bricks +
           mg->stored_bricks * CELLS_PER_BRICK *
               (sizeof *mg->cells + (mg->boxes ? sizeof *mg->boxes : 0));
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
    const majorant_brick *br = &mg->bricks[majorant_brick_index(mg, b)];
    *out = br->cells < 0 ? br->bounds
                         : mg->cells[(size_t)br->cells * CELLS_PER_BRICK + cell_index(c)];
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
    w->cell = NULL;
    w->clip_cell = NULL;
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
    const ptrdiff_t stride[3] = {1, B, B * B};
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
void majorant_walk_enter_brick(majorant_walk *w, const majorant_brick *br, double exit)
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
    w->cell = w->mg->cells + (size_t)br->cells * CELLS_PER_BRICK + cell_index(w->cell_ijk);
}

void majorant_walk_clip(majorant_walk *w)
{
    const majorant_box *bx = &w->mg->boxes[w->cell - w->mg->cells];
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
    w->clip_cell = w->cell;
    w->clip_t0 = t0;
    w->clip_t1 = t1;
}
