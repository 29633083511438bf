/* The data files the stand-ins of tests/standins name, for the spectral part
 * of `make bench` (bench/spectral.sh, bench/README.md): the same patterns
 * tests/render/test_standins.c writes, under the same names.
 *
 * Usage: haze_spectral_data DIR
 * Writes DIR/textures/sky.exr (a 64x64 equal-area sky: a blue gradient over
 * a dark ground and a small warm sun) and DIR/textures/stone.png, leaf.png,
 * bump.png (32x32 RGBA). DIR/textures must exist. Exit 0 written, 1 failed,
 * 2 usage. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <png.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "core/sampling.h"
#include "core/vec.h"
#include "film/exr.h"

static bool write_sky(const char *path)
{
    enum { RES = 64 };
    exr_image img;
    hz_error err = {0};
    if (exr_image_alloc(&img, RES, RES, 3, &err) != HZ_OK) {
        fprintf(stderr, "haze_spectral_data: %s\n", err.message);
        return false;
    }
    const char *names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c)
        snprintf(img.channels[c].name, sizeof img.channels[c].name, "%s", names[c]);
    vec3 sun = v3_normalize(v3(0.4, 0.3, 0.8));
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            vec3 w = equal_area_square_to_sphere(v2((x + 0.5) / RES, (y + 0.5) / RES));
            double up = fmax(w.z, 0.0);
            float v[3] = {(float)(0.3 + 0.2 * up), (float)(0.45 + 0.3 * up), (float)(0.7 + up)};
            if (w.z < 0.0)
                v[0] = v[1] = v[2] = 0.05f;
            if (v3_dot(w, sun) > 0.995)
                v[0] = 400.0f, v[1] = 350.0f, v[2] = 300.0f;
            for (int c = 0; c < 3; ++c)
                img.channels[c].pixels[y * RES + x] = v[c];
        }
    bool ok = exr_write(path, &img, &err) == HZ_OK;
    if (!ok)
        fprintf(stderr, "haze_spectral_data: %s\n", err.message);
    exr_image_free(&img);
    return ok;
}

/* Stone: warm tiles with dark joints. */
static void stone(int x, int y, double v[4])
{
    bool joint = x % 8 == 0 || y % 8 == 0;
    v[0] = joint ? 0.2 : 0.7 + 0.02 * (x % 5);
    v[1] = joint ? 0.2 : 0.55;
    v[2] = joint ? 0.2 : 0.4 + 0.02 * (y % 3);
}

/* A leaf: green inside an ellipse, alpha 1 there and 0 outside. */
static void leaf(int x, int y, double v[4])
{
    double dx = (x - 15.5) / 15.0, dy = (y - 15.5) / 9.0;
    v[0] = 0.1;
    v[1] = 0.6;
    v[2] = 0.15;
    v[3] = dx * dx + dy * dy < 1.0 ? 1.0 : 0.0;
}

static void bumps(int x, int y, double v[4])
{
    v[0] = v[1] = v[2] = 0.5 + 0.25 * sin(x * 0.6) * cos(y * 0.4);
}

/* A 32x32 8-bit RGBA PNG of pattern(x, y) in [0, 1] per channel. */
static bool write_png(const char *path, void (*pattern)(int x, int y, double out[4]))
{
    enum { RES = 32 };
    uint8_t buf[RES * RES * 4];
    for (int y = 0; y < RES; ++y)
        for (int x = 0; x < RES; ++x) {
            double v[4] = {0, 0, 0, 1};
            pattern(x, y, v);
            for (int c = 0; c < 4; ++c)
                buf[4 * (y * RES + x) + c] = (uint8_t)lround(255.0 * v[c]);
        }
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = im.height = RES;
    im.format = PNG_FORMAT_RGBA;
    if (!png_image_write_to_file(&im, path, 0, buf, 0, NULL)) {
        fprintf(stderr, "haze_spectral_data: cannot write %s\n", path);
        return false;
    }
    return true;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: haze_spectral_data DIR\n");
        return 2;
    }
    static const struct {
        const char *name;
        void (*pattern)(int, int, double[4]);
    } pngs[] = {{"stone.png", stone}, {"leaf.png", leaf}, {"bump.png", bumps}};
    char path[4096];
    snprintf(path, sizeof path, "%s/textures/sky.exr", argv[1]);
    if (!write_sky(path))
        return 1;
    for (size_t i = 0; i < sizeof pngs / sizeof pngs[0]; ++i) {
        snprintf(path, sizeof path, "%s/textures/%s", argv[1], pngs[i].name);
        if (!write_png(path, pngs[i].pattern))
            return 1;
    }
    return 0;
}
