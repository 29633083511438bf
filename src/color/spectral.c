#include "color/spectral.h"

#include "color/rgb_spectrum.h"

rgb spectral_from_rgb(const spectral_ctx *sp, rgb c, spectral_use use)
{
    double v[WAVELENGTH_LANES];
    const double *l = sp->wl.lambda;
    switch (use) {
    case SPECTRAL_ALBEDO: {
        if (c.r == c.g && c.g == c.b) /* a grey reflectance is flat */
            return rgb_grey(c.r < 0.0 ? 0.0 : (c.r > 1.0 ? 1.0 : c.r));
        rgb_albedo_spectrum s = rgb_albedo_spectrum_from_rgb(COLOR_SPACE_SRGB, c);
        for (int i = 0; i < WAVELENGTH_LANES; ++i)
            v[i] = rgb_albedo_spectrum_eval(s, l[i]);
        break;
    }
    case SPECTRAL_UNBOUNDED: {
        if (c.r == c.g && c.g == c.b)
            return rgb_grey(c.r > 0.0 ? c.r : 0.0);
        rgb_unbounded_spectrum s = rgb_unbounded_spectrum_from_rgb(COLOR_SPACE_SRGB, c);
        for (int i = 0; i < WAVELENGTH_LANES; ++i)
            v[i] = rgb_unbounded_spectrum_eval(s, l[i]);
        break;
    }
    case SPECTRAL_ILLUMINANT: {
        rgb_illuminant_spectrum s = rgb_illuminant_spectrum_from_rgb(COLOR_SPACE_SRGB, c);
        for (int i = 0; i < WAVELENGTH_LANES; ++i)
            v[i] = rgb_illuminant_spectrum_eval(s, l[i]);
        break;
    }
    }
    return rgb_make(v[0], v[1], v[2]);
}

rgb spectral_to_rgb(const spectral_ctx *sp, rgb L)
{
    (void)sp;
    return rgb_spectrum_rgb_from_xyz(COLOR_SPACE_SRGB, wavelengths_xyz(&sp->wl, L));
}
