/* Warps from the unit square [0,1)^2 to common domains, following pbrt-v4's
 * util/sampling.h (same names without the CamelCase, same conventions: +z is
 * "up" for hemispheres and cones). Each sampler that is not uniform over its
 * domain's measure has a matching _pdf. Pure functions: no state, no tables. */
#ifndef HAZE_CORE_SAMPLING_H
#define HAZE_CORE_SAMPLING_H

#include <stdbool.h>

#include "core/vec.h"

/* Shirley-Chiu concentric mapping onto the unit disk (pdf 1/pi by area). It keeps
 * strata compact, which is why the lens uses it rather than the polar map. */
vec2 sample_uniform_disk_concentric(vec2 u);
/* r = sqrt(u0), phi = 2 pi u1 (pdf 1/pi by area). */
vec2 sample_uniform_disk_polar(vec2 u);

/* Uniform by area over the regular polygon with `n` >= 3 vertices inscribed in the
 * unit circle, the first vertex at angle `rotation` (radians) from +x. The pdf is
 * 1 / sample_regular_polygon_area(n). */
vec2 sample_regular_polygon(int n, double rotation, vec2 u);
double sample_regular_polygon_area(int n);
/* True when p lies inside (or on, within `eps`) that polygon. */
bool regular_polygon_contains(int n, double rotation, vec2 p, double eps);

/* Uniform over the triangle's area: barycentrics (b0, b1), b2 = 1 - b0 - b1
 * (pbrt-v4's SampleUniformTriangle). */
vec2 sample_uniform_triangle(vec2 u);

vec3 sample_uniform_sphere(vec2 u);
static inline double uniform_sphere_pdf(void) { return 1.0 / (4.0 * HZ_PI); }
vec3 sample_uniform_hemisphere(vec2 u);
static inline double uniform_hemisphere_pdf(void) { return 1.0 / (2.0 * HZ_PI); }
/* Malley's method: pdf = cos(theta) / pi. */
vec3 sample_cosine_hemisphere(vec2 u);
static inline double cosine_hemisphere_pdf(double cos_theta) { return cos_theta * HZ_INV_PI; }
/* Uniform over the cone of directions around +z with cos(theta) >= cos_max. */
vec3 sample_uniform_cone(vec2 u, double cos_max);
static inline double uniform_cone_pdf(double cos_max)
{
    return 1.0 / (2.0 * HZ_PI * (1.0 - cos_max));
}

/* Exponential distance with rate a (pdf a e^{-a x}); u in [0,1). */
double sample_exponential(double u, double a);

/* Clarberg's equal-area mapping between the unit square and the unit
 * sphere, as pbrt-v4 (the square's centre is +z, its corners -z). */
vec3 equal_area_square_to_sphere(vec2 p);
vec2 equal_area_sphere_to_square(vec3 d);
/* A point outside the unit square folded back in, as the octahedral map
 * continues across its edges (pbrt-v4's WrapEqualAreaSquare; within one
 * square's width of it). */
vec2 equal_area_wrap(vec2 p);

#endif
