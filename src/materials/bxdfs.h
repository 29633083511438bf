/* pbrt-v4's BxDFs in the shading frame (z along the shading normal): diffuse,
 * diffuse transmission, conductor, dielectric, thin dielectric, each with
 * pbrt-v4's sampling restricted to reflection or transmission (the layered
 * BxDF needs both halves) and its transport mode (radiance scales refraction
 * by 1/eta^2, importance does not). materials/bsdf.h dispatches to these in
 * render space. */
#ifndef HAZE_MATERIALS_BXDFS_H
#define HAZE_MATERIALS_BXDFS_H

#include <stdbool.h>

#include "core/vec.h"
#include "materials/microfacet.h"

typedef enum { BXDF_REFLECTION = 1, BXDF_TRANSMISSION = 2, BXDF_ALL = 3 } bxdf_flags;

typedef struct {
    vec3 wi;
    rgb f;
    double pdf;
    bool specular;
    bool transmission;
    /* The pdf is only proportional to the density (a layered BxDF's random
     * walk): MIS uses bsdf_pdf instead (pbrt-v4's pdfIsProportional). */
    bool pdf_proportional;
    /* The relative index of refraction the sample crossed (pbrt-v4's
     * BSDFSample::eta): a dielectric's transmission, eta entering and 1 / eta
     * leaving; 1 for every other sample. A radiance transmission is divided
     * by its square, which volpath's roulette takes back out. */
    double eta;
} bsdf_sample;

static inline bool same_hemisphere(vec3 a, vec3 b) { return a.z * b.z > 0.0; }

/* Lambertian reflection of r, on wo's side. */
rgb bxdf_diffuse_f(rgb r, vec3 wo, vec3 wi);
double bxdf_diffuse_pdf(vec3 wo, vec3 wi, bxdf_flags flags);
bool bxdf_diffuse_sample(rgb r, vec3 wo, vec2 u, bxdf_flags flags, bsdf_sample *out);

/* A conductor of complex index eta + i k per channel (reflection only; wo
 * above the surface: callers flip two-sided lobes). */
bool bxdf_conductor_smooth(tr_distribution d);
rgb bxdf_conductor_f(tr_distribution d, rgb eta, rgb k, vec3 wo, vec3 wi);
double bxdf_conductor_pdf(tr_distribution d, vec3 wo, vec3 wi, bxdf_flags flags);
bool bxdf_conductor_sample(tr_distribution d, rgb eta, rgb k, vec3 wo, vec2 u, bxdf_flags flags,
                           bsdf_sample *out);

/* A dielectric interface of relative index eta (inside, below z = 0, over
 * outside). */
bool bxdf_dielectric_smooth(tr_distribution d, double eta);
rgb bxdf_dielectric_f(tr_distribution d, double eta, vec3 wo, vec3 wi, bool radiance);
double bxdf_dielectric_pdf(tr_distribution d, double eta, vec3 wo, vec3 wi, bxdf_flags flags);
bool bxdf_dielectric_sample(tr_distribution d, double eta, vec3 wo, double uc, vec2 u,
                            bxdf_flags flags, bool radiance, bsdf_sample *out);

/* A thin dielectric sheet (delta lobes only). */
bool bxdf_thin_sample(double eta, vec3 wo, double uc, bsdf_sample *out);

/* Diffuse reflection r and transmission t, the lobe by its largest channel. */
rgb bxdf_dt_f(rgb r, rgb t, vec3 wo, vec3 wi);
double bxdf_dt_pdf(rgb r, rgb t, vec3 wo, vec3 wi);
bool bxdf_dt_sample(rgb r, rgb t, vec3 wo, double uc, vec2 u, bsdf_sample *out);

#endif
