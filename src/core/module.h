/* Finding and opening haze's dlopen'd modules: the OpenVDB module
 * (media/vdb_module.h) and the MPI module (mpi/mpi_module.h). A module
 * exports one const data symbol, its entry table, whose first two fields are
 * the ABI version and the table's size in the module's build.
 *
 * Where a module is looked for, in order:
 *   1. $ENV (spec.env), if set and not empty: that path only;
 *   2. next to the executable (the directory of /proc/self/exe);
 *   3. the build tree's module (an absolute path baked in at compile time, so
 *      test programs in build/tests and the fuzzers find it). */
#ifndef HAZE_CORE_MODULE_H
#define HAZE_CORE_MODULE_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

typedef struct {
    const char *env;        /* the variable naming the module's path */
    const char *file_name;  /* looked for next to the executable */
    const char *build_path; /* the build tree's module ("" for none) */
    const char *entry;      /* the entry table's symbol */
    uint32_t abi_version;   /* what the table's first field must hold */
    uint32_t struct_size;   /* and its second */
    const char *kind;       /* "OpenVDB": named in "not a haze OpenVDB module" */
} hz_module_spec;

enum { HZ_MODULE_PATH_MAX = 4096, HZ_MODULE_CANDIDATES = 2 };

/* The places to look, in order; returns their count. */
int hz_module_candidates(const hz_module_spec *spec,
                         char out[HZ_MODULE_CANDIDATES][HZ_MODULE_PATH_MAX]);

/* dlopens the first candidate that loads and holds a table of the spec's ABI
 * (RTLD_NOW | RTLD_LOCAL; never unloaded): the table, its path in `path`.
 * NULL when none does, with `reasons` listing each path tried and why it
 * failed ("; " between them) and *tried their count: the caller words the
 * message. */
const void *hz_module_open(const hz_module_spec *spec, char *path, size_t path_size,
                           char *reasons, size_t reasons_size, int *tried);

/* snprintf that may cut long paths short (the result is a message, not a
 * path). */
void hz_module_message(char *out, size_t size, const char *fmt, ...) HZ_PRINTF(3, 4);

#endif
