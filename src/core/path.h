/* File names as scene files give them. */
#ifndef HAZE_CORE_PATH_H
#define HAZE_CORE_PATH_H

#include "core/error.h"

/* `name` relative to the directory of the file `base` (a scene file that names
 * it). Absolute names, and names from a `base` without a directory (a scene
 * parsed from a string, or a file in the working directory), come back as they
 * are. The result is malloc'ed; NULL when out of memory. */
char *path_relative_to(const char *base, const char *name);
/* A file a scene names at `loc`: relative to the top-level scene file's
 * directory (loc.root; loc.file when unset), as pbrt-v4 resolves every file
 * name, in included files too. */
char *path_of_scene_file(file_loc loc, const char *name);

#endif
