/* --color auto (docs/spectral.md): whether a scene renders spectrally. RGB
 * rendering multiplies colours channel by channel; where a scene's colours
 * make that wrong by more than noise, paths carry wavelengths instead:
 *   - a medium whose coefficients differ between channels (its transmittance
 *     is exp(-sigma(lambda) d), not exp(-sigma_rgb d));
 *   - a material whose colour enters nonlinearly (metals' Fresnel term,
 *     coatings, hair, measured BRDFs: material_is_spectrally_nonlinear).
 *   - under volpath, a dielectric whose index is a spectrum that varies (a
 *     named glass): only spectral rendering disperses light through it;
 *   - a Film with a camera sensor: its response is a spectral integral, which
 *     the RGB fit (film/sensor.h) misses by up to 27% on saturated lights
 *     (a (0.8, 0.1, 0.1) emitter's blue on nikon_d850; spectral: within 1%
 *     of pbrt-v4);
 *   - a Film "maxcomponentvalue": it clamps each sample's sensor RGB, which
 *     pbrt-v4 makes from four wavelengths; an RGB sample's spread differs,
 *     and so does what the clamp takes (the bathroom stand-in at 50: RGB
 *     7-25% above pbrt-v4, spectral within 0.3%).
 * Diffuse colours and coloured lights only scale each wavelength: their
 * products over bounces differ per pixel, but image means stay within 0.6%
 * of pbrt-v4's in RGB on saturated rooms (bench/results/spectral.md), where
 * spectral rendering costs 1.5x the time at equal error (2.4x there). */
#ifndef HAZE_RENDER_COLOR_CHOICE_H
#define HAZE_RENDER_COLOR_CHOICE_H

#include <stdbool.h>
#include <stddef.h>

#include "materials/material.h"
#include "media/medium.h"

typedef struct {
    bool spectral;
    const char *why; /* what decided it (NULL: RGB) */
} color_choice;

typedef struct {
    const material *materials;
    size_t material_count;
    const material *default_material;
    const medium *media;
    size_t medium_count;
    bool camera_sensor; /* the Film's sensor has response curves */
    bool clamped;       /* the Film's maxcomponentvalue is finite */
    bool volpath;       /* the integrator disperses (material.dispersive) */
} color_choice_scene;

color_choice color_choice_auto(const color_choice_scene *s);

#endif
