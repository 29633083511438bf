/* Structural validation of a NanoVDB grid buffer from an untrusted file,
 * before anything follows an offset in it. NanoVDB's own validator and every
 * tree walk (lookups, node statistics) follow the tree's node offsets, the
 * root's tile table and each node's child pointers without checking them: a
 * file with its checksum marked absent and one offset changed crashed haze.
 * Kept free of PNanoVDB so the C++ loader can call it too. */
#ifndef HAZE_MEDIA_NVDB_CHECK_H
#define HAZE_MEDIA_NVDB_CHECK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Checks that the grid at the start of `data` (`size` bytes, 8-byte aligned)
 * is a float or vec3f NanoVDB grid whose every offset haze or NanoVDB follows
 * stays inside the buffer: grid size, blind metadata, the tree's first-node
 * offsets and node counts, the root's tile table, and every child pointer of
 * the root, upper and lower nodes (each pointing at a whole node of the right
 * level, no more children per level than the tree declares nodes). Returns 0,
 * or -1 with a reason (no file name) in why. Work is proportional to the
 * number of nodes the buffer can hold. */
int nvdb_check_tree(const void *data, uint64_t size, char *why, size_t why_size);

/* nvdb_check_tree, then NanoVDB's checksum of the grid's header when the
 * grid has one: the CRC-32 of the grid, tree and root records and the root's
 * tiles (the "partial" checksum; a "full" one also covers every node, whose
 * CRC is not checked: a second pass over the whole grid). */
int nvdb_check_grid(const void *data, uint64_t size, char *why, size_t why_size);

/* The root's statistics of a grid that passed nvdb_check_tree: the least
 * and greatest active value of a float grid, the shortest and longest
 * vector's length of a vec3f grid. */
void nvdb_root_range(const void *data, uint64_t size, double *lo, double *hi);

/* What the majorant build reads of each leaf of the tree's leaf array,
 * gathered by nvdb_check_float_values while it reads the leaf anyway, so
 * that the build need not touch the leaves again: the leaf's stored min/max
 * statistics, whether all, some or none of its voxels are active, and
 * where: bit c of xs (ys, zs) is set when an active voxel has x (y, z)
 * = c within the leaf. */
enum { NVDB_LEAF_NONE_ACTIVE, NVDB_LEAF_SOME_ACTIVE, NVDB_LEAF_ALL_ACTIVE };
typedef struct {
    float min, max;
    uint8_t active;
    uint8_t xs, ys, zs;
} nvdb_leaf_stats;

/* A partly active leaf's value mask (slice x: bit 8 y + z), which the
 * build's support queries read many times over: kept in one compact array
 * rather than read scattered over the whole buffer. */
typedef struct {
    uint64_t slice[8];
} nvdb_leaf_mask;

typedef struct {
    nvdb_leaf_stats *leaf; /* one per leaf, in array order (malloc'd); NULL: none */
    /* One per leaf (calloc'd: only the partly active leaves' entries are
     * written, so the others cost no memory); NULL with leaf. */
    nvdb_leaf_mask *mask;
    uint64_t first;        /* the first leaf's byte offset in the buffer */
    uint64_t count;        /* leaves in the array */
    uint64_t stride;       /* bytes per leaf */
} nvdb_leaf_table;

/* For a float grid whose buffer passed nvdb_check_tree (every grid buffer
 * does, in grid_create_from_buffer; this does not walk it again): every
 * active value (voxels, tile values at every level) and the background are
 * finite (and >= 0 when `nonnegative`: a density), and every node's stored
 * min/max bound the values under it (the majorant grid is built from those
 * statistics). Every inactive value (voxel or tile) that is not the
 * background is overwritten with it, and *folded counts the voxels they
 * cover: haze takes inactive voxels to hold the background. Fills the true
 * range of the active values (0, 0 when there are none). When `leaves` is
 * not NULL, fills it (the caller frees leaves->leaf; NULL when it could not
 * be held or on failure). Returns 0, or -1 with the first bad value's place
 * in why. One pass over the values. */
int nvdb_check_float_values(void *data, uint64_t size, int nonnegative, float *vmin,
                            float *vmax, uint64_t *folded, nvdb_leaf_table *leaves, char *why,
                            size_t why_size);

#ifdef __cplusplus
}
#endif

#endif
