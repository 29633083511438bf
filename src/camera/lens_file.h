/* pbrt-v4's lens description files (RealisticCamera's "lensfile"): one lens
 * element interface per line, four numbers in millimetres and as given:
 * curvature radius (0 = the aperture stop), thickness to the next interface
 * toward the film, index of refraction behind the interface, aperture
 * diameter; `#` starts a comment. Rows are listed from the scene side to the
 * film side, as pbrt-v4's files are written. */
#ifndef HAZE_CAMERA_LENS_FILE_H
#define HAZE_CAMERA_LENS_FILE_H

#include "core/error.h"

#define LENS_FILE_MAX_ELEMENTS 64

typedef struct {
    double radius, thickness, eta, aperture; /* millimetres, eta unitless */
} lens_row;

typedef struct {
    int count;
    lens_row rows[LENS_FILE_MAX_ELEMENTS];
} lens_table;

/* Parses `text` (the contents of the file `name`, which messages name as
 * name:line:column). Refuses a row without exactly four numbers, a token that
 * is not a number, no rows, more than LENS_FILE_MAX_ELEMENTS rows, a
 * non-finite value, a negative thickness or index, and an aperture diameter
 * that is not > 0. */
hz_status lens_file_parse(const char *name, const char *text, lens_table *out, hz_error *err);
/* Reads and parses the file at `path`. */
hz_status lens_file_read(const char *path, lens_table *out, hz_error *err);

#endif
