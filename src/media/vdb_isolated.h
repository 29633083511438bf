/* Reading the grids of a .vdb file in a process of its own (vdb_isolated.c):
 * the renderer's side, which vdb_load.cpp calls, and the reader's, which
 * haze_vdb_reader (src/vdb_reader.c) runs. */
#ifndef HAZE_MEDIA_VDB_ISOLATED_H
#define HAZE_MEDIA_VDB_ISOLATED_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "media/vdb_grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads a grid of a .vdb file with the module in a separate process, the
 * reader (haze_vdb_reader, src/vdb_reader.c), which builds the NanoVDB
 * grid in a memory file both map (or, where there is none, sends it back
 * through the pipe its replies take): whatever OpenVDB and its libraries do
 * when memory runs out or a file is hostile (Blosc writes through a failed
 * allocation), the renderer survives and reports one line, and OpenVDB's
 * working memory is the reader's. The reader is a fresh program (started with
 * posix_spawn), so the renderer's threads (Embree's, MPI's) and their locks
 * do not follow it. */
hz_status vdb_module_load_grid_isolated(const char *path, uint64_t file_size,
                                        const vdb_grid_request *req, size_t n, vdb_buffer *outs,
                                        int *present, size_t *failed, char *err,
                                        size_t err_size);

/* Where the reader finds request i's memory file (the renderer passes one
 * per request where it can: a third digit 1 in the request's type). */
enum { VDB_READER_MEMFD = 10 };

/* The reader's side: loads each requested grid with the module at `module`
 * (built into memory file memfds[i] when that is >= 0) and writes one reply
 * per request (a header, then the buffer or the message; no buffer when it
 * is in the memory file) to fd, stopping after the first failure. Returns
 * the exit status. */
int vdb_reader_run(const char *module, const char *path, uint64_t file_size,
                   const vdb_grid_request *req, size_t n, const int *memfds, int fd);

#ifdef __cplusplus
}
#endif

#endif
