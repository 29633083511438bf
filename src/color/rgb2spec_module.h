/* The RGB -> spectrum tables live in a data module, libhaze_rgb2spec.so (about
 * 38 MB at 64 nodes per axis), that haze loads only when a render needs them,
 * so neither haze nor a program that never looks a colour up carries them.
 *
 * This header holds the ABI between the two: the entry table the module
 * exports (a const data symbol, HAZE_RGB2SPEC_ENTRY, found by dlsym and checked
 * for HAZE_RGB2SPEC_ABI and its sizes), and rgb2spec_tables_load, which finds
 * and loads the module.
 *
 * Where the module is looked for, in order (core/module.h):
 *   1. $HAZE_RGB2SPEC_MODULE, if set and not empty: that path only;
 *   2. next to the executable (the directory of /proc/self/exe);
 *   3. the build tree's module (an absolute path baked in at compile time, so
 *      test programs in build/tests find it). */
#ifndef HAZE_COLOR_RGB2SPEC_MODULE_H
#define HAZE_COLOR_RGB2SPEC_MODULE_H

#include <stdint.h>

#include "color/rgb2spec_table.h"
#include "core/error.h"

/* Bump when haze_rgb2spec_api, rgb2spec_table or rgb2spec_solution change in
 * any way (the sizes below catch most changes, not all). */
#define HAZE_RGB2SPEC_ABI 1
#define HAZE_RGB2SPEC_ENTRY "haze_rgb2spec_entry"

typedef struct {
    uint32_t abi_version;   /* HAZE_RGB2SPEC_ABI of the module's build */
    uint32_t struct_size;   /* sizeof(haze_rgb2spec_api) of the module's build */
    uint32_t table_size;    /* sizeof(rgb2spec_table) */
    uint32_t solution_size; /* sizeof(rgb2spec_solution) */
    uint32_t count;         /* COLOR_SPACE_COUNT */
    const rgb2spec_table *tables; /* [count], tables[cs].cs == cs */
} haze_rgb2spec_api;

/* Loads the module (dlopen's reference count: calling this again is cheap and
 * returns the same tables; the module is never unloaded) and points *out at
 * its COLOR_SPACE_COUNT tables, indexed by color_space. On failure *out is
 * NULL and err holds one line naming every path tried and why it failed. */
hz_status rgb2spec_tables_load(const rgb2spec_table **out, hz_error *err);

#endif
