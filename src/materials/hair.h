/* pbrt-v4's HairBxDF (d'Eon et al.'s and Chiang et al.'s hair model, as
 * pbrt-v4 implements it): a dielectric cylinder with an absorbing interior,
 * scattering in lobes p = 0 (reflection), 1 (transmission), 2 (one internal
 * reflection) and the rest summed; longitudinal M_p (roughness beta_m),
 * azimuthal N_p (trimmed logistic, roughness beta_n), attenuation A_p, and
 * cuticle scales tilting the lobes by alpha. Directions are in the hair's
 * frame: x along the hair, z the surface normal; h in [-1, 1] is the offset
 * across the hair where the ray hit it. Its colours are RGB or, in spectral
 * rendering, the four wavelengths' lanes (`lanes`, which the lobes' sampling
 * probabilities average over). */
#ifndef HAZE_MATERIALS_HAIR_H
#define HAZE_MATERIALS_HAIR_H

#include "core/vec.h"
#include "materials/bxdfs.h"

enum { HAIR_P_MAX = 3 };

typedef struct {
    double h, eta;
    rgb sigma_a;
    double v[HAIR_P_MAX + 1]; /* longitudinal variances */
    double s;                 /* azimuthal logistic scale */
    double sin2k_alpha[HAIR_P_MAX], cos2k_alpha[HAIR_P_MAX];
    int lanes; /* 3: RGB (hair_make's), WAVELENGTH_LANES: spectral */
} hair_bxdf;

/* beta_m and beta_n in [0.01, 1] (clamped, as pbrt-v4's material does),
 * alpha in degrees. */
hair_bxdf hair_make(double h, double eta, rgb sigma_a, double beta_m, double beta_n,
                    double alpha_deg);
rgb hair_f(const hair_bxdf *b, vec3 wo, vec3 wi);
double hair_pdf(const hair_bxdf *b, vec3 wo, vec3 wi);
bool hair_sample(const hair_bxdf *b, vec3 wo, double uc, vec2 u, bsdf_sample *out);

/* sigma_a of eumelanin and pheomelanin concentrations (pbrt-v4's RGB
 * coefficients), and of a desired reflectance `c` (per channel, in
 * [0, 1]) at azimuthal roughness beta_n (Chiang et al.'s fit). */
rgb hair_sigma_a_from_concentration(double eumelanin, double pheomelanin);
rgb hair_sigma_a_from_reflectance(rgb c, double beta_n);

#endif
