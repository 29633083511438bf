/* libFuzzer target: the .nvdb loader (NanoVDB file reading, haze's structural
 * check, NanoVDB's validator), then what a render does with a grid: its
 * support, its majorant grid and trilinear lookups across it. grid_load takes
 * a path, so each input goes to an anonymous in-memory file (memfd) read back
 * through /proc/self/fd/N. Seeds: volumes/box.nvdb and vec_ramp.nvdb. */
#define _GNU_SOURCE
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "media/grid.h"
#include "media/majorant.h"
#include "fuzz_memfd.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void use_grid(grid *g)
{
    vec3 lo, hi;
    if (grid_support_bounds(g, &lo, &hi)) {
        majorant_grid mg;
        hz_error err;
        int32_t pad[3] = {1, 0, 2};
        if (majorant_grid_build(g, NULL, lo, hi, pad, &mg, &err) == HZ_OK) {
            size_t bricks, cells; /* every brick, also those left to their first use */
            majorant_grid_count(&mg, &bricks, &cells);
            majorant_grid_free(&mg);
        }
        grid_accessor acc;
        grid_accessor_init(g, &acc);
        volatile double sink = 0.0;
        for (int i = 0; i <= 16; ++i) {
            double t = i / 16.0;
            sink += grid_density_index(g, &acc, v3(lo.x + t * (hi.x - lo.x), lo.y + t * (hi.y - lo.y),
                                                   hi.z - t * (hi.z - lo.z)));
        }
        (void)sink;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* Only NanoVDB files: a mutation that makes an OpenVDB file would go to
     * the dlopened OpenVDB module, whose reader trusts the sizes it reads
     * (outside this target; docs/fuzzing.md). */
    if (size < 7 || memcmp(data, "NanoVDB", 7) != 0)
        return 0;
    char path[64];
    int fd = fuzz_memfd("haze-fuzz-nvdb", data, size, path, sizeof path);
    const char *names[2] = {"density", "v"};
    for (int k = 0; k < 2; ++k) {
        grid *g = NULL;
        hz_error err;
        hz_status st = k == 0 ? grid_load(path, names[k], &g, &err)
                              : grid_load_vec3(path, names[k], &g, &err);
        if (st == HZ_OK) {
            if (k == 0)
                use_grid(g);
            grid_destroy(g);
        }
    }
    close(fd);
    return 0;
}
