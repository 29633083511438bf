/* The stand-ins' generated textures (standin_textures.h). */
#define _POSIX_C_SOURCE 200809L
#include "standins/standin_textures.h"

#include <math.h>
#include <png.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "core/sampling.h"
#include "core/vec.h"
#include "film/exr.h"

/* A 64x64 equal-area sky: a blue gradient over a dark ground and a small
 * warm sun, in the scenes' +z-up light space. */
static hz_status write_sky(const char *path, hz_error *err)
{
    enum { RES = 64 };
    exr_image img;
    if (exr_image_alloc(&img, RES, RES, 3, err) != HZ_OK)
        return HZ_ERROR;
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
    hz_status st = exr_write(path, &img, err);
    exr_image_free(&img);
    return st;
}

/* A 32x32 8-bit RGBA PNG of pattern(x, y) in [0, 1] per channel (R, G, B,
 * A; the pattern sets A only where it is not 1). */
static hz_status write_png(const char *path, void (*pattern)(int x, int y, double out[4]),
                           hz_error *err)
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
    if (!png_image_write_to_file(&im, path, 0, buf, 0, NULL))
        return hz_fail(err, "cannot write %s: %s", path, im.message);
    return HZ_OK;
}

/* Stone: warm tiles with dark joints. */
static void stone(int x, int y, double v[4])
{
    bool joint = x % 8 == 0 || y % 8 == 0;
    v[0] = joint ? 0.2 : 0.7 + 0.02 * (x % 5);
    v[1] = joint ? 0.2 : 0.55;
    v[2] = joint ? 0.2 : 0.4 + 0.02 * (y % 3);
}

/* A leaf: green inside an ellipse, alpha 1 there and 0 outside (a float
 * texture of it reads the alpha, as pbrt-v4's does). */
static void leaf(int x, int y, double v[4])
{
    double dx = (x - 15.5) / 15.0, dy = (y - 15.5) / 9.0;
    double in = dx * dx + dy * dy < 1.0 ? 1.0 : 0.0;
    v[0] = 0.1;
    v[1] = 0.6;
    v[2] = 0.15;
    v[3] = in;
}

static void bumps(int x, int y, double v[4])
{
    v[0] = v[1] = v[2] = 0.5 + 0.25 * sin(x * 0.6) * cos(y * 0.4);
}

hz_status standin_textures_write(const char *dir, hz_error *err)
{
    static const struct {
        const char *name;
        void (*pattern)(int, int, double[4]);
    } pngs[] = {{"stone.png", stone}, {"leaf.png", leaf}, {"bump.png", bumps}};
    static const char *skies[] = {"sky.exr", "sunflowers_equiarea_blurred.exr"};
    char path[4096];
    for (size_t i = 0; i < sizeof skies / sizeof skies[0]; ++i) {
        snprintf(path, sizeof path, "%s/textures/%s", dir, skies[i]);
        if (write_sky(path, err) != HZ_OK)
            return HZ_ERROR;
    }
    for (size_t i = 0; i < sizeof pngs / sizeof pngs[0]; ++i) {
        snprintf(path, sizeof path, "%s/textures/%s", dir, pngs[i].name);
        if (write_png(path, pngs[i].pattern, err) != HZ_OK)
            return HZ_ERROR;
    }
    return HZ_OK;
}
