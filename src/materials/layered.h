/* pbrt-v4's LayeredBxDF as its coated materials use it (two-sided): a
 * dielectric coating over a diffuse or conductor base, with an optional
 * scattering medium of albedo and g between them, `thickness` apart in
 * units of the medium's mean free path. f, pdf and sampling are stochastic
 * estimates by random walks between the two interfaces (pbrt-v4's
 * algorithm; the walks of f and pdf take their random numbers from a hash
 * of the directions, so they are deterministic functions of them). Shading
 * frame: z along the shading normal. */
#ifndef HAZE_MATERIALS_LAYERED_H
#define HAZE_MATERIALS_LAYERED_H

#include <stdbool.h>

#include "materials/bxdfs.h"

typedef struct {
    double eta;              /* the coating's index */
    tr_distribution top;     /* the coating's roughness */
    bool conductor;          /* base: conductor, else diffuse */
    rgb reflectance;         /* diffuse base */
    rgb eta_rgb, k;          /* conductor base, relative to the coating (divided by eta) */
    tr_distribution bottom;  /* conductor base roughness */
    double thickness;
    rgb albedo;              /* of the medium between the layers (0: none) */
    double g;
    int max_depth, n_samples;
} layered;

bool layered_is_non_specular(const layered *l);
rgb layered_f(const layered *l, vec3 wo, vec3 wi);
double layered_pdf(const layered *l, vec3 wo, vec3 wi);
bool layered_sample(const layered *l, vec3 wo, double uc, vec2 u, bsdf_sample *out);

#endif
