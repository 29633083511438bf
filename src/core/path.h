/* File names as scene files give them. */
#ifndef HAZE_CORE_PATH_H
#define HAZE_CORE_PATH_H

/* `name` relative to the directory of the file `base` (a scene file that names
 * it). Absolute names, and names from a `base` without a directory (a scene
 * parsed from a string, or a file in the working directory), come back as they
 * are. The result is malloc'ed; NULL when out of memory. */
char *path_relative_to(const char *base, const char *name);

#endif
