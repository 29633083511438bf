/* Image textures' files (textures/texture_image.h). */
#include "textures/texture_image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "film/exr.h"
#include "film/png.h"

static double srgb_to_linear(double v)
{
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

hz_status tex_image_read_png(const char *path, file_loc loc, int enc, double gamma, tex_image *out,
                            float **alpha, hz_error *err)
{
    *alpha = NULL;
    png_samples ps;
    hz_error e;
    if (png_read_samples(path, &ps, &e) != HZ_OK)
        return hz_fail_at(err, loc, "cannot read PNG \"%s\": %s", path, e.message);
    size_t n = (size_t)ps.width * (size_t)ps.height;
    out->rgb = malloc((n ? 3 * n : 1) * sizeof *out->rgb);
    *alpha = ps.rgba ? malloc((n ? n : 1) * sizeof **alpha) : NULL;
    if (!out->rgb || (ps.rgba && !*alpha)) {
        free(out->rgb);
        free(*alpha);
        out->rgb = NULL;
        *alpha = NULL;
        png_samples_free(&ps);
        return hz_fail(err, "out of memory");
    }
    out->width = ps.width;
    out->height = ps.height;
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < (ps.rgba ? 4 : 3); ++c) {
            double v = ps.samples[4 * i + (size_t)c] / (double)ps.max;
            float f = (float)(enc == 0 ? srgb_to_linear(v) : enc == 1 ? v : pow(v, gamma));
            if (c < 3)
                out->rgb[3 * i + (size_t)c] = f;
            else
                (*alpha)[i] = f;
        }
    png_samples_free(&ps);
    return HZ_OK;
}

hz_status tex_image_read_exr(const char *path, file_loc loc, tex_image *out, float **alpha,
                            hz_error *err)
{
    *alpha = NULL;
    exr_image img;
    memset(&img, 0, sizeof img);
    hz_error e;
    if (exr_read(path, &img, &e) != HZ_OK)
        return hz_fail_at(err, loc, "cannot read EXR \"%s\": %s", path, e.message);
    const exr_channel *ch[3] = {exr_find_channel(&img, "R"), exr_find_channel(&img, "G"),
                                exr_find_channel(&img, "B")};
    if (!ch[0] || !ch[1] || !ch[2]) {
        const exr_channel *y = exr_find_channel(&img, "Y");
        if (!y && img.channel_count == 1)
            y = &img.channels[0];
        ch[0] = ch[1] = ch[2] = y;
    }
    const exr_channel *a = ch[0] != ch[1] ? exr_find_channel(&img, "A") : NULL;
    if (!ch[0]) {
        exr_image_free(&img);
        return hz_fail_at(err, loc, "EXR \"%s\" has no R, G, B or Y channel", path);
    }
    size_t n = (size_t)img.width * (size_t)img.height;
    out->rgb = malloc((n ? n : 1) * 3 * sizeof *out->rgb);
    *alpha = a ? malloc((n ? n : 1) * sizeof **alpha) : NULL;
    if (!out->rgb || (a && !*alpha)) {
        free(out->rgb);
        out->rgb = NULL;
        free(*alpha);
        *alpha = NULL;
        exr_image_free(&img);
        return hz_fail(err, "out of memory");
    }
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k)
            out->rgb[3 * i + (size_t)k] = ch[k]->pixels[i];
        if (a)
            (*alpha)[i] = a->pixels[i];
    }
    out->width = img.width;
    out->height = img.height;
    exr_image_free(&img);
    return HZ_OK;
}


hz_status tex_image_read_encoding(param_list *pl, bool png, int *enc, double *gamma,
                                  hz_error *err)
{
    const char *e = params_string(pl, "encoding", png ? "sRGB" : "linear");
    *gamma = 1.0;
    if (strcmp(e, "sRGB") == 0)
        *enc = 0;
    else if (strcmp(e, "linear") == 0)
        *enc = 1;
    else if (sscanf(e, "gamma %lf", gamma) == 1 && isfinite(*gamma) && *gamma > 0.0)
        *enc = 2;
    else
        return hz_fail_at(err, params_loc(pl, "encoding"),
                          "\"encoding\" \"%s\" must be \"sRGB\", \"linear\" or \"gamma G\"", e);
    return HZ_OK;
}

void tex_image_float_channels(tex_image *im, const float *alpha)
{
    size_t n = (size_t)im->width * (size_t)im->height;
    bool use_alpha = false;
    for (size_t i = 0; alpha && i < n && !use_alpha; ++i)
        use_alpha = alpha[i] != 1.0f;
    for (size_t i = 0; i < n; ++i) {
        float *p = &im->rgb[3 * i];
        float v = use_alpha ? alpha[i] : (p[0] + p[1] + p[2]) / 3.0f;
        p[1] = p[2] = v;
    }
}
