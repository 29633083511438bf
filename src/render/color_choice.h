/* --color auto (docs/spectral.md): whether a scene renders spectrally. RGB
 * rendering multiplies colours channel by channel; where the scene's colours
 * make that measurably wrong, paths carry wavelengths instead:
 *   - a medium whose coefficients differ between channels (its transmittance
 *     is exp(-sigma(lambda) d), not exp(-sigma_rgb d));
 *   - a material whose colour enters nonlinearly (metals' Fresnel term,
 *     coatings, hair, measured BRDFs: material_is_spectrally_nonlinear);
 *   - a product of two of the scene's colours (a light on a reflectance, a
 *     reflectance on a reflectance: one bounce, or two) whose RGB differs
 *     from its spectral value by more than COLOR_CHOICE_TOLERANCE of its
 *     largest channel (spectral_product_error). Greys and near-greys never
 *     trip it; saturated colours that light or reflect each other do.
 * Only volpath renders spectrally; the caller decides that. */
#ifndef HAZE_RENDER_COLOR_CHOICE_H
#define HAZE_RENDER_COLOR_CHOICE_H

#include <stdbool.h>
#include <stddef.h>

#include "color/spectral.h"
#include "core/error.h"
#include "lights/lights.h"
#include "materials/material.h"
#include "media/medium.h"

#define COLOR_CHOICE_TOLERANCE 0.01

typedef struct {
    bool spectral;
    const char *why;    /* what decided it (NULL: nothing, RGB) */
    double worst_error; /* the largest product error met (spectral_product_error) */
} color_choice;

typedef struct {
    const material *materials;
    size_t material_count;
    const material *default_material;
    const light *lights;
    size_t light_count;
    const medium *media;
    size_t medium_count;
} color_choice_scene;

/* The choice for scene s. The RGB -> spectrum tables are loaded only when
 * the scene has a colour that is not grey; when they cannot be, the choice
 * is RGB and err says why (err->message empty otherwise). */
color_choice color_choice_auto(const color_choice_scene *s, hz_error *err);

#endif
