/* The data files the stand-ins of tests/standins name, for the spectral part
 * of `make bench` (bench/spectral.sh, bench/README.md): the textures
 * tests/render/test_standins.c writes too (tests/standins/standin_textures.h),
 * under the same names.
 *
 * Usage: haze_spectral_data DIR
 * Writes DIR/textures/sky.exr (and sunflowers_equiarea_blurred.exr: a 64x64
 * equal-area sky, a blue gradient over a dark ground and a small warm sun)
 * and DIR/textures/stone.png, leaf.png, bump.png (32x32 RGBA). DIR/textures
 * must exist. Exit 0 written, 1 failed, 2 usage. */
#include <stdio.h>

#include "standins/standin_textures.h"

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: haze_spectral_data DIR\n");
        return 2;
    }
    hz_error err = {0};
    if (standin_textures_write(argv[1], &err) != HZ_OK) {
        fprintf(stderr, "haze_spectral_data: %s\n", err.message);
        return 1;
    }
    return 0;
}
