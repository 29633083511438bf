#include "camera/lens.h"

#include <math.h>

#include "core/sampling.h"

vec2 lens_sample_aperture(double radius, int blades, double rotation, vec2 u)
{
    vec2 p = blades >= 3 ? sample_regular_polygon(blades, rotation, u)
                         : sample_uniform_disk_concentric(u);
    return v2(radius * p.x, radius * p.y);
}

double lens_fov_from_focal_length(double focal_length_mm, double sensor_width_mm, double frame)
{
    double short_over_long = frame > 1.0 ? 1.0 / frame : frame;
    double sensor_short = sensor_width_mm * short_over_long;
    return 2.0 * atan(0.5 * sensor_short / focal_length_mm) * (180.0 / HZ_PI);
}

double lens_radius_from_fstop(double focal_length_mm, double fstop)
{
    return (focal_length_mm / 1000.0) / (2.0 * fstop);
}
