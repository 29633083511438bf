/* PNG input: a file's samples as stored, as pbrt-v4 reads textures (no gamma,
 * sRGB or ICC conversion: libpng's simplified API would apply gAMA and take
 * 16-bit data as linear). libpng reports errors by longjmp; the state the
 * error path frees lives in a heap struct set up before setjmp. */
#include "film/png.h"

#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <png.h>
#include <sys/stat.h>

#include "core/file.h"

typedef struct {
    char message[200];
    FILE *f;
    png_structp png;
    png_infop info;
    png_bytep pixels;
    png_bytepp rows;
} png_reader;

static void reader_error(png_structp png, png_const_charp msg)
{
    png_reader *r = png_get_error_ptr(png);
    snprintf(r->message, sizeof r->message, "%s", msg);
    png_longjmp(png, 1);
}

static void reader_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;
}

static void reader_close(png_reader *r)
{
    if (r->png)
        png_destroy_read_struct(&r->png, r->info ? &r->info : NULL, NULL);
    if (r->f)
        fclose(r->f);
    free(r->pixels);
    free(r->rows);
    free(r);
}

/* Decodes r->f into out; false (r->message set) on error. */
static bool reader_run(png_reader *r, png_samples *out)
{
    if (setjmp(png_jmpbuf(r->png)))
        return false;
    png_init_io(r->png, r->f);
    png_set_user_limits(r->png, 1u << 16, 1u << 16);
    png_read_info(r->png, r->info);
    int type = png_get_color_type(r->png, r->info);
    int depth = png_get_bit_depth(r->png, r->info);
    if (type == PNG_COLOR_TYPE_PALETTE)
        png_set_palette_to_rgb(r->png);
    if (type == PNG_COLOR_TYPE_GRAY && depth < 8)
        png_set_expand_gray_1_2_4_to_8(r->png);
    if (!(type & PNG_COLOR_MASK_COLOR))
        png_set_gray_to_rgb(r->png);
    png_set_interlace_handling(r->png);
    png_read_update_info(r->png, r->info);
    png_uint_32 w = png_get_image_width(r->png, r->info);
    png_uint_32 h = png_get_image_height(r->png, r->info);
    int channels = png_get_channels(r->png, r->info);
    int bits = png_get_bit_depth(r->png, r->info);
    size_t row_bytes = png_get_rowbytes(r->png, r->info);
    if ((channels != 3 && channels != 4) || (bits != 8 && bits != 16)) {
        snprintf(r->message, sizeof r->message, "unexpected layout (%d channels of %d bits)",
                 channels, bits);
        return false;
    }
    r->pixels = malloc(row_bytes * h + 1);
    r->rows = malloc(sizeof *r->rows * (h + 1));
    out->samples = malloc(sizeof *out->samples * 4 * (size_t)w * h + 1);
    if (!r->pixels || !r->rows || !out->samples) {
        snprintf(r->message, sizeof r->message, "out of memory");
        return false;
    }
    for (png_uint_32 y = 0; y < h; ++y)
        r->rows[y] = r->pixels + y * row_bytes;
    png_read_image(r->png, r->rows);
    png_read_end(r->png, NULL);
    out->width = (int)w;
    out->height = (int)h;
    out->max = bits == 16 ? 65535 : 255;
    out->rgba = type == PNG_COLOR_TYPE_RGB_ALPHA;
    for (png_uint_32 y = 0; y < h; ++y)
        for (png_uint_32 x = 0; x < w; ++x)
            for (int c = 0; c < 4; ++c) {
                size_t i = (size_t)x * (size_t)channels + (size_t)c;
                const png_byte *p = r->rows[y] + (bits == 16 ? 2 * i : i);
                uint16_t v = c >= channels ? out->max
                             : bits == 16  ? (uint16_t)(p[0] << 8 | p[1])
                                           : p[0];
                out->samples[4 * ((size_t)y * w + x) + (size_t)c] = v;
            }
    return true;
}

hz_status png_read_samples(const char *path, png_samples *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    png_reader *r = calloc(1, sizeof *r);
    if (!r)
        return hz_fail(err, "out of memory");
    /* A FIFO's open would wait for a writer, a device never end. */
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        reader_close(r);
        return hz_fail(err, "is %s; haze reads only regular files", file_kind_name(st.st_mode));
    }
    r->f = fopen(path, "rb");
    if (!r->f) {
        reader_close(r);
        return hz_fail(err, "cannot open");
    }
    r->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, r, reader_error, reader_warning);
    r->info = r->png ? png_create_info_struct(r->png) : NULL;
    if (!r->info) {
        reader_close(r);
        return hz_fail(err, "out of memory");
    }
    bool ok = reader_run(r, out);
    if (!ok) {
        hz_fail(err, "%s", r->message);
        png_samples_free(out);
    }
    reader_close(r);
    return ok ? HZ_OK : HZ_ERROR;
}

void png_samples_free(png_samples *s)
{
    free(s->samples);
    memset(s, 0, sizeof *s);
}
