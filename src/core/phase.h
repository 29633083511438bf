/* The Henyey–Greenstein phase function, with pbrt-v4's conventions: both
 * directions point away from the scattering point (wo toward the viewer, wi
 * toward the light), so forward scattering (g > 0) peaks at dot(wo, wi) = -1.
 * Valid for -1 < g < 1; finite (if very peaked) up to |g| = 1 - 1e-5 and beyond. */
#ifndef HAZE_CORE_PHASE_H
#define HAZE_CORE_PHASE_H

#include "core/vec.h"

/* p(wo, wi) per steradian for cos_theta = dot(wo, wi); integrates to 1 over the
 * sphere of wi, and the mean of dot(-wo, wi) is g. */
double hg_phase(double cos_theta, double g);

/* Samples wi with density hg_phase(dot(wo, wi), g) (pbrt-v4's
 * SampleHenyeyGreenstein); `wo` must be unit; returns unit wi and its pdf. */
vec3 hg_sample(vec3 wo, double g, vec2 u, double *pdf);

#endif
