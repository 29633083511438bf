/* A stand-in for the OpenVDB module whose grid reader dies the way OpenVDB
 * and Blosc do when memory runs out (a write through a failed allocation),
 * after printing what Blosc prints: the renderer must survive it and report
 * one line (test_vdb_module.c). */
#include <signal.h>
#include <stdio.h>

#include "media/vdb_module.h"

static hz_status load_grid(const char *path, uint64_t file_size, const char *gridname,
                           vdb_value_type type, int memfd, vdb_buffer *out, char *err,
                           size_t err_size)
{
    (void)path, (void)file_size, (void)memfd, (void)gridname, (void)type, (void)out, (void)err,
        (void)err_size;
    fprintf(stderr, "Error allocating memory!");
    raise(SIGSEGV);
    return HZ_ERROR;
}

const haze_openvdb_api haze_openvdb_entry = {HAZE_OPENVDB_ABI, sizeof(haze_openvdb_api),
                                             load_grid, NULL};
