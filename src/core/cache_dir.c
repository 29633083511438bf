#define _POSIX_C_SOURCE 200809L
#include "core/cache_dir.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

bool hz_cache_dir(char *out, size_t size)
{
    const char *dir = getenv("HAZE_CACHE_DIR");
    int n;
    if (dir)
        n = snprintf(out, size, "%s", dir);
    else if ((dir = getenv("XDG_CACHE_HOME")) && dir[0] == '/')
        n = snprintf(out, size, "%s/haze", dir);
    else if ((dir = getenv("HOME")) && dir[0] == '/')
        n = snprintf(out, size, "%s/.cache/haze", dir);
    else
        return false;
    return n > 0 && (size_t)n < size && out[0];
}

bool hz_cache_dir_prepare(const char *dir)
{
    char path[4096];
    size_t len = strlen(dir);
    if (len == 0 || len >= sizeof path)
        return false;
    memcpy(path, dir, len + 1);
    for (char *p = path + 1;; ++p) {
        bool end = *p == '\0';
        if (*p == '/' || end) {
            *p = '\0';
            if (mkdir(path, 0700) != 0 && errno != EEXIST)
                return false;
            if (end)
                break;
            *p = '/';
        }
    }
    struct stat st;
    return stat(dir, &st) == 0 && S_ISDIR(st.st_mode);
}
