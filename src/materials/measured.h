/* pbrt-v4's MeasuredBxDF in the shading frame (z along the shading normal):
 * reflection only, on wo's side (a wo below the surface flips both
 * directions, as pbrt-v4). With wm the half vector of wo and wi,
 *
 *   f(wo, wi) = R(u) D(wm) / (4 sigma(wo) cos theta_i)
 *
 * where u is the point of the sample square that the visible-normal warp
 * of wo maps to wm, R the tabulated reflectance (RGB here), D the NDF and
 * sigma its projected area; a file whose "jacobian" flag is 0 holds
 * R D / (4 sigma) itself (Mitsuba's reading; pbrt-v4 ignores the flag).
 * Sampling draws u from the luminance warp, maps it through the visible
 * normals to wm and reflects wo about it. Data: materials/measured_data.h. */
#ifndef HAZE_MATERIALS_MEASURED_H
#define HAZE_MATERIALS_MEASURED_H

#include <stdbool.h>

#include "core/vec.h"
#include "materials/bxdfs.h"
#include "materials/measured_data.h"

rgb bxdf_measured_f(const measured_brdf *m, vec3 wo, vec3 wi);
double bxdf_measured_pdf(const measured_brdf *m, vec3 wo, vec3 wi);
bool bxdf_measured_sample(const measured_brdf *m, vec3 wo, vec2 u, bsdf_sample *out);

#endif
