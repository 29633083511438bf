/* Finding and loading the RGB -> spectrum tables' module (see rgb2spec_module.h). */
#include "color/rgb2spec_module.h"

#include <stddef.h>

#include "core/module.h"

/* Set by the build: the module's file name and its absolute path in the build tree. */
#ifndef HAZE_RGB2SPEC_MODULE_NAME
#define HAZE_RGB2SPEC_MODULE_NAME "libhaze_rgb2spec.so"
#endif
#ifndef HAZE_RGB2SPEC_MODULE_BUILD_PATH
#define HAZE_RGB2SPEC_MODULE_BUILD_PATH ""
#endif

hz_status rgb2spec_tables_load(const rgb2spec_table **out, hz_error *err)
{
    static const hz_module_spec spec = {
        "HAZE_RGB2SPEC_MODULE", HAZE_RGB2SPEC_MODULE_NAME, HAZE_RGB2SPEC_MODULE_BUILD_PATH,
        HAZE_RGB2SPEC_ENTRY,    HAZE_RGB2SPEC_ABI,         sizeof(haze_rgb2spec_api),
        "RGB -> spectrum"};
    char path[HZ_MODULE_PATH_MAX], reasons[2 * HZ_MODULE_PATH_MAX + 8];
    int tried = 0;
    *out = NULL;
    const haze_rgb2spec_api *api =
        hz_module_open(&spec, path, sizeof path, reasons, sizeof reasons, &tried);
    if (!api)
        return hz_fail(err, "cannot load the RGB -> spectrum tables (tried %s); set "
                            "HAZE_RGB2SPEC_MODULE to the path of %s",
                       tried ? reasons : "no path", HAZE_RGB2SPEC_MODULE_NAME);
    if (api->table_size != sizeof(rgb2spec_table) ||
        api->solution_size != sizeof(rgb2spec_solution) || api->count != COLOR_SPACE_COUNT)
        return hz_fail(err, "%s: tables of another haze build (%u spaces of %u + %u bytes, "
                            "this haze needs %d of %zu + %zu)",
                       path, (unsigned)api->count, (unsigned)api->table_size,
                       (unsigned)api->solution_size, (int)COLOR_SPACE_COUNT,
                       sizeof(rgb2spec_table), sizeof(rgb2spec_solution));
    *out = api->tables;
    return HZ_OK;
}
