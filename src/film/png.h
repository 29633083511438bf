/* PNG through libpng: 8-bit RGB output, written atomically (temporary file
 * in the same directory, then rename), and input of a file's samples. */
#ifndef HAZE_FILM_PNG_H
#define HAZE_FILM_PNG_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "film/exr.h" /* tmp_file_note */

/* `rgb8` holds width*height*3 bytes, top row first. */
hz_status png_out_write_rgb8(const char *path, int width, int height, const uint8_t *rgb8,
                             hz_error *err);
/* Same, publishing the temporary file's name in `note` (may be NULL) while it exists. */
hz_status png_out_write_rgb8_noted(const char *path, int width, int height, const uint8_t *rgb8,
                                   tmp_file_note *note, hz_error *err);

/* sRGB transfer of a linear value in [0,1] to 8 bits (round half up). */
uint8_t png_out_srgb8(double linear);

/* A PNG's samples as stored in the file, with no gamma or colour conversion
 * (as pbrt-v4 reads them): RGBA, 4 per pixel, top row first, each in
 * [0, max] (255, or 65535 for 16-bit files). Grey is expanded to R = G = B
 * and a palette to its colours; A is max unless the file has an alpha
 * channel. `rgba`: the file is an RGBA image (grey + alpha and palette
 * transparency do not count, as in pbrt-v4). */
typedef struct {
    int width, height;
    uint16_t max;
    bool rgba;
    uint16_t *samples;
} png_samples;

/* Reads `path`; on error fills err with libpng's reason (the caller names
 * the file) and leaves *out empty. */
hz_status png_read_samples(const char *path, png_samples *out, hz_error *err);
void png_samples_free(png_samples *s);

#endif
