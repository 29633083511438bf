/* OpenEXR reading and writing through OpenEXRCore (the C API). */
#ifndef HAZE_FILM_EXR_H
#define HAZE_FILM_EXR_H

#include <stdbool.h>

#include "core/error.h"

typedef struct {
    char name[64];      /* "R", "G", "B", "A", "Z", "Variance.R", ... */
    bool half;          /* stored as half (read) / to store as half (write) */
    float *pixels;      /* width*height values, row-major, top row first */
} exr_channel;

typedef struct {
    int width, height;            /* data window size */
    int data_x0, data_y0;         /* data window origin */
    int display_width, display_height; /* display window is [0,w) x [0,h) */
    int channel_count;
    exr_channel *channels;
    /* Optional string attributes written to / read from the header. */
    int attribute_count;
    char (*attribute_names)[64];
    char (*attribute_values)[256];
} exr_image;

/* Allocates channels (zeroed); names are set by the caller. */
hz_status exr_image_alloc(exr_image *img, int width, int height, int channel_count, hz_error *err);
void exr_image_free(exr_image *img);
const exr_channel *exr_find_channel(const exr_image *img, const char *name);

/* Scanline, ZIP-compressed; written to "path.tmp-XXXXXX" in the same directory
 * and renamed, so a failure never leaves a broken file at `path`. */
hz_status exr_write(const char *path, const exr_image *img, hz_error *err);
/* Reads every channel (half or float; uint channels are refused) into float. */
hz_status exr_read(const char *path, exr_image *out, hz_error *err);

#endif
