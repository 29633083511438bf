/* The thin lens's aperture and haze's physical-lens parameters (an extension
 * of pbrt-v4): a focal length in millimetres and an f-number describe a lens
 * in scene units of metres. */
#ifndef HAZE_CAMERA_LENS_H
#define HAZE_CAMERA_LENS_H

#include "core/vec.h"

/* A point on the aperture of circumradius `radius` from u in [0,1)^2, uniform by
 * area: the concentric disk when blades == 0 (bit-identical to pbrt-v4), else
 * the regular `blades`-gon whose first vertex is at `rotation` radians. */
vec2 lens_sample_aperture(double radius, int blades, double rotation, vec2 u);

/* Full field of view in degrees across the frame's shorter axis, for a sensor
 * `sensor_width_mm` wide along the longer axis and frame aspect ratio `frame`
 * (x over y): 2 atan((sensor_short / 2) / focal_length). */
double lens_fov_from_focal_length(double focal_length_mm, double sensor_width_mm, double frame);
/* Aperture radius in metres: (focal_length / 1000) / (2 fstop). */
double lens_radius_from_fstop(double focal_length_mm, double fstop);

#endif
