/* Trowbridge-Reitz (GGX) microfacets and Fresnel reflectance, as pbrt-v4
 * defines them: the distribution D, Smith's masking Lambda/G1/G, the
 * distribution of visible normals and its sampling (Heitz 2018), and the
 * dielectric and conductor Fresnel equations. Directions are in the shading
 * frame: z along the shading normal. */
#ifndef HAZE_MATERIALS_MICROFACET_H
#define HAZE_MATERIALS_MICROFACET_H

#include <stdbool.h>

#include "core/vec.h"

typedef struct {
    double alpha_x, alpha_y;
} tr_distribution;

/* pbrt-v4's roughness to alpha map (remaproughness true): sqrt(roughness). */
double tr_roughness_to_alpha(double roughness);
/* Below this alpha the surface is treated as perfectly smooth (pbrt-v4). */
static inline bool tr_effectively_smooth(tr_distribution d)
{
    return (d.alpha_x > d.alpha_y ? d.alpha_x : d.alpha_y) < 1e-3;
}
/* pbrt-v4's Regularize: alpha < 0.3 becomes clamp(2 alpha, 0.1, 0.3). */
void tr_regularize(tr_distribution *d);

double tr_d(tr_distribution d, vec3 wm);
double tr_lambda(tr_distribution d, vec3 w);
double tr_g1(tr_distribution d, vec3 w);
double tr_g(tr_distribution d, vec3 wo, vec3 wi);
/* The density of visible normals seen from w: G1(w) / |cos w| D(wm) |w.wm|. */
double tr_d_visible(tr_distribution d, vec3 w, vec3 wm);
/* A visible normal from w, distributed as tr_d_visible. */
vec3 tr_sample_wm(tr_distribution d, vec3 w, vec2 u);

/* Unpolarised Fresnel reflectance of a dielectric interface with relative
 * index eta (inside over outside) at cos_i (negative: from inside). */
double fresnel_dielectric(double cos_i, double eta);
/* The same for a conductor of complex index eta + i k, per channel. */
rgb fresnel_complex(double cos_i, rgb eta, rgb k);

/* Refraction of wi about n (pbrt-v4's Refract): false at total internal
 * reflection; *etap is the relative index actually used (eta, or 1/eta when
 * wi is below n). */
bool refract_dir(vec3 wi, vec3 n, double eta, double *etap, vec3 *wt);

/* The mirror direction of wo about n. */
static inline vec3 reflect_dir(vec3 wo, vec3 n)
{
    return v3_sub(v3_scale(n, 2.0 * v3_dot(wo, n)), wo);
}

#endif
