/* The OpenVDB module: everything that needs libopenvdb (reading .vdb files,
 * converting their grids to NanoVDB, listing them) lives in a shared module,
 * libhaze_openvdb.so, that haze dlopens the first time a .vdb file is read, so a
 * run that reads no .vdb file never maps OpenVDB, TBB, Boost, Imath or Blosc
 * (.nvdb files are read by haze itself, see vdb_load.h).
 *
 * This header holds the C ABI between the two: the entry table the module
 * exports (a const data symbol, HAZE_OPENVDB_ENTRY, found by dlsym and checked
 * for HAZE_OPENVDB_ABI), and vdb_module_get, which finds and loads the module.
 *
 * Where the module is looked for, in order:
 *   1. $HAZE_OPENVDB_MODULE, if set and not empty: that path only;
 *   2. next to the executable (the directory of /proc/self/exe);
 *   3. the build tree's module (an absolute path baked in at compile time, so
 *      test programs in build/tests and the fuzzers find it).
 * If none loads, the error names every path tried and why it failed. */
#ifndef HAZE_MEDIA_VDB_MODULE_H
#define HAZE_MEDIA_VDB_MODULE_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "media/vdb_grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bump when haze_openvdb_api changes in any way. */
#define HAZE_OPENVDB_ABI 2
#define HAZE_OPENVDB_ENTRY "haze_openvdb_entry"

/* The module's entry table. Its functions behave as vdb_load_typed_grid and
 * vdb_list_grids for a file already known to be an OpenVDB file of `file_size`
 * bytes: they never throw, a failure is one line in `err`. Buffers they return
 * are malloc'd (aligned_alloc), or with memfd >= 0 built in that file (sized
 * to the grid, mapped shared: out->mapping), and freed by haze with
 * vdb_buffer_free. */
typedef struct {
    uint32_t abi_version;  /* HAZE_OPENVDB_ABI of the module's build */
    uint32_t struct_size;  /* sizeof(haze_openvdb_api) of the module's build */
    hz_status (*load_grid)(const char *path, uint64_t file_size, const char *gridname,
                           vdb_value_type type, int memfd, vdb_buffer *out, char *err,
                           size_t err_size);
    hz_status (*list_grids)(const char *path, uint64_t file_size, vdb_grid_callback cb,
                            void *user, char *err, size_t err_size);
} haze_openvdb_api;

/* The module's entry table, loading the module on the first call (thread-safe:
 * the search runs once, under pthread_once, and its outcome, the table or the
 * error message, is kept for the life of the process; the module is never
 * unloaded). On failure `*api` is NULL and `err` holds one line naming the
 * paths tried. */
hz_status vdb_module_get(const haze_openvdb_api **api, char *err, size_t err_size);

/* The module's path, found as vdb_module_get finds it but without loading it
 * (the reader process loads it): the first of the places to look that
 * exists. On failure err names every place tried. */
hz_status vdb_module_locate(char *path, size_t path_size, char *err, size_t err_size);

/* Where the reader is: $HAZE_VDB_READER if set, else next to the executable,
 * else the build tree's (baked in at compile time, for the test programs). */
void vdb_reader_path(char *out, size_t size);

#ifdef __cplusplus
}
#endif

#endif
