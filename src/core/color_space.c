#include "core/color_space.h"

#include <assert.h>
#include <ctype.h>
#include <string.h>

typedef struct {
    const char *name;
    double xy[8]; /* r, g, b, white */
} space_def;

/* Primaries as pbrt-v4 defines them; white points: the CIE 1931 xy of D65
 * and of the ACES D60 illuminant. */
static const space_def spaces[COLOR_SPACE_COUNT] = {
    [COLOR_SPACE_SRGB] = {"srgb", {0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290}},
    [COLOR_SPACE_REC2020] = {"rec2020", {0.708, 0.292, 0.170, 0.797, 0.131, 0.046, 0.3127, 0.3290}},
    [COLOR_SPACE_ACES2065_1] = {"aces2065-1",
                                {0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767}},
    [COLOR_SPACE_DCI_P3] = {"dci-p3", {0.680, 0.320, 0.265, 0.690, 0.150, 0.060, 0.3127, 0.3290}},
};

bool color_space_lookup(const char *name, color_space *out)
{
    for (int i = 0; i < COLOR_SPACE_COUNT; ++i) {
        const char *a = name, *b = spaces[i].name;
        while (*a && *b && tolower((unsigned char)*a) == *b) {
            ++a;
            ++b;
        }
        if (*a == '\0' && *b == '\0') {
            *out = (color_space)i;
            return true;
        }
    }
    return false;
}

const char *color_space_name(color_space cs)
{
    assert(cs >= 0 && cs < COLOR_SPACE_COUNT);
    return spaces[cs].name;
}

const char *color_space_names(void) { return "srgb, rec2020, aces2065-1, dci-p3"; }

static void invert3(const double a[9], double out[9])
{
    double c0 = a[4] * a[8] - a[5] * a[7], c1 = a[5] * a[6] - a[3] * a[8],
           c2 = a[3] * a[7] - a[4] * a[6];
    double det = a[0] * c0 + a[1] * c1 + a[2] * c2;
    assert(det != 0.0);
    double k = 1.0 / det;
    out[0] = c0 * k;
    out[1] = (a[2] * a[7] - a[1] * a[8]) * k;
    out[2] = (a[1] * a[5] - a[2] * a[4]) * k;
    out[3] = c1 * k;
    out[4] = (a[0] * a[8] - a[2] * a[6]) * k;
    out[5] = (a[2] * a[3] - a[0] * a[5]) * k;
    out[6] = c2 * k;
    out[7] = (a[1] * a[6] - a[0] * a[7]) * k;
    out[8] = (a[0] * a[4] - a[1] * a[3]) * k;
}

static void multiply3(const double a[9], const double b[9], double out[9])
{
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            out[r * 3 + c] = a[r * 3] * b[c] + a[r * 3 + 1] * b[3 + c] + a[r * 3 + 2] * b[6 + c];
}

void color_space_xyz_from_rgb_white(color_space cs, const double w[3], double m[9])
{
    assert(cs >= 0 && cs < COLOR_SPACE_COUNT);
    const double *xy = spaces[cs].xy;
    double p[9];
    for (int i = 0; i < 3; ++i) { /* column i: primary i at Y = 1 */
        double x = xy[2 * i], y = xy[2 * i + 1];
        p[i] = x / y;
        p[3 + i] = 1.0;
        p[6 + i] = (1.0 - x - y) / y;
    }
    double inv[9];
    invert3(p, inv);
    for (int i = 0; i < 3; ++i) {
        double s = inv[i * 3] * w[0] + inv[i * 3 + 1] * w[1] + inv[i * 3 + 2] * w[2];
        for (int r = 0; r < 3; ++r)
            m[r * 3 + i] = p[r * 3 + i] * s;
    }
}

void color_space_rgb_from_xyz_white(color_space cs, const double w[3], double m[9])
{
    double a[9];
    color_space_xyz_from_rgb_white(cs, w, a);
    invert3(a, m);
}

/* XYZ from RGB with the space's white point at Y = 1. */
static void xyz_from_rgb(color_space cs, double m[9])
{
    double wx = spaces[cs].xy[6], wy = spaces[cs].xy[7];
    double w[3] = {wx / wy, 1.0, (1.0 - wx - wy) / wy};
    color_space_xyz_from_rgb_white(cs, w, m);
}

void color_space_convert_matrix(color_space from, color_space to, double m[9])
{
    assert(from >= 0 && from < COLOR_SPACE_COUNT && to >= 0 && to < COLOR_SPACE_COUNT);
    if (from == to) {
        static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        memcpy(m, id, sizeof id);
        return;
    }
    double a[9], b[9], inv_b[9];
    xyz_from_rgb(from, a);
    xyz_from_rgb(to, b);
    invert3(b, inv_b);
    multiply3(inv_b, a, m);
}

void color_space_chromaticities(color_space cs, double xy[8])
{
    assert(cs >= 0 && cs < COLOR_SPACE_COUNT);
    memcpy(xy, spaces[cs].xy, sizeof spaces[cs].xy);
}
