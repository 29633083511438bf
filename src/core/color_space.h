/* pbrt-v4's RGB colour spaces (ColorSpace directive): sRGB (haze's working
 * space), Rec. 2020, ACES2065-1 and DCI-P3 (P3-D65), each by its primaries and
 * white point, and the 3x3 matrices between them (through XYZ, as pbrt-v4's
 * ConvertRGBColorSpace: no chromatic adaptation). */
#ifndef HAZE_CORE_COLOR_SPACE_H
#define HAZE_CORE_COLOR_SPACE_H

#include <stdbool.h>

typedef enum {
    COLOR_SPACE_SRGB = 0, /* the default: what haze renders in */
    COLOR_SPACE_REC2020,
    COLOR_SPACE_ACES2065_1,
    COLOR_SPACE_DCI_P3,
    COLOR_SPACE_COUNT
} color_space;

/* By pbrt-v4's name ("srgb", "rec2020", "aces2065-1", "dci-p3"; any case).
 * False for another name. */
bool color_space_lookup(const char *name, color_space *out);
const char *color_space_name(color_space cs);
/* "srgb, rec2020, aces2065-1, dci-p3", for messages. */
const char *color_space_names(void);
/* Row-major 3x3: RGB in `to` from RGB in `from`. */
void color_space_convert_matrix(color_space from, color_space to, double m[9]);
/* Row-major 3x3: XYZ from RGB for the primaries of `cs` and the white `w`
 * (XYZ): RGB (1,1,1) is w. color_space_convert_matrix uses the space's white
 * point at Y = 1; a spectral film uses the XYZ of the space's illuminant
 * spectrum (as pbrt-v4's RGBColorSpace). */
void color_space_xyz_from_rgb_white(color_space cs, const double w[3], double m[9]);
/* Its inverse. */
void color_space_rgb_from_xyz_white(color_space cs, const double w[3], double m[9]);
/* The primaries and white point as x, y pairs: red, green, blue, white
 * (OpenEXR's chromaticities). */
void color_space_chromaticities(color_space cs, double xy[8]);

#endif
