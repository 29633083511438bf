#include "materials/material.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "materials/microfacet.h"

material material_default(void)
{
    return (material){.kind = MATERIAL_DIFFUSE, .reflectance = rgb_grey(0.5)};
}

bool material_needs_volpath(const material *m)
{
    switch (m->kind) {
    case MATERIAL_DIFFUSE:
    case MATERIAL_INTERFACE:
        return false;
    case MATERIAL_CONDUCTOR:
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_DIFFUSE_TRANSMISSION:
        return true;
    }
    return true;
}

/* pbrt-v4's "metal-Cu-eta" and "metal-Cu-k" (its default conductor), reduced
 * to RGB: per channel, eta is the spectrum's mean weighted by the channel's
 * sRGB matching function under D65, and k is chosen so that the normal-
 * incidence reflectance equals the RGB of the spectral one under D65
 * (0.956, 0.638, 0.538); at 60 degrees the reduction is within 0.4% of the
 * spectral reflectance, at 78 degrees within 2.5% (red). */
static const rgb copper_eta = {0.43052, 0.96400, 1.16244};
static const rgb copper_k = {6.06186, 2.60415, 2.32192};

/* "roughness", or "uroughness"/"vroughness", to Trowbridge-Reitz alphas
 * (remapped unless "remaproughness" is false), as pbrt-v4. */
static void read_roughness(param_list *pl, material *out)
{
    double r = params_float(pl, "roughness", 0.0);
    double u = params_float(pl, "uroughness", r), v = params_float(pl, "vroughness", r);
    bool remap = params_bool(pl, "remaproughness", true);
    const char *names[3] = {"roughness", "uroughness", "vroughness"};
    const double vals[3] = {r, u, v};
    for (int i = 0; i < 3; ++i)
        if (!(isfinite(vals[i]) && vals[i] >= 0.0))
            params_reject(pl, names[i], "\"%s\" must be finite and >= 0, got %g", names[i],
                          vals[i]);
    out->alpha_x = remap ? tr_roughness_to_alpha(u) : u;
    out->alpha_y = remap ? tr_roughness_to_alpha(v) : v;
}

static hz_status read_conductor(param_list *pl, material *out, hz_error *err)
{
    out->kind = MATERIAL_CONDUCTOR;
    bool has_r = params_has(pl, "reflectance");
    if (has_r && (params_has(pl, "eta") || params_has(pl, "k")))
        return hz_fail_at(err, params_loc(pl, "reflectance"),
                          "give \"reflectance\" or \"eta\" and \"k\", not both (as pbrt-v4)");
    if (has_r) {
        /* pbrt-v4: eta 1 and the k whose normal-incidence Fresnel is r. */
        rgb r = params_rgb(pl, "reflectance", rgb_grey(0.0));
        if (!(r.r >= 0 && r.g >= 0 && r.b >= 0 && r.r <= 1 && r.g <= 1 && r.b <= 1))
            params_reject(pl, "reflectance", "conductor reflectance must be within [0, 1]");
        double c[3] = {r.r, r.g, r.b}, k[3];
        for (int i = 0; i < 3; ++i) {
            double ri = fmin(fmax(c[i], 0.0), 1.0 - 1e-9);
            k[i] = 2.0 * sqrt(ri) / sqrt(1.0 - ri);
        }
        out->eta_rgb = rgb_grey(1.0);
        out->k = rgb_make(k[0], k[1], k[2]);
    } else {
        out->eta_rgb = params_rgb(pl, "eta", copper_eta);
        out->k = params_rgb(pl, "k", copper_k);
        rgb e = out->eta_rgb, k = out->k;
        if (!(e.r > 0 && e.g > 0 && e.b > 0 && isfinite(e.r + e.g + e.b)))
            params_reject(pl, "eta", "conductor \"eta\" must be finite and > 0");
        if (!(k.r >= 0 && k.g >= 0 && k.b >= 0 && isfinite(k.r + k.g + k.b)))
            params_reject(pl, "k", "conductor \"k\" must be finite and >= 0");
    }
    read_roughness(pl, out);
    return HZ_OK;
}

static hz_status read_dielectric(param_list *pl, bool thin, material *out, hz_error *err)
{
    out->kind = thin ? MATERIAL_THIN_DIELECTRIC : MATERIAL_DIELECTRIC;
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, "eta") == 0 && pl->items[i].type != PARAM_FLOAT)
            return hz_fail_at(err, params_loc(pl, "eta"),
                              "a dielectric's \"eta\" must be a \"float\": spectral (dispersive) "
                              "indices are not supported yet");
    out->eta = params_float(pl, "eta", 1.5);
    if (!(isfinite(out->eta) && out->eta > 0.0))
        params_reject(pl, "eta", "\"eta\" must be finite and > 0, got %g", out->eta);
    if (!thin)
        read_roughness(pl, out);
    return HZ_OK;
}

hz_status material_from_entity(material_entity *e, material *out, hz_error *err)
{
    param_list *pl = &e->entity.params;
    const char *type = e->entity.type ? e->entity.type : "";
    /* MakeNamedMaterial carries its type as a "string type" parameter; accept
     * it here too in case the parser left it in the list. */
    if (params_has(pl, "type"))
        type = params_string(pl, "type", type);
    *out = (material){.kind = MATERIAL_INTERFACE};

    if (strcmp(type, "diffuse") == 0) {
        out->kind = MATERIAL_DIFFUSE;
        out->reflectance = params_rgb(pl, "reflectance", rgb_grey(0.5));
        rgb r = out->reflectance;
        if (r.r < 0 || r.g < 0 || r.b < 0 || r.r > 1 || r.g > 1 || r.b > 1)
            params_reject(pl, "reflectance", "diffuse reflectance must be within [0, 1]");
    } else if (strcmp(type, "diffusetransmission") == 0) {
        /* pbrt-v4: reflectance and transmittance 0.25, times "scale",
         * clamped to [0, 1]. */
        out->kind = MATERIAL_DIFFUSE_TRANSMISSION;
        double scale = params_float(pl, "scale", 1.0);
        rgb r = params_rgb(pl, "reflectance", rgb_grey(0.25));
        rgb t = params_rgb(pl, "transmittance", rgb_grey(0.25));
        if (!(isfinite(scale) && scale >= 0.0))
            params_reject(pl, "scale", "\"scale\" must be finite and >= 0, got %g", scale);
        out->reflectance = rgb_make(hz_clamp(scale * r.r, 0, 1), hz_clamp(scale * r.g, 0, 1),
                                    hz_clamp(scale * r.b, 0, 1));
        out->transmittance = rgb_make(hz_clamp(scale * t.r, 0, 1), hz_clamp(scale * t.g, 0, 1),
                                      hz_clamp(scale * t.b, 0, 1));
    } else if (strcmp(type, "conductor") == 0) {
        if (read_conductor(pl, out, err) != HZ_OK)
            return HZ_ERROR;
    } else if (strcmp(type, "dielectric") == 0 || strcmp(type, "thindielectric") == 0) {
        if (read_dielectric(pl, strcmp(type, "thindielectric") == 0, out, err) != HZ_OK)
            return HZ_ERROR;
    } else if (strcmp(type, "interface") == 0 || strcmp(type, "") == 0 ||
               strcmp(type, "none") == 0) {
        /* pbrt-v4 makes no material for all three: rays pass the surface,
         * which only bounds media. */
        out->kind = MATERIAL_INTERFACE;
    } else {
        return hz_fail_at(err, e->entity.loc,
                          "Material \"%s\" is not supported (supported: \"diffuse\", "
                          "\"conductor\", \"dielectric\", \"thindielectric\", "
                          "\"diffusetransmission\", \"interface\", \"\" or \"none\" as "
                          "\"interface\")",
                          type);
    }
    char what[128];
    snprintf(what, sizeof what, "Material \"%s\"", type);
    return params_finish(pl, what, err);
}
