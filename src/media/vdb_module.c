/* Finding and loading the OpenVDB module (see vdb_module.h). */
#define _POSIX_C_SOURCE 200809L
#include "media/vdb_module.h"

#include "core/module.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Set by the build: the module's file name and its absolute path in the build tree. */
#ifndef HAZE_OPENVDB_MODULE_NAME
#define HAZE_OPENVDB_MODULE_NAME "libhaze_openvdb.so"
#endif
#ifndef HAZE_OPENVDB_MODULE_BUILD_PATH
#define HAZE_OPENVDB_MODULE_BUILD_PATH ""
#endif
#ifndef HAZE_VDB_READER_NAME
#define HAZE_VDB_READER_NAME "haze_vdb_reader"
#endif
#ifndef HAZE_VDB_READER_BUILD_PATH
#define HAZE_VDB_READER_BUILD_PATH ""
#endif

#define MODULE_PATH_MAX HZ_MODULE_PATH_MAX

static const hz_module_spec vdb_module_spec = {
    "HAZE_OPENVDB_MODULE", HAZE_OPENVDB_MODULE_NAME, HAZE_OPENVDB_MODULE_BUILD_PATH,
    HAZE_OPENVDB_ENTRY,    HAZE_OPENVDB_ABI,         sizeof(haze_openvdb_api),
    "OpenVDB"};

/* The outcome of the one search for the module: the only state in this file.
 * It is written once, by module_search under pthread_once, and only read after
 * that (pthread_once orders the write before every return from it). The module
 * stays loaded until the process exits. */
typedef struct {
    const haze_openvdb_api *api; /* NULL if the search failed */
    char path[MODULE_PATH_MAX];  /* the module loaded */
    char error[3 * MODULE_PATH_MAX];
} module_state;

static pthread_once_t module_once = PTHREAD_ONCE_INIT;
static module_state the_module;

static void not_found(char *out, size_t size, int count, const char *reasons)
{
    hz_module_message(out, size,
                      "cannot load the OpenVDB module that reading .vdb files needs (tried "
                      "%s); convert the file to .nvdb, or set HAZE_OPENVDB_MODULE to the "
                      "module's path",
                      count ? reasons : "no path");
}

static void module_search(void)
{
    char reasons[2 * MODULE_PATH_MAX + 8];
    int count = 0;
    the_module.api = hz_module_open(&vdb_module_spec, the_module.path, sizeof the_module.path,
                                    reasons, sizeof reasons, &count);
    if (!the_module.api)
        not_found(the_module.error, sizeof the_module.error, count, reasons);
}

hz_status vdb_module_locate(char *path, size_t path_size, char *err, size_t err_size)
{
    char candidates[HZ_MODULE_CANDIDATES][MODULE_PATH_MAX];
    int count = hz_module_candidates(&vdb_module_spec, candidates);
    char reasons[2 * MODULE_PATH_MAX + 8] = "";
    for (int i = 0; i < count; ++i) {
        if (access(candidates[i], R_OK) == 0) {
            hz_module_message(path, path_size, "%s", candidates[i]);
            return HZ_OK;
        }
        size_t used = strlen(reasons);
        hz_module_message(reasons + used, sizeof reasons - used, "%s%s: %s", i ? "; " : "",
                          candidates[i], strerror(errno));
    }
    if (err && err_size)
        not_found(err, err_size, count, reasons);
    return HZ_ERROR;
}

hz_status vdb_module_get(const haze_openvdb_api **api, char *err, size_t err_size)
{
    pthread_once(&module_once, module_search);
    *api = the_module.api;
    if (*api)
        return HZ_OK;
    if (err && err_size)
        hz_module_message(err, err_size, "%s", the_module.error);
    return HZ_ERROR;
}

void vdb_reader_path(char *out, size_t size)
{
    const char *env = getenv("HAZE_VDB_READER");
    if (env && env[0]) {
        hz_module_message(out, size, "%s", env);
        return;
    }
    char exe[MODULE_PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
        exe[n] = '\0';
        char *slash = strrchr(exe, '/');
        if (slash) {
            slash[1] = '\0';
            hz_module_message(out, size, "%s%s", exe, HAZE_VDB_READER_NAME);
            if (access(out, X_OK) == 0)
                return;
        }
    }
    hz_module_message(out, size, "%s", HAZE_VDB_READER_BUILD_PATH);
}
