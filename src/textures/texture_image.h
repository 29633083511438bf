/* The images of image textures and normal maps: PNG and EXR files read as
 * linear RGB, as pbrt-v4 reads them. */
#ifndef HAZE_TEXTURES_TEXTURE_IMAGE_H
#define HAZE_TEXTURES_TEXTURE_IMAGE_H

#include <stdbool.h>

#include "core/error.h"
#include "scene/params.h"

/* pbrt-v4 reads a float image texture from an RGB(A) image in two ways: a
 * texel lookup (point filter, ewa, the coarsest level) takes its first
 * channel, a bilinear one the mean of R, G and B, or A when the image has an
 * alpha channel that is not all one. A float texture's image holds R in
 * channel 0 and that second value in channels 1 and 2. */
typedef struct {
    int width, height;
    float *rgb; /* 3 per texel, linear, top row first */
} tex_image;

/* A PNG as rgb in [0, 1], its samples as stored (8 or 16 bits; no gAMA or
 * sRGB chunk applied, as pbrt-v4) decoded by `enc` (0 sRGB, 1 linear, 2
 * gamma `gamma`), and *alpha (decoded alike, as pbrt-v4) when it is an RGBA
 * image; as pbrt-v4, grey and palette images have none. */
hz_status tex_image_read_png(const char *path, file_loc loc, int enc, double gamma, tex_image *out,
                            float **alpha, hz_error *err);
/* An EXR's R, G, B (or Y, or its one channel) as linear rgb, and its A as
 * *alpha when it has R, G, B and A. */
hz_status tex_image_read_exr(const char *path, file_loc loc, tex_image *out, float **alpha,
                            hz_error *err);
/* "string encoding" (default sRGB for a PNG, linear otherwise) as `enc` and
 * `gamma` for tex_image_read_png. */
hz_status tex_image_read_encoding(param_list *pl, bool png, int *enc, double *gamma,
                                  hz_error *err);
/* A float texture's image (see tex_image): R, then the mean of R, G and B,
 * or alpha when there is one that is not all one (pbrt-v4 drops an all-one
 * alpha). */
void tex_image_float_channels(tex_image *im, const float *alpha);

#endif
