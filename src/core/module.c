/* Finding and opening haze's modules (see module.h). */
#define _POSIX_C_SOURCE 200809L
#include "core/module.h"

#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void hz_module_message(char *out, size_t size, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out, size, fmt, ap);
    va_end(ap);
}

/* The module file next to the executable, or "" if /proc/self/exe is unreadable. */
static void next_to_executable(const char *file_name, char *out, size_t size)
{
    char exe[HZ_MODULE_PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    out[0] = '\0';
    if (n <= 0)
        return;
    exe[n] = '\0';
    char *slash = strrchr(exe, '/');
    if (!slash)
        return;
    slash[1] = '\0';
    int len = snprintf(out, size, "%s%s", exe, file_name);
    if (len < 0 || (size_t)len >= size)
        out[0] = '\0';
}

int hz_module_candidates(const hz_module_spec *spec,
                         char out[HZ_MODULE_CANDIDATES][HZ_MODULE_PATH_MAX])
{
    int count = 0;
    const char *env = getenv(spec->env);
    if (env && env[0]) {
        hz_module_message(out[count++], HZ_MODULE_PATH_MAX, "%s", env);
    } else {
        next_to_executable(spec->file_name, out[count], HZ_MODULE_PATH_MAX);
        if (out[count][0])
            count++;
        const char *built = spec->build_path;
        if (built[0] && (count == 0 || strcmp(out[0], built) != 0))
            hz_module_message(out[count++], HZ_MODULE_PATH_MAX, "%s", built);
    }
    return count;
}

/* The table's first two fields. */
typedef struct {
    uint32_t abi_version, struct_size;
} table_head;

/* dlopens `path` and checks its entry table; on failure returns NULL with the
 * reason (starting with the path) in `why`. */
static const void *try_load(const hz_module_spec *spec, const char *path, char *why,
                            size_t why_size)
{
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        const char *e = dlerror();
        hz_module_message(why, why_size, "%s", e ? e : path);
        return NULL;
    }
    /* The entry table is a data symbol: no object-to-function pointer cast. */
    const table_head *head = dlsym(handle, spec->entry);
    if (!head) {
        hz_module_message(why, why_size, "%s: no %s table (not a haze %s module)", path,
                          spec->entry, spec->kind);
        dlclose(handle);
        return NULL;
    }
    if (head->abi_version != spec->abi_version || head->struct_size != spec->struct_size) {
        hz_module_message(why, why_size,
                          "%s: module ABI version %u (table of %u bytes), this haze needs "
                          "version %u (%u bytes): a module from another haze build",
                          path, (unsigned)head->abi_version, (unsigned)head->struct_size,
                          (unsigned)spec->abi_version, (unsigned)spec->struct_size);
        dlclose(handle);
        return NULL;
    }
    return head;
}

const void *hz_module_open(const hz_module_spec *spec, char *path, size_t path_size,
                           char *reasons, size_t reasons_size, int *tried)
{
    char candidates[HZ_MODULE_CANDIDATES][HZ_MODULE_PATH_MAX];
    int count = hz_module_candidates(spec, candidates);
    *tried = count;
    if (reasons_size)
        reasons[0] = '\0';
    for (int i = 0; i < count; ++i) {
        char why[HZ_MODULE_PATH_MAX + 256];
        const void *table = try_load(spec, candidates[i], why, sizeof why);
        if (table) {
            hz_module_message(path, path_size, "%s", candidates[i]);
            return table;
        }
        size_t used = strlen(reasons);
        if (used < reasons_size)
            hz_module_message(reasons + used, reasons_size - used, "%s%s", i ? "; " : "",
                              why);
    }
    return NULL;
}
