/* Equiangular sampling (Kulla & Fajardo 2012) of s in [lo, hi) on the ray
 * o + s w for a light at c: pdf proportional to 1 / |x(s) - c|^2 there, 0
 * elsewhere. A point light's radiance falls as 1 / |x - c|^2, so light
 * scattered in a medium sampled this way has no singularity where the ray
 * passes near the light (distance sampling's estimate there has unbounded
 * variance). */
#ifndef HAZE_INTEGRATOR_EQUIANGULAR_H
#define HAZE_INTEGRATOR_EQUIANGULAR_H

#include <stdbool.h>

#include "core/vec.h"
#include "lights/lights.h"

typedef struct {
    double lo, hi, delta, D, theta_a, theta_b;
    bool valid;
} equiangular;

equiangular equiangular_make(vec3 o, vec3 w, double lo, double hi, vec3 c);
double equiangular_sample(const equiangular *e, double u);
/* 0 outside [lo, hi] and for an invalid e. */
double equiangular_pdf(const equiangular *e, double s);
/* Toward a light with a position (point, spot: the part of the ray inside
 * its cone), over [0, len) of o + s w; invalid (valid false) for other
 * lights or a ray that misses the cone. */
equiangular light_equiangular(const light *l, vec3 o, vec3 w, double len);

#endif
