/* A measured BRDF as RGL publishes them (Dupuy and Jakob 2018, "An Adaptive
 * Parameterization for Efficient Material Acquisition and Rendering"):
 * pbrt-v4's MeasuredBxDFData, read from a ".bsdf" tensor file
 * (materials/tensor_file.h) whose fields are
 *
 *   theta_i, phi_i  float32 [T], [P]   the incident elevations and azimuths
 *                                      (radians) the tables are given at
 *   ndf             float32 [Ny, Nx]   the microfacet normal distribution D
 *   sigma           float32 [Ny, Nx]   its projected area seen from wo
 *   vndf            float32 [P, T, Ny', Nx']  the visible normals: the warp
 *                                      from the sample square to normals
 *   luminance       float32 [P, T, N, N]  the reflectance's luminance over
 *                                      the sample square (a second warp)
 *   spectra         float32 [P, T, L, N, N]  the reflectance over the sample
 *                                      square at each wavelength
 *   wavelengths     float32 [L]        nanometres, increasing
 *   description     uint8 [n]          text
 *   jacobian        uint8 [1]          1: spectra hold f cos / (D / 4 sigma)
 *
 * The 2D tables are over (x, y) = (sqrt(2 theta / pi), phi / 2 pi + 1/2); a
 * table with P <= 2 is isotropic and its normals' azimuths are relative to
 * wo's. haze renders in RGB: the spectra are reduced to linear sRGB when
 * read, each wavelength's table weighted as haze weighs a reflectance
 * spectrum (scene/spectrum.h), the spectrum held at its end values outside
 * the tabulated wavelengths (where pbrt-v4's lookup clamps). */
#ifndef HAZE_MATERIALS_MEASURED_DATA_H
#define HAZE_MATERIALS_MEASURED_DATA_H

#include <stdbool.h>

#include "core/error.h"
#include "materials/tensor_file.h"
#include "materials/warp2d.h"

typedef struct measured_brdf {
    bool isotropic;
    bool jacobian;
    warp2d ndf, sigma;      /* no parameters */
    warp2d vndf, luminance; /* sampling warps over (phi_i, theta_i) */
    warp2d rgb[3];          /* the reflectance per channel, over (phi_i, theta_i) */
} measured_brdf;

/* The BRDF of a parsed tensor file; every field's type, shape and values are
 * checked (the message is the reason only). */
hz_status measured_brdf_from_tensor(const tensor_file *t, measured_brdf **out, hz_error *err);
/* Reads the file at `path`; the message starts with the path. */
hz_status measured_brdf_read(const char *path, measured_brdf **out, hz_error *err);
void measured_brdf_destroy(measured_brdf *m);

/* The BRDFs of a scene, each file read once (as pbrt-v4). */
typedef struct measured_cache measured_cache;
hz_status measured_cache_create(measured_cache **out, hz_error *err);
void measured_cache_destroy(measured_cache *c);
/* The BRDF of the file at `path`, read now or before; the message starts
 * with the path. */
hz_status measured_cache_get(measured_cache *c, const char *path, const measured_brdf **out,
                             hz_error *err);

#endif
