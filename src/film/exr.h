/* OpenEXR reading and writing through OpenEXRCore (the C API). */
#ifndef HAZE_FILM_EXR_H
#define HAZE_FILM_EXR_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"

/* Room for a string attribute's value, its NUL included: an interrupted
 * render's haze:tile_ranges can be long. */
enum { EXR_ATTRIBUTE_VALUE_SIZE = 1024 };

typedef struct {
    char name[64];      /* "R", "G", "B", "A", "Z", "Variance.R", ... */
    bool half;          /* stored as half (read) / to store as half (write) */
    float *pixels;      /* width*height values, row-major, top row first */
} exr_channel;

typedef struct {
    int width, height;            /* data window size */
    int data_x0, data_y0;         /* data window origin */
    int display_width, display_height; /* display window is [0,w) x [0,h) */
    /* exr_read: where the file's display window starts (the data window in
     * the file is data_x0/y0 plus this); ignored by exr_write. */
    int file_display_x0, file_display_y0;
    int channel_count;
    exr_channel *channels;
    /* Optional string attributes written to / read from the header. */
    int attribute_count;
    char (*attribute_names)[64];
    char (*attribute_values)[EXR_ATTRIBUTE_VALUE_SIZE];
    /* exr_write: a "chromaticities" attribute (red, green, blue, white x, y)
     * when has_chromaticities (the image is not in sRGB/Rec. 709). */
    bool has_chromaticities;
    float chromaticities[8];
    /* exr_write: threads compressing chunks (0 or 1: the calling thread only;
     * at most EXR_MAX_WRITE_THREADS). The file is the same for any count. */
    int threads;
    /* exr_write: when set, the lines are made chunk by chunk as they are
     * compressed, and the channels have no pixels (NULL): fill(fill_ctx, y0,
     * y1, pixels) sets lines [y0, y1) of the data window (0 its top line) of
     * channel c in pixels[c], width values per line. The writer's threads
     * call it at once for disjoint lines. The file is the same as from
     * pixels holding those values. */
    void (*fill)(void *fill_ctx, int y0, int y1, float *const *pixels);
    void *fill_ctx;
} exr_image;

#define EXR_MAX_WRITE_THREADS 64

/* Allocates channels (zeroed); names are set by the caller. The display
 * window is set to the data size; data_x0/y0 to 0. */
hz_status exr_image_alloc(exr_image *img, int width, int height, int channel_count, hz_error *err);
/* The same without the pixels, for exr_image.fill. */
hz_status exr_image_alloc_lines(exr_image *img, int width, int height, int channel_count,
                                hz_error *err);
/* Frees the channels and the attribute arrays (which must be heap memory:
 * add attributes with exr_image_add_attribute). */
void exr_image_free(exr_image *img);
/* Appends a string attribute (name < 64 bytes, value < EXR_ATTRIBUTE_VALUE_SIZE bytes). */
hz_status exr_image_add_attribute(exr_image *img, const char *name, const char *value, hz_error *err);
const exr_channel *exr_find_channel(const exr_image *img, const char *name);

/* The name of an atomic writer's temporary file, published while the file
 * exists so that a signal handler can unlink it before _exit: `path` is
 * complete whenever `valid` is non-zero. (Between mkstemp and publication
 * there is a window of a few instructions in which it is not yet valid.) */
typedef struct {
    char path[4200];
    volatile sig_atomic_t valid;
} tmp_file_note;

/* Publish / withdraw a temporary name (no-ops on a NULL note). */
void tmp_file_note_set(tmp_file_note *note, const char *tmp);
void tmp_file_note_clear(tmp_file_note *note);

/* Scanline, ZIP-compressed; written to "path.tmp-XXXXXX" in the same directory
 * and renamed, so a failure never leaves a broken file at `path`; on failure
 * the temporary file is removed. */
hz_status exr_write(const char *path, const exr_image *img, hz_error *err);
/* Same, publishing the temporary file's name in `note` (may be NULL) while it exists. */
hz_status exr_write_noted(const char *path, const exr_image *img, tmp_file_note *note,
                          hz_error *err);
/* Reads the first part's channels (half or float; uint, subsampled and deep
 * data are refused) into float; scanline files and the full-resolution level
 * of tiled files. data_x0/y0 are relative to the display window's origin.
 * String attributes are returned; other attribute types are skipped. */
hz_status exr_read(const char *path, exr_image *out, hz_error *err);

/* IEEE half <-> float; float to half rounds to nearest, ties to even. */
uint16_t exr_half_from_float(float f);
float exr_half_to_float(uint16_t h);

#endif
