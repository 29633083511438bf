/* A NanoVDB grid read from C through PNanoVDB: a float grid (the density field
 * of a grid medium) or a grid of float 3-vectors (a velocity field). The grid
 * owns its buffer (from vdb_load_typed_grid).
 *
 * Conventions (DESIGN.md, "Scene files"): the value of voxel (i,j,k) sits at the
 * index-space point (i,j,k); between those points the field is trilinear; voxels
 * that are not stored read as the background. So the field's support reaches one
 * voxel beyond the active voxels: index [min - 1, max + 1].
 *
 * Per-sample lookups go through a grid_accessor, a small value each thread keeps
 * on its stack: it caches the last tree path, so nearby lookups are cheap. */
#ifndef HAZE_MEDIA_GRID_H
#define HAZE_MEDIA_GRID_H

#include <stdbool.h>
#include <stdint.h>

#ifndef PNANOVDB_C
#define PNANOVDB_C
#endif
#ifndef PNANOVDB_HDDA
#define PNANOVDB_HDDA
#endif
#include <nanovdb/PNanoVDB.h>

#include "core/error.h"
#include "core/transform.h"
#include "core/vec.h"
#include "media/vdb_load.h"

typedef struct grid grid;

/* Per-thread lookup cache. Initialise with grid_accessor_init before use; valid
 * only with the grid it was initialised for. */
typedef struct {
    pnanovdb_readaccessor_t acc;
} grid_accessor;

/* An inclusive box of voxel coordinates. */
typedef struct {
    int32_t min[3], max[3];
} grid_ibox;

typedef enum { GRID_FLOAT, GRID_VEC3 } grid_value_type;

/* Takes ownership of `buf` on success (and leaves it untouched on failure).
 * Fails unless `buf` holds a valid NanoVDB float or vec3f grid, or when a
 * non-empty grid has no min/max statistics. `name` is used in messages. */
hz_status grid_create_from_buffer(vdb_buffer *buf, const char *name, grid **out, hz_error *err);
/* vdb_load_typed_grid + grid_create_from_buffer: a float grid. */
hz_status grid_load(const char *path, const char *gridname, grid **out, hz_error *err);
/* Several grids of one file at once (one OpenVDB reader process for a .vdb
 * file): outs[i] for req[i], NULL for an optional grid the file lacks. On
 * failure nothing is kept and *failed names the request that failed. */
typedef struct {
    const char *name;
    grid_value_type type;
    bool optional;
} grid_request;
hz_status grid_load_set(const char *path, const grid_request *req, size_t n, grid **outs,
                        size_t *failed, hz_error *err);
/* The same for a vec3 grid (OpenVDB Vec3SGrid, NanoVDB Vec3f). */
hz_status grid_load_vec3(const char *path, const char *gridname, grid **out, hz_error *err);
void grid_destroy(grid *g);

/* A float grid used as a density: checks the values themselves (every active
 * voxel and tile finite and >= 0, the background too, every node's stored
 * range bounding what lies under it) and sets grid_min_value/grid_max_value
 * to the true range. Inactive voxels and tiles are made to hold the
 * background (grid_inactive_folded counts those that did not). The message
 * names the first bad value's place. */
hz_status grid_check_density(grid *g, hz_error *err);
/* The same for a float grid of any sign (a temperature): finite values. */
hz_status grid_check_finite(grid *g, hz_error *err);

grid_value_type grid_type(const grid *g);

void grid_accessor_init(const grid *g, grid_accessor *a);

/* The voxel-to-world map of the grid (world = M index + t), and its inverse. */
transform grid_world_from_index_transform(const grid *g);
vec3 grid_index_from_world(const grid *g, vec3 p_world);
vec3 grid_world_from_index(const grid *g, vec3 p_index);

/* Value stored at voxel (i,j,k) (background if not stored). Float grids. */
float grid_voxel(const grid *g, grid_accessor *a, int32_t i, int32_t j, int32_t k);
/* Trilinear density at an index-space point. Float grids. */
double grid_density_index(const grid *g, grid_accessor *a, vec3 p_index);

/* The same for vec3 grids: the vector stored at voxel (i,j,k), and the
 * trilinear vector field at an index-space point (background outside the
 * support [min - 1, max + 1], as for floats). */
vec3 grid_vec3_voxel(const grid *g, grid_accessor *a, int32_t i, int32_t j, int32_t k);
vec3 grid_vec3_index(const grid *g, grid_accessor *a, vec3 p_index);

/* Bounding box of the active voxels (from the root node). False for an empty grid. */
bool grid_index_bounds(const grid *g, grid_ibox *out);
/* Where the trilinear field can be non-background: [min - 1, max + 1] in index space. */
bool grid_support_bounds(const grid *g, vec3 *lo, vec3 *hi);
/* Largest active value (root statistics), and the background value. A majorant
 * of the whole field is fmax(grid_max_value, grid_background). For vec3 grids
 * these are lengths: of the longest and shortest active vector and of the
 * background vector, so fmax(grid_max_value, grid_background) bounds the length
 * of every trilinear value. */
float grid_max_value(const grid *g);
float grid_min_value(const grid *g);
float grid_background(const grid *g);
uint64_t grid_active_voxel_count(const grid *g);
const char *grid_name(const grid *g);
/* Drops what the value check gathered of each leaf (grid_blocks, and the
 * supports of partial leaves, then read the leaves themselves: the same
 * answers, slower). For tests. */
void grid_drop_leaf_stats(grid *g);
/* Voxels whose inactive value was not the background when the grid was
 * checked (they hold it now). */
uint64_t grid_inactive_folded(const grid *g);
/* Size of the grid's NanoVDB buffer in bytes. */
size_t grid_buffer_bytes(const grid *g);

/* Node statistics and region maxima below: float grids only. */

/* Tree levels, finest first: a leaf spans 8^3 voxels, a lower internal node
 * 128^3, an upper internal node 4096^3. */
typedef enum { GRID_LEAF = 0, GRID_LOWER = 1, GRID_UPPER = 2 } grid_level;

int32_t grid_level_dim(grid_level level);

typedef enum {
    GRID_NODE_CHILD,      /* a node of that level exists; min/max are its statistics */
    GRID_NODE_TILE,       /* a coarser tile covers the region: constant value */
    GRID_NODE_BACKGROUND, /* nothing is stored there: background */
} grid_node_kind;

/* The node of `level` containing voxel (i,j,k). For GRID_NODE_CHILD, min/max come
 * from NanoVDB's node statistics, which cover active values only; for tiles and
 * background they are the constant value. `origin` is the node's first voxel and
 * `dim` its edge length in voxels (grid_level_dim(level)). Note that a trilinear
 * lookup inside a node also reads its neighbours' voxels: a node's max bounds the
 * field only once dilated by one voxel (see grid_region_range). */
typedef struct {
    grid_node_kind kind;
    int32_t origin[3];
    int32_t dim;
    float min, max;
} grid_node;

grid_node grid_node_at(const grid *g, grid_level level, int32_t i, int32_t j, int32_t k);

/* Conservative lower and upper bounds of the values of all voxels in the
 * inclusive index box `box`, from the node statistics and tile values of every
 * node that overlaps it, and the background where no node or tile covers part
 * of it. Inactive voxels inside leaves are assumed to hold the background, as
 * they do in fog volumes (so the lower bound of a leaf that is not fully active
 * includes the background). For the trilinear field over the index-space
 * region [a, b], pass the voxels floor(a) .. floor(b) + 1. */
void grid_region_range(const grid *g, grid_ibox box, float *min, float *max);

/* The smallest index box inside `box` that holds every voxel of `box` whose
 * value may be non-zero: the active voxels of leaves (from their masks:
 * inactive voxels are taken to hold the background, as above) and tiles with
 * a non-zero value. False when there is none (the region is all zero). A
 * grid whose background is not 0 returns `box` itself. */
bool grid_region_support(const grid *g, grid_ibox box, grid_ibox *out);

/* The tree read once per 8^3 block of index space (the place of one leaf):
 * what grid_region_range and grid_region_support would find there, so that
 * many boxes over the same region cost one walk of the tree. */
typedef enum {
    GRID_BLOCK_ZERO,    /* no voxel may be non-zero (no active voxel, a 0 tile, no node) */
    GRID_BLOCK_FULL,    /* every voxel may be (a fully active leaf, a non-zero tile) */
    GRID_BLOCK_PARTIAL, /* a leaf's active voxels (its mask says which) */
} grid_block_support;

typedef struct {
    float min, max;          /* as grid_region_range over the block's voxels */
    uint64_t leaf;           /* GRID_BLOCK_PARTIAL: the leaf's byte offset in the buffer */
    uint32_t stats;          /* its entry in the value check's leaf table (UINT32_MAX: none) */
    grid_block_support support; /* for a zero background (else see grid_region_support) */
} grid_block;

/* The blocks b (voxels 8 b .. 8 b + 7 per axis) of the inclusive box
 * `blocks`, x fastest, into out (one per block). */
void grid_blocks(const grid *g, grid_ibox blocks, grid_block *out);
/* What grid_visit_active_blocks hands over: blocks lo .. hi (inclusive, per axis)
 * of a leaf or tile, and what each of them holds. */
typedef void (*grid_block_fn)(void *ctx, const int64_t lo[3], const int64_t hi[3], grid_block b);
/* Every leaf and tile of the tree that covers blocks of the inclusive box
 * `blocks`, once each, with the blocks of the box it covers (a leaf: one),
 * but the tiles that are inactive in a checked grid: the blocks no call
 * covers read the background. grid_blocks is a fill of the same walk with
 * those tiles too. */
void grid_visit_active_blocks(const grid *g, grid_ibox blocks, grid_block_fn fn, void *ctx);
/* Adds to *acc (*any: whether it holds anything yet) the voxels of `box`
 * where block b (first voxel `origin`) may be non-zero, as
 * grid_region_support would find them. Zero background only. */
void grid_block_support_add(const grid *g, const grid_block *b, const int32_t origin[3],
                            grid_ibox box, grid_ibox *acc, bool *any);

#endif
