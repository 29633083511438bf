#include "core/path.h"

#include <stdlib.h>
#include <string.h>

char *path_relative_to(const char *base, const char *name)
{
    const char *slash = base ? strrchr(base, '/') : NULL;
    size_t dir = (name[0] != '/' && slash) ? (size_t)(slash - base) + 1 : 0;
    size_t n = strlen(name);
    char *path = malloc(dir + n + 1);
    if (!path)
        return NULL;
    memcpy(path, base, dir);
    memcpy(path + dir, name, n + 1);
    return path;
}

char *path_of_scene_file(file_loc loc, const char *name)
{
    return path_relative_to(loc.root ? loc.root : loc.file, name);
}
