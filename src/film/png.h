/* 8-bit RGB PNG output through libpng, written atomically (temporary file in
 * the same directory, then rename). */
#ifndef HAZE_FILM_PNG_H
#define HAZE_FILM_PNG_H

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

#endif
