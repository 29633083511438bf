/* A cache of .vdb grids converted to NanoVDB: the second render of the same
 * .vdb file reads its grids as a .nvdb file, without the reader process that
 * loads OpenVDB and converts (vdb_module.h). Entries are keyed by the file's
 * bytes (a 128-bit hash and the size; the digest cache keeps it while the
 * file is unchanged, core/digest_cache.h), the grid's name and value type, the
 * module ABI and the module file that would convert it (its path, size and
 * modification time: a rebuilt or another module has entries of its own);
 * they are written to a temporary file and renamed, so a reader sees a
 * whole entry or none, and an entry that fails to load is ignored (the grid
 * is converted again and the entry rewritten). Nothing is deleted.
 *
 * Where: core/cache_dir.h's folder. */
#ifndef HAZE_MEDIA_VDB_CACHE_H
#define HAZE_MEDIA_VDB_CACHE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "media/vdb_grid.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    char dir[2048];
    uint64_t key[2]; /* of the file's bytes, size and the converter */
} vdb_cache;

/* The cache for the .vdb file at `path` (file_size bytes): false when there is
 * no cache directory or the file cannot be read (then there is no cache). */
bool vdb_cache_open(vdb_cache *c, const char *path, uint64_t file_size);
/* The entry of grid (name, type): "DIR/KEY.nvdb", or "DIR/KEY.absent" for the
 * marker of an optional grid the file lacks. False when it does not fit. */
bool vdb_cache_entry(const vdb_cache *c, const char *name, vdb_value_type type, bool absent,
                     char *out, size_t size);
/* Creates the directory (and its parents, mode 0700). */
bool vdb_cache_prepare(const vdb_cache *c);

#ifdef __cplusplus
}
#endif

#endif
