/* pbrt-v4's Film "sensor" and "whitebalance": each sensor is two 3x3
 * matrices (tools/gen_sensor_table.py derives them from pbrt-v4's spectral
 * response curves). A radiance value in haze's linear sRGB becomes the
 * sensor's RGB (sensor_from_render; spectral rendering projects its
 * wavelengths on the camera's curves instead), which Film
 * "maxcomponentvalue" clamps as in pbrt-v4, then output RGB
 * (output_from_sensor, pbrt-v4's fitted XYZ-from-sensor matrix for the
 * white-balance temperature, then sRGB). */
#ifndef HAZE_FILM_SENSOR_H
#define HAZE_FILM_SENSOR_H

#include <stdbool.h>

#include "core/vec.h"

/* A camera's spectral response: pbrt-v4's curves, piecewise linear on nodes
 * every SENSOR_CURVE_STEP nm from SENSOR_CURVE_MIN, zero outside. */
#define SENSOR_CURVE_MIN 380.0
#define SENSOR_CURVE_STEP 10.0
#define SENSOR_CURVE_NODES 35

typedef struct {
    bool active;                 /* false: the identity ("cie1931" without white balance) */
    double sensor_from_render[9]; /* row-major */
    double output_from_sensor[9];
    /* A camera's response curves (r, g, b), for spectral rendering, which
     * projects a sample's wavelengths on them instead of using
     * sensor_from_render (sensor_response); NULL for "cie1931". */
    const double (*curves)[SENSOR_CURVE_NODES];
} film_sensor;

/* White-balance temperatures haze accepts (kelvin): the table's range. */
#define SENSOR_MIN_KELVIN 1000.0
#define SENSOR_MAX_KELVIN 50000.0

/* The sensor `name` ("cie1931" or one of pbrt-v4's cameras, e.g.
 * "nikon_d850") balanced for `kelvin` (0 = pbrt-v4's default: no balance for
 * "cie1931", 6500 K for a camera). False for an unknown name; `kelvin` must be
 * 0 or in [SENSOR_MIN_KELVIN, SENSOR_MAX_KELVIN]. */
bool sensor_lookup(const char *name, double kelvin, film_sensor *out);

/* The camera's response (r, g, b) at `lambda` nm; s->curves must be set. */
rgb sensor_response(const film_sensor *s, double lambda);

/* The names sensor_lookup knows, comma separated, for error messages. */
const char *sensor_names(void);

/* sensor_from_render and output_from_sensor of one sensor; out = m * v. */
static inline rgb sensor_apply(const double m[9], rgb v)
{
    return rgb_make(m[0] * v.r + m[1] * v.g + m[2] * v.b, m[3] * v.r + m[4] * v.g + m[5] * v.b,
                    m[6] * v.r + m[7] * v.g + m[8] * v.b);
}

/* The generated table (src/film/sensor_table.c). output_from_sensor is
 * tabulated at nodes evenly spaced in mired (1e6 / kelvin) on three pieces,
 * [bounds[i], bounds[i+1]] with segment_nodes[i] nodes each, concatenated. */
#define SENSOR_TABLE_COUNT 18
#define SENSOR_TABLE_NODES 41
typedef struct {
    const char *name;
    double sensor_from_render[9];
    bool has_curves;
    double curves[3][SENSOR_CURVE_NODES];
    double output_from_sensor[SENSOR_TABLE_NODES][9];
} sensor_table_entry;
extern const double sensor_mired_bounds[4];
extern const int sensor_segment_nodes[3];
extern const sensor_table_entry sensor_table[SENSOR_TABLE_COUNT];

#endif
