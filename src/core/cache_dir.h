/* haze's cache folder, shared by the caches that keep work between runs
 * (converted .vdb grids, large files' digests): $HAZE_CACHE_DIR (empty: no
 * cache), else $XDG_CACHE_HOME/haze, else $HOME/.cache/haze. */
#ifndef HAZE_CORE_CACHE_DIR_H
#define HAZE_CORE_CACHE_DIR_H

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The folder's path in out[size]; false when there is none (no variable set,
 * HAZE_CACHE_DIR empty) or it does not fit. */
bool hz_cache_dir(char *out, size_t size);
/* Creates the folder `dir` and its parents (mode 0700); true when it is a
 * folder afterwards. */
bool hz_cache_dir_prepare(const char *dir);

#ifdef __cplusplus
}
#endif

#endif
