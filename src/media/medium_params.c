#include "media/medium_params.h"

#include <math.h>
#include <stdio.h>

#include "media/presets.h"

bool medium_rgb_is_finite(rgb c) { return isfinite(c.r) && isfinite(c.g) && isfinite(c.b); }

bool medium_transform_is_finite(const transform *t)
{
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (!isfinite(t->m.m[r][c]) || !isfinite(t->m_inv.m[r][c]))
                return false;
    return true;
}

const char *medium_entity_name(const medium_entity *e) { return e->name ? e->name : ""; }

/* A coefficient spectrum: finite and non-negative in every channel. */
static rgb read_sigma(param_list *pl, const char *name, spectrum_value *spec)
{
    *spec = params_spectrum(pl, name, SPECTRUM_USE_UNBOUNDED, rgb_grey(1.0));
    rgb s = spec->rgb;
    if (!medium_rgb_is_finite(s) || s.r < 0.0 || s.g < 0.0 || s.b < 0.0)
        params_reject(pl, name, "\"%s\" must be finite and non-negative, got (%g, %g, %g)", name,
                      s.r, s.g, s.b);
    return s;
}

/* pbrt-v4's named measured media (homogeneous only, as pbrt-v4): the preset
 * gives sigma_a and sigma_s, so those may not be given beside it. */
static void read_preset(param_list *pl, bool is_grid, rgb *sigma_a, rgb *sigma_s)
{
    *sigma_a = rgb_grey(1.0);
    *sigma_s = rgb_grey(1.0);
    const char *name = params_string(pl, "preset", "");
    if (is_grid) {
        params_reject(pl, "preset",
                      "\"preset\" names a homogeneous medium's coefficients (pbrt-v4 reads it "
                      "for \"homogeneous\" only)");
        return;
    }
    if (!medium_preset(name, sigma_a, sigma_s)) {
        params_reject(pl, "preset",
                      "no preset \"%s\" (pbrt-v4's %zu measured media, e.g. \"Skin1\", "
                      "\"Wholemilk\", \"Espresso\": docs/media.md lists them)",
                      name, medium_preset_count());
        return;
    }
    const char *given[2] = {"sigma_a", "sigma_s"};
    for (int k = 0; k < 2; ++k)
        if (params_has(pl, given[k]))
            params_reject(pl, given[k],
                          "\"%s\" beside \"preset\" \"%s\": the preset gives both "
                          "coefficients (pbrt-v4 does not read them either)",
                          given[k], name);
}

void medium_params_read(param_list *pl, const medium_param_rules *rules, medium_common_params *c)
{
    c->sigma_a_spec = spectrum_value_rgb(rgb_grey(0.0), SPECTRUM_USE_UNBOUNDED);
    c->sigma_s_spec = spectrum_value_rgb(rgb_grey(1.0), SPECTRUM_USE_UNBOUNDED);
    c->Le_spec = spectrum_value_rgb(rgb_grey(0.0), SPECTRUM_USE_ILLUMINANT);
    if (params_has(pl, "preset"))
        read_preset(pl, rules->grid, &c->sigma_a, &c->sigma_s);
    else if (rules->coefficients) {
        c->sigma_a = read_sigma(pl, "sigma_a", &c->sigma_a_spec);
        c->sigma_s = read_sigma(pl, "sigma_s", &c->sigma_s_spec);
    } else {
        c->sigma_a = rgb_grey(0.0);
        c->sigma_s = rgb_grey(1.0);
    }
    c->scale = params_float(pl, "scale", 1.0);
    if (!isfinite(c->scale) || c->scale < 0.0)
        params_reject(pl, "scale", "\"scale\" must be finite and non-negative, got %g", c->scale);
    c->g = params_float(pl, "g", 0.0);
    if (!(fabs(c->g) < 1.0))
        params_reject(pl, "g", "\"g\" must lie in (-1, 1), got %g", c->g);
    switch (rules->Le) {
    case MEDIUM_LE_NONE:
        c->Le = rgb_grey(0.0);
        break;
    case MEDIUM_LE_READ:
        c->Le_spec = params_spectrum(pl, "Le", SPECTRUM_USE_ILLUMINANT, rgb_grey(0.0));
        c->Le = c->Le_spec.rgb;
        break;
    case MEDIUM_LE_TINT:
        c->Le = params_illuminant(pl, "Le", rgb_grey(1.0));
        break;
    }
    c->Le_scale = rules->Le_scale ? params_float(pl, "Lescale", 1.0) : 1.0;
}

void medium_params_check_emission(param_list *pl, const medium_common_params *c)
{
    rgb Le = c->Le;
    if (!(isfinite(c->Le_scale) && c->Le_scale >= 0.0))
        params_reject(pl, "Lescale", "\"Lescale\" must be finite and non-negative, got %g",
                      c->Le_scale);
    else if (!(medium_rgb_is_finite(rgb_scale(Le, c->Le_scale)) && Le.r >= 0.0 && Le.g >= 0.0 &&
               Le.b >= 0.0))
        params_reject(pl, "Le", "\"Le\" times \"Lescale\" must be finite and non-negative");
}

hz_status medium_params_finish(medium_entity *e, const medium_common_params *c, medium *out,
                               hz_error *err)
{
    param_list *pl = &e->entity.params;
    rgb sa = rgb_scale(c->sigma_a, c->scale), ss = rgb_scale(c->sigma_s, c->scale);
    if (!medium_rgb_is_finite(sa) || !medium_rgb_is_finite(ss))
        params_reject(pl, "scale", "\"scale\" times \"sigma_a\" or \"sigma_s\" overflows");
    char what[300];
    snprintf(what, sizeof what, "MakeNamedMedium \"%s\" (\"%s\")", medium_entity_name(e),
             e->entity.type ? e->entity.type : "");
    if (params_finish(pl, what, err) != HZ_OK)
        return HZ_ERROR;
    out->name = e->name;
    out->sigma_a = sa;
    out->sigma_s = ss;
    out->g = c->g;
    out->sigma_a_spec = c->sigma_a_spec;
    out->sigma_s_spec = c->sigma_s_spec;
    out->Le_spec = c->Le_spec;
    return HZ_OK;
}

void medium_params_temperature(param_list *pl, temperature_params *tp)
{
    /* As pbrt-v4, temperatureoffset falls back to its older name
     * temperaturecutoff. */
    if (params_has(pl, "temperatureoffset") && params_has(pl, "temperaturecutoff"))
        params_reject(pl, "temperaturecutoff",
                      "give one of \"temperatureoffset\" and \"temperaturecutoff\" (its "
                      "older name), not both");
    tp->offset = params_float(pl, "temperatureoffset",
                              params_float(pl, "temperaturecutoff", 0.0));
    tp->scale = params_float(pl, "temperaturescale", 1.0);
    const char *bad = !isfinite(tp->scale)  ? "temperaturescale"
                      : !isfinite(tp->offset) ? (params_has(pl, "temperatureoffset")
                                                    ? "temperatureoffset"
                                                    : "temperaturecutoff")
                                             : NULL;
    if (bad)
        params_reject(pl, bad, "\"%s\" must be finite", bad);
}
