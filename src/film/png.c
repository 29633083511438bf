/* PNG preview writer. libpng reports errors by longjmp; everything the
 * error path needs is set up before setjmp, so nothing has to be volatile. */
#define _POSIX_C_SOURCE 200809L

#include "film/png.h"

#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <png.h>

uint8_t png_out_srgb8(double v)
{
    if (!(v > 0.0)) /* also NaN */
        return 0;
    if (v >= 1.0)
        return 255;
    double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (uint8_t)(s * 255.0 + 0.5);
}

typedef struct {
    char message[256];
} png_out_errors;

static void png_out_error(png_structp png, png_const_charp msg)
{
    png_out_errors *e = png_get_error_ptr(png);
    snprintf(e->message, sizeof e->message, "%s", msg);
    png_longjmp(png, 1);
}

static void png_out_warning(png_structp png, png_const_charp msg)
{
    (void)png; /* warnings are not errors; keep stderr quiet */
    (void)msg;
}

/* Encodes into an open stream; returns 0 on success. */
static int png_out_encode(FILE *fp, int width, int height, const uint8_t *rgb8, png_bytep *rows,
                          png_out_errors *errs)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, errs, png_out_error,
                                              png_out_warning);
    if (!png) {
        snprintf(errs->message, sizeof errs->message, "out of memory");
        return -1;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, NULL);
        snprintf(errs->message, sizeof errs->message, "out of memory");
        return -1;
    }
    for (int y = 0; y < height; y++)
        rows[y] = (png_bytep)(rgb8 + (size_t)y * (size_t)width * 3);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    png_init_io(png, fp);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_set_rows(png, info, rows);
    png_write_png(png, info, PNG_TRANSFORM_IDENTITY, NULL);
    png_destroy_write_struct(&png, &info);
    return 0;
}

hz_status png_out_write_rgb8(const char *path, int width, int height, const uint8_t *rgb8,
                             hz_error *err)
{
    return png_out_write_rgb8_noted(path, width, height, rgb8, NULL, err);
}

hz_status png_out_write_rgb8_noted(const char *path, int width, int height, const uint8_t *rgb8,
                                   tmp_file_note *note, hz_error *err)
{
    if (width < 1 || height < 1 || width > 1000000 || height > 1000000)
        return hz_fail(err, "%s: invalid PNG size %dx%d", path, width, height);
    png_bytep *rows = malloc((size_t)height * sizeof *rows);
    size_t len = strlen(path);
    char *tmp = malloc(len + 16);
    if (!rows || !tmp) {
        free(rows);
        free(tmp);
        return hz_fail(err, "png: out of memory");
    }
    memcpy(tmp, path, len);
    memcpy(tmp + len, ".tmp-XXXXXX", 12);
    int fd = mkstemp(tmp);
    if (fd < 0) {
        hz_status st = hz_fail(err, "%s: cannot create a temporary file next to it: %s", path,
                               strerror(errno));
        free(rows);
        free(tmp);
        return st;
    }
    tmp_file_note_set(note, tmp);
    struct stat old;
    hz_status st = HZ_OK;
    FILE *fp = NULL;
    if (fchmod(fd, stat(path, &old) == 0 ? (old.st_mode & 07777) : 0644) != 0) {
        st = hz_fail(err, "%s: cannot set the temporary file's mode: %s", path, strerror(errno));
        close(fd);
    } else if (!(fp = fdopen(fd, "wb"))) {
        st = hz_fail(err, "%s: cannot open the temporary file: %s", path, strerror(errno));
        close(fd);
    } else {
        png_out_errors errs = {{0}};
        errno = 0; /* libpng's "Write Error" does not say why; the failed write's errno does */
        if (png_out_encode(fp, width, height, rgb8, rows, &errs) != 0)
            st = errno ? hz_fail(err, "%s: cannot write PNG: %s (%s)", path, errs.message,
                                 strerror(errno))
                       : hz_fail(err, "%s: cannot write PNG: %s", path, errs.message);
        else if (fflush(fp) != 0 || fsync(fileno(fp)) != 0)
            st = hz_fail(err, "%s: cannot write PNG: %s", path, strerror(errno));
        if (fclose(fp) != 0 && st == HZ_OK)
            st = hz_fail(err, "%s: cannot close PNG: %s", path, strerror(errno));
    }
    if (st == HZ_OK && rename(tmp, path) != 0)
        st = hz_fail(err, "%s: cannot rename the temporary PNG into place: %s", path, strerror(errno));
    if (st != HZ_OK)
        unlink(tmp);
    tmp_file_note_clear(note);
    free(rows);
    free(tmp);
    return st;
}
