/* The bridge to OpenVDB/NanoVDB (the one C++ file in src/): reads a grid from a
 * .vdb file (through OpenVDB, converted to NanoVDB with node statistics) or from
 * a .nvdb file, and hands C an owned NanoVDB buffer that PNanoVDB can read.
 * Every failure (missing file, not a VDB file, truncated file, missing grid, wrong
 * value type) becomes one line of text in `err`; no C++ exception escapes. */
#ifndef HAZE_MEDIA_VDB_LOAD_H
#define HAZE_MEDIA_VDB_LOAD_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "media/vdb_grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Loads the grid called `gridname` from `path` (a .vdb or .nvdb file, told apart
 * by its magic number, not its extension). Only grids of value type `type` load;
 * any other value type is an error naming the type. On failure `out` is left
 * empty and `err` (of `err_size` bytes, may be NULL) holds the message. */
hz_status vdb_load_typed_grid(const char *path, const char *gridname, vdb_value_type type,
                              vdb_buffer *out, char *err, size_t err_size);
/* Several grids of one file at once (for a .vdb file, one run of the OpenVDB
 * reader process): outs[i] for req[i]; an optional grid the file lacks leaves
 * outs[i] empty and present[i] 0. On failure every buffer is freed, *failed
 * names the request that failed and err its message. */
hz_status vdb_load_grid_set(const char *path, const vdb_grid_request *req, size_t n,
                            vdb_buffer *outs, int *present, size_t *failed, char *err,
                            size_t err_size);
/* vdb_load_typed_grid of a float grid. */
hz_status vdb_load_grid(const char *path, const char *gridname, vdb_buffer *out, char *err,
                        size_t err_size);

/* A NanoVDB float grid (with min/max statistics) from nx*ny*nz dense values,
 * x fastest: voxel (i, j, k) holds values[(k ny + j) nx + i]; zeros are left
 * inactive (the background is 0). Placed by world = origin + scale * ijk per
 * axis (scale > 0). Values must be finite. */
hz_status vdb_grid_from_dense(const float *values, int nx, int ny, int nz, const double scale[3],
                              const double origin[3], const char *name, vdb_buffer *out,
                              char *err, size_t err_size);

/* Calls `cb` once per grid in the file, in file order. */
hz_status vdb_list_grids(const char *path, vdb_grid_callback cb, void *user, char *err,
                         size_t err_size);

#ifdef __cplusplus
}
#endif

#endif
