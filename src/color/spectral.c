#include "color/spectral.h"

#include "color/rgb_spectrum.h"


spectral_ctx spectral_ctx_make(const rgb2spec_table *table, double u)
{
    spectral_ctx sp = {table, wavelengths_sample_visible(u), {0}};
    for (int i = 0; i < WAVELENGTH_LANES; ++i)
        sp.illuminant[i] = rgb_spectrum_illuminant(table, sp.wl.lambda[i]);
    return sp;
}

static double clamp_unit(double v) { return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v); }

spectral_color spectral_prepare(const rgb2spec_table *t, rgb c, spectral_use use)
{
    spectral_color out = {true, use, 1.0, {0.0, 0.0, 0.0}};
    if (use == SPECTRAL_ALBEDO) {
        out.poly = sigmoid_poly_from_rgb(t, c);
        if (c.r == c.g && c.g == c.b) { /* flat: exactly the grey */
            out.poly = (sigmoid_poly){0.0, 0.0, 0.0};
            out.scale = 2.0 * clamp_unit(c.r);
        }
        return out;
    }
    rgb_unbounded_spectrum u = rgb_unbounded_spectrum_from_rgb(t, c);
    out.scale = u.scale;
    out.poly = u.poly;
    return out;
}

rgb spectral_eval(const spectral_ctx *sp, const spectral_color *c)
{
    double v[WAVELENGTH_LANES];
    for (int i = 0; i < WAVELENGTH_LANES; ++i) {
        v[i] = c->scale == 0.0 ? 0.0 : c->scale * sigmoid_poly_eval(c->poly, sp->wl.lambda[i]);
        if (c->use == SPECTRAL_ILLUMINANT)
            v[i] *= sp->illuminant[i];
    }
    return wavelengths_lanes(v);
}

rgb spectral_from_rgb(const spectral_ctx *sp, rgb c, spectral_use use)
{
    double v[WAVELENGTH_LANES];
    const double *l = sp->wl.lambda;
    switch (use) {
    case SPECTRAL_ALBEDO: {
        if (c.r == c.g && c.g == c.b) /* a grey reflectance is flat */
            return rgb_grey(c.r < 0.0 ? 0.0 : (c.r > 1.0 ? 1.0 : c.r));
        rgb_albedo_spectrum s = rgb_albedo_spectrum_from_rgb(sp->table, c);
        for (int i = 0; i < WAVELENGTH_LANES; ++i)
            v[i] = rgb_albedo_spectrum_eval(s, l[i]);
        break;
    }
    case SPECTRAL_UNBOUNDED: {
        if (c.r == c.g && c.g == c.b)
            return rgb_grey(c.r > 0.0 ? c.r : 0.0);
        rgb_unbounded_spectrum s = rgb_unbounded_spectrum_from_rgb(sp->table, c);
        for (int i = 0; i < WAVELENGTH_LANES; ++i)
            v[i] = rgb_unbounded_spectrum_eval(s, l[i]);
        break;
    }
    case SPECTRAL_ILLUMINANT: {
        rgb_unbounded_spectrum s = rgb_unbounded_spectrum_from_rgb(sp->table, c);
        for (int i = 0; i < WAVELENGTH_LANES; ++i)
            v[i] = s.scale == 0.0
                       ? 0.0
                       : rgb_unbounded_spectrum_eval(s, l[i]) * sp->illuminant[i];
        break;
    }
    }
    return wavelengths_lanes(v);
}

rgb spectral_from_value(const spectral_ctx *sp, const spectrum_value *s)
{
    if (s->kind == SPECTRUM_VALUE_RGB) {
        spectral_use use = s->use == SPECTRUM_USE_ALBEDO      ? SPECTRAL_ALBEDO
                           : s->use == SPECTRUM_USE_UNBOUNDED ? SPECTRAL_UNBOUNDED
                                                              : SPECTRAL_ILLUMINANT;
        return spectral_from_rgb(sp, s->rgb, use);
    }
    const double *l = sp->wl.lambda;
    double v[WAVELENGTH_LANES];
    for (int i = 0; i < WAVELENGTH_LANES; ++i)
        v[i] = spectrum_value_eval(s, l[i]);
    return wavelengths_lanes(v);
}

rgb spectral_to_rgb(const spectral_ctx *sp, rgb L)
{
    return rgb_spectrum_rgb_from_xyz(sp->table, wavelengths_xyz(&sp->wl, L));
}
