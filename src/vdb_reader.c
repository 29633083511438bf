/* haze_vdb_reader MODULE FILE FILE_SIZE GRID TYPE: reads one grid of an
 * OpenVDB file with haze's OpenVDB module and writes it, as a NanoVDB buffer,
 * to stdout (see src/media/vdb_module.h, vdb_module_load_grid_isolated). Run
 * by haze, not by users. */
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "media/vdb_module.h"

int main(int argc, char **argv)
{
    if (argc != 6) {
        fprintf(stderr, "usage: %s MODULE FILE FILE_SIZE GRID TYPE (run by haze)\n", argv[0]);
        return 2;
    }
    uint64_t size = strtoull(argv[3], NULL, 10);
    vdb_value_type type = atoi(argv[5]) == VDB_VEC3 ? VDB_VEC3 : VDB_FLOAT;
    return vdb_reader_run(argv[1], argv[2], size, argv[4], type, STDOUT_FILENO);
}
