/* Richardson extrapolation of two renders for `make bench` (bench/README.md,
 * the peer): OUT = 2 FINE - COARSE, channel by channel, where FINE and COARSE
 * differ only in a step whose error is first order (FINE's step half of
 * COARSE's). vdb_render's image moves linearly with its shadow step (thick
 * smoke, the image's mean at shadow steps 0.5, 0.25, 0.125 voxels: 0.012397,
 * 0.012189, 0.012087, differences in the ratio 2.04), so the extrapolated
 * image is its converged one to second order, and a rung at either of the two
 * shadow steps measures its own error against it instead of sharing the
 * reference's bias.
 *
 * Usage: exr_extrapolate FINE.exr COARSE.exr OUT.exr
 * The two images must have the same size and channels; OUT is written in
 * float. Exit 0 written, 1 refused or failed, 2 usage. */
#define _POSIX_C_SOURCE 200809L

#include <stdio.h>
#include <string.h>

#include "film/exr.h"

static int fail(const char *what, const hz_error *err)
{
    fprintf(stderr, "exr_extrapolate: %s: %s\n", what, err->message);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: exr_extrapolate FINE.exr COARSE.exr OUT.exr\n");
        return 2;
    }
    hz_error err = {0};
    exr_image fine = {0}, coarse = {0};
    int rc = 1;
    if (exr_read(argv[1], &fine, &err) != HZ_OK) {
        rc = fail(argv[1], &err);
        goto out;
    }
    if (exr_read(argv[2], &coarse, &err) != HZ_OK) {
        rc = fail(argv[2], &err);
        goto out;
    }
    if (fine.width != coarse.width || fine.height != coarse.height ||
        fine.channel_count != coarse.channel_count) {
        fprintf(stderr, "exr_extrapolate: %s and %s differ in size or channels\n", argv[1],
                argv[2]);
        goto out;
    }
    size_t n = (size_t)fine.width * (size_t)fine.height;
    for (int c = 0; c < fine.channel_count; ++c) {
        exr_channel *f = &fine.channels[c];
        const exr_channel *k = exr_find_channel(&coarse, f->name);
        if (!k) {
            fprintf(stderr, "exr_extrapolate: %s has no channel %s\n", argv[2], f->name);
            goto out;
        }
        for (size_t i = 0; i < n; ++i)
            f->pixels[i] = 2.0f * f->pixels[i] - k->pixels[i];
        f->half = false;
    }
    fine.threads = 1;
    if (exr_write(argv[3], &fine, &err) != HZ_OK) {
        rc = fail(argv[3], &err);
        goto out;
    }
    rc = 0;
out:
    exr_image_free(&fine);
    exr_image_free(&coarse);
    return rc;
}
