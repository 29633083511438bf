/* Film sensors: table lookup and Catmull-Rom interpolation in mired. */
#include "film/sensor.h"

#include <string.h>

/* Catmull-Rom through p[i-1..i+2] at t in [0, 1] between p[i] and p[i+1];
 * beyond the ends of a piece the missing point comes from the quadratic
 * through the three nearest nodes. */
static double catmull_rom(const double *p, int n, int i, double t)
{
    double p1 = p[i], p2 = p[i + 1];
    double p0 = i > 0 ? p[i - 1] : 3.0 * p1 - 3.0 * p2 + p[i + 2];
    double p3 = i + 2 < n ? p[i + 2] : 3.0 * p2 - 3.0 * p1 + p[i - 1];
    double t2 = t * t, t3 = t2 * t;
    return 0.5 * (2.0 * p1 + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2 +
                  (3.0 * p1 - p0 - 3.0 * p2 + p3) * t3);
}

static void output_at(const sensor_table_entry *e, double kelvin, double out[9])
{
    double m = 1e6 / kelvin;
    /* pbrt-v4's illuminant is a blackbody below 4000 K (correlated colour
     * temperature), so the pieces split there and at its 7000 K kink. */
    int seg = m <= sensor_mired_bounds[1] ? 0 : m <= sensor_mired_bounds[2] ? 1 : 2;
    int first = 0;
    for (int s = 0; s < seg; s++)
        first += sensor_segment_nodes[s];
    int n = sensor_segment_nodes[seg];
    double a = sensor_mired_bounds[seg], b = sensor_mired_bounds[seg + 1];
    double u = (m - a) / (b - a) * (n - 1);
    u = u < 0.0 ? 0.0 : u > n - 1 ? n - 1 : u;
    int i = (int)u < n - 2 ? (int)u : n - 2;
    double column[SENSOR_TABLE_NODES];
    for (int k = 0; k < 9; k++) {
        for (int j = 0; j < n; j++)
            column[j] = e->output_from_sensor[first + j][k];
        out[k] = catmull_rom(column, n, i, u - i);
    }
}

bool sensor_lookup(const char *name, double kelvin, film_sensor *out)
{
    for (int i = 0; i < SENSOR_TABLE_COUNT; i++) {
        const sensor_table_entry *e = &sensor_table[i];
        if (strcmp(e->name, name) != 0)
            continue;
        bool xyz = i == 0; /* "cie1931" */
        memset(out, 0, sizeof *out);
        if (xyz && kelvin == 0.0)
            return true; /* pbrt-v4: no white balance, the identity */
        out->active = true;
        memcpy(out->sensor_from_render, e->sensor_from_render, sizeof out->sensor_from_render);
        output_at(e, kelvin == 0.0 ? 6500.0 : kelvin, out->output_from_sensor);
        out->curves = e->has_curves ? e->curves : NULL;
        return true;
    }
    return false;
}

rgb sensor_response(const film_sensor *s, double lambda)
{
    double x = (lambda - SENSOR_CURVE_MIN) / SENSOR_CURVE_STEP;
    if (!(x >= 0.0 && x <= SENSOR_CURVE_NODES - 1))
        return rgb_grey(0.0);
    int i = (int)x;
    if (i >= SENSOR_CURVE_NODES - 1)
        i = SENSOR_CURVE_NODES - 2;
    double t = x - i, v[3];
    for (int c = 0; c < 3; ++c)
        v[c] = (1.0 - t) * s->curves[c][i] + t * s->curves[c][i + 1];
    return rgb_make(v[0], v[1], v[2]);
}

const char *sensor_names(void)
{
    return "cie1931, canon_eos_100d, canon_eos_1dx_mkii, canon_eos_200d, canon_eos_200d_mkii, "
           "canon_eos_5d, canon_eos_5d_mkii, canon_eos_5d_mkiii, canon_eos_5d_mkiv, canon_eos_5ds, "
           "canon_eos_m, hasselblad_l1d_20c, nikon_d810, nikon_d850, sony_ilce_6400, "
           "sony_ilce_7m3, sony_ilce_7rm3, sony_ilce_9";
}
