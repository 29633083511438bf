/* Reading input files whole: scene files, includes, PLY meshes. */
#ifndef HAZE_CORE_FILE_H
#define HAZE_CORE_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

#include "core/error.h"

/* Size limits of what haze reads whole (after decompression). They stop a
 * device such as /dev/zero, or a gzip bomb, from growing memory until the
 * process is killed; real scenes stay far below them. */
#define FILE_LIMIT_SCENE ((size_t)1 << 30) /* scene text: 1 GiB */
#define FILE_LIMIT_MESH ((size_t)8 << 30)  /* a PLY mesh: 8 GiB */

/* "a directory", "a device", "a FIFO", "a socket" or "not a regular file":
 * what a file of this st_mode is, for messages. */
const char *file_kind_name(mode_t mode);

/* Opens `path` for reading (*fd, blocking reads) and gives its size, only when
 * it is a regular file: a directory, device, FIFO or socket is refused
 * without blocking on it (a FIFO's open would wait for a writer). The message
 * is the reason only. */
hz_status file_open_regular(const char *path, int *fd, off_t *size, hz_error *err);

/* Fails when `path` exists and is not a regular file, told by stat() without
 * opening it (a FIFO's open would wait for a writer; /dev/urandom never
 * ends), for readers that open the file themselves (OpenEXR, OpenVDB). The
 * message names the file: "PATH: cannot read: is a FIFO; haze reads only
 * regular files". A missing file passes: its reader says so. */
hz_status file_check_regular(const char *path, hz_error *err);

/* Whether `path` ends in `suffix` (".exr", ".png"), ignoring case. */
bool file_has_suffix(const char *path, const char *suffix);

/* Reads `path` whole into a malloc'ed buffer (*data, NUL-terminated; *len
 * excludes the NUL). Only regular files are read: a directory, device, FIFO or
 * socket is refused without blocking on it. A name ending in ".gz" is
 * gunzipped (pbrt-v4 reads .pbrt.gz and .ply.gz). More than `limit` bytes is
 * an error. The message is the reason only; callers name the file. */
hz_status file_read_all(const char *path, size_t limit, char **data, size_t *len, hz_error *err);

#endif
