/* What the parts of the VDB bridge hand each other: a NanoVDB grid in a
 * buffer C owns, the grids asked for, what `haze info` lists. Its own header,
 * so that the readers (vdb_load.h), the OpenVDB module (vdb_module.h), its
 * reader process (vdb_isolated.h) and the cache (vdb_cache.h) include it
 * rather than each other. */
#ifndef HAZE_MEDIA_VDB_GRID_H
#define HAZE_MEDIA_VDB_GRID_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* One NanoVDB grid (header, tree, nodes, statistics) in one block of memory,
 * released with vdb_buffer_free. `size` is the grid's size in bytes. `data`
 * is 8-byte aligned (PNanoVDB reads 64-bit words; NanoVDB's C++ types want
 * 32, so C++ code copies fields out rather than cast the buffer). Either
 * malloc'd (`mapping` NULL) or inside a private mapping of a .nvdb file
 * (`mapping`, `mapping_size`: the pages mmap gave, copied only where
 * written). */
typedef struct {
    void *data;
    size_t size;
    void *mapping;
    size_t mapping_size;
} vdb_buffer;

void vdb_buffer_free(vdb_buffer *b);

/* The value types haze reads: float (density) and 3-vectors of floats (velocity;
 * OpenVDB's Vec3SGrid, NanoVDB's Vec3f). */
typedef enum { VDB_FLOAT, VDB_VEC3 } vdb_value_type;

/* One grid of a set read at once (vdb_load_grid_set): an optional grid the
 * file lacks is no error. */
typedef struct {
    const char *name;
    vdb_value_type type;
    int optional;
} vdb_grid_request;
/* At most this many grids in one set (a medium needs three). */
enum { VDB_MAX_GRID_REQUESTS = 8 };

/* True for the message of a file that holds no grid of the name asked for,
 * from either reader (vdb_load.cpp's of .nvdb files, the OpenVDB module). */
int vdb_error_is_missing_grid(const char *message);

/* What `haze info` shows about one grid. Strings are valid during the callback only.
 * index_min/max is the active voxel bounding box (inclusive); world_min/max bounds
 * the world-space cells of those voxels ([min - 1/2, max + 1/2] in index space,
 * mapped through the grid's transform). min/max_value are over active values:
 * the values themselves for scalar grids, vector lengths for vector grids, absent
 * (has_range = 0) for other types. */
typedef struct {
    const char *name;
    const char *type; /* OpenVDB's value type name: "float", "vec3s", ... */
    uint64_t active_voxels;
    int32_t index_min[3], index_max[3];
    double world_min[3], world_max[3];
    double voxel_size[3];
    int has_range;
    double min_value, max_value;
} vdb_grid_info;

typedef void (*vdb_grid_callback)(const vdb_grid_info *info, void *user);

#ifdef __cplusplus
}
#endif

#endif
