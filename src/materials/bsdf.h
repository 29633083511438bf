/* Surface scattering for path tracing: a BSDF at one hit, built from the hit's
 * material, evaluated and sampled in render space. A closed set of kinds
 * dispatched with a switch: diffuse, conductor, dielectric, thin dielectric,
 * diffuse transmission, the coated (layered) ones and measured ones: pbrt-v4's
 * BxDFs of the same names (materials/bxdfs.h, materials/layered.h), with Trowbridge-Reitz
 * microfacets for the rough ones (materials/microfacet.h).
 *
 * Conventions as pbrt-v4: wo and wi point away from the surface; f excludes
 * the cosine; pdfs are per solid angle; transmission is in radiance mode (a
 * ray refracting into a denser medium carries 1/eta^2 of the radiance). The
 * diffuse BSDF reflects on the side of wo relative to the shading normal
 * (pbrt-v4's DiffuseBxDF, two-sided); conductors reflect on both sides too;
 * a dielectric's inside is where the shading normal points away from. */
#ifndef HAZE_MATERIALS_BSDF_H
#define HAZE_MATERIALS_BSDF_H

#include <stdbool.h>

#include "core/vec.h"
#include "materials/bxdfs.h"
#include "materials/hair.h"
#include "materials/layered.h"
#include "materials/material.h"
#include "materials/measured.h"

typedef enum {
    BSDF_DIFFUSE,
    BSDF_CONDUCTOR,
    BSDF_DIELECTRIC,
    BSDF_THIN_DIELECTRIC,
    BSDF_DIFFUSE_TRANSMISSION,
    BSDF_COATED, /* coateddiffuse, coatedconductor: a layered BxDF */
    BSDF_HAIR,   /* pbrt-v4's HairBxDF, in the frame of the hair's dp/du */
    BSDF_MEASURED, /* pbrt-v4's MeasuredBxDF (materials/measured.h) */
} bsdf_kind;

typedef struct {
    bsdf_kind kind;
    vec3 n;           /* unit shading normal */
    vec3 s, t;        /* tangents: (s, t, n) is the shading frame */
    rgb reflectance;  /* diffuse, diffuse transmission */
    rgb transmittance; /* diffuse transmission */
    rgb eta_rgb, k;   /* conductor: complex index per channel */
    double eta;       /* dielectric, thin dielectric: inside over outside */
    tr_distribution distrib; /* conductor, dielectric */
    layered coat;            /* coated */
    hair_bxdf hair;          /* hair */
    const measured_brdf *measured; /* measured */
    /* measured, spectral rendering: the wavelengths its RGB values are
     * turned into (NULL: RGB; only measured BSDFs read it) */
    const spectral_ctx *spectral;
} bsdf;

/* The BSDF of a material at a hit with unit shading normal `ns`. False for a
 * material with no surface (interface) or one that scatters nothing (a black
 * diffuse reflectance): the path goes through, or ends. Hair also needs the
 * hit's dp/du (its frame: x along it, as pbrt-v4) and v (the offset across
 * the hair, h = 2 v - 1); the others ignore them. */
bool bsdf_from_material(const material *m, vec3 ns, vec3 dpdu, double v, bsdf *out);

/* True when the BSDF has a non-delta part that light sampling can reach. */
bool bsdf_is_non_specular(const bsdf *b);

rgb bsdf_f(const bsdf *b, vec3 wo, vec3 wi);
double bsdf_pdf(const bsdf *b, vec3 wo, vec3 wi);

/* Samples wi given wo with the 1D and 2D numbers `uc`, `u` (pbrt-v4's
 * Sample_f(wo, uc, u)). False when no direction was produced. */
bool bsdf_sample_f(const bsdf *b, vec3 wo, double uc, vec2 u, bsdf_sample *out);

/* pbrt-v4's BSDF::Regularize (volpath "regularize"): roughens near-specular
 * lobes after a non-specular bounce. Diffuse lobes are left as they are. */
void bsdf_regularize(bsdf *b);

#endif
