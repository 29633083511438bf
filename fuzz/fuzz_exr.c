/* libFuzzer target: the EXR reader (exr_read) on arbitrary bytes. exr_read takes
 * a path, so each input is written to an anonymous in-memory file (memfd) and
 * read back through /proc/self/fd/N: nothing touches the disk, and concurrent
 * fuzzing processes cannot collide. */
#define _GNU_SOURCE
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

#include <openexr.h>

#include "film/exr.h"
#include "fuzz_memfd.h"

/* exr_read accepts images up to 16 GiB: a few flipped header bits make a tiny
 * file claim gigabytes, which exr_read allocates before it finds the pixel
 * data missing (slow, and libFuzzer reports it as out-of-memory). Skip inputs
 * whose header claims more than this many channel samples; see
 * docs/fuzzing.md. */
#define FUZZ_MAX_SAMPLES (1 << 22)

static void quiet(exr_const_context_t ctx, exr_result_t code, const char *msg)
{
    (void)ctx;
    (void)code;
    (void)msg;
}

static bool header_too_large(const char *path)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    exr_context_t ctx = NULL;
    bool big = false;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *chl = NULL;
    if (exr_start_read(&ctx, path, &init) == EXR_ERR_SUCCESS &&
        exr_get_data_window(ctx, 0, &dw) == EXR_ERR_SUCCESS &&
        exr_get_channels(ctx, 0, &chl) == EXR_ERR_SUCCESS && chl) {
        double w = (double)dw.max.x - dw.min.x + 1, h = (double)dw.max.y - dw.min.y + 1;
        big = w * h * chl->num_channels > FUZZ_MAX_SAMPLES;
    }
    exr_finish(&ctx);
    return big;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int fd = fuzz_memfd("haze-fuzz-exr", data, size, path, sizeof path);
    exr_image img;
    hz_error err;
    if (!header_too_large(path) && exr_read(path, &img, &err) == HZ_OK) {
        /* Touch what was read so uninitialised or short buffers show up. */
        volatile float sink = 0.0f;
        size_t npix = (size_t)img.width * (size_t)img.height;
        for (int c = 0; c < img.channel_count; c++)
            for (size_t i = 0; i < npix; i++)
                sink += img.channels[c].pixels[i];
        (void)sink;
        exr_image_free(&img);
    }
    close(fd);
    return 0;
}
