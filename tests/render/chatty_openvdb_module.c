/* A stand-in for the OpenVDB module that prints to stdout what OpenVDB's
 * log4cplus prints there (a coloured warning, flushed) before it fails: the
 * reader's replies must not take it in, and haze's error must be the
 * module's one line (test_vdb_module.c). */
#include <stdio.h>

#include "media/vdb_module.h"

static hz_status load_grid(const char *path, uint64_t file_size, const char *gridname,
                           vdb_value_type type, int memfd, vdb_buffer *out, char *err,
                           size_t err_size)
{
    (void)file_size, (void)memfd, (void)type, (void)out;
    for (int i = 0; i < 3; ++i)
        printf("\033[35m WARN: %s has more than one grid named \"%s\"\n\033[0m", path, gridname);
    fflush(stdout);
    snprintf(err, err_size, "%s: the chatty module reads no grid", path);
    return HZ_ERROR;
}

const haze_openvdb_api haze_openvdb_entry = {HAZE_OPENVDB_ABI, sizeof(haze_openvdb_api),
                                             load_grid, NULL};
