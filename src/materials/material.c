#include "materials/material.h"

#include "scene/named_spectra.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/hash.h"
#include "core/path.h"
#include "core/rng.h"

#include "materials/hair.h"
#include "materials/microfacet.h"

material material_default(void)
{
    return (material){.kind = MATERIAL_DIFFUSE, .reflectance = rgb_grey(0.5)};
}

/* A uniform number in [0, 1) from the bits of p and wo (pbrt-v4 hashes
 * them too; its hash differs, the choice's probability does not). */
static double hash_unit(vec3 p, vec3 wo)
{
    const double v[6] = {p.x, p.y, p.z, wo.x, wo.y, wo.z};
    rng r = rng_seeded(fnv1a(HZ_FNV_OFFSET, v, sizeof v));
    return rng_uniform(&r);
}

const material *material_at(const material *m, vec3 p, vec3 wo, const texture_ctx *c)
{
    /* Bounded: mixes refer only to materials defined before them. */
    while (m->kind == MATERIAL_MIX) {
        double amount = m->amount_tex && c ? texture_eval_float(m->amount_tex, c) : m->amount;
        if (amount <= 0.0)
            m = m->mix[0];
        else if (amount >= 1.0)
            m = m->mix[1];
        else
            m = amount < hash_unit(p, wo) ? m->mix[0] : m->mix[1];
    }
    return m;
}

hz_status material_resolve_mixes(material *materials, const material_entity *entities, size_t n,
                                 hz_error *err)
{
    for (size_t i = 0; i < n; ++i) {
        material *m = &materials[i];
        if (m->kind != MATERIAL_MIX)
            continue;
        for (int c = 0; c < 2; ++c) {
            const material *found = NULL;
            for (size_t j = 0; j < i && !found; ++j)
                if (entities[j].name && strcmp(entities[j].name, m->mix_names[c]) == 0)
                    found = &materials[j];
            if (!found)
                return hz_fail_at(err, entities[i].entity.loc,
                                  "Material \"mix\": no material named \"%s\" defined before "
                                  "it",
                                  m->mix_names[c]);
            if (found->kind == MATERIAL_INTERFACE)
                return hz_fail_at(err, entities[i].entity.loc,
                                  "Material \"mix\": \"%s\" is an interface (no surface); a "
                                  "mix needs two surfaces",
                                  m->mix_names[c]);
            m->mix[c] = found;
        }
        m->mix_names[0] = m->mix_names[1] = NULL; /* the scene's strings: not kept */
    }
    return HZ_OK;
}

bool material_transmits(const material *m)
{
    switch (m->kind) {
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_DIFFUSE_TRANSMISSION:
    case MATERIAL_HAIR:
        return true;
    case MATERIAL_DIFFUSE:
    case MATERIAL_CONDUCTOR:
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
    case MATERIAL_MEASURED:
    case MATERIAL_MIX:
    case MATERIAL_INTERFACE:
        return false;
    }
    return false;
}

/* pbrt-v4's "metal-Cu-eta" and "metal-Cu-k" (its default conductor), reduced
 * to RGB: per channel, eta is the spectrum's mean weighted by the channel's
 * sRGB matching function under D65, and k is chosen so that the normal-
 * incidence reflectance equals the RGB of the spectral one under D65
 * (0.956, 0.638, 0.538); at 60 degrees the reduction is within 0.4% of the
 * spectral reflectance, at 78 degrees within 2.5% (red). */
static const rgb copper_eta = {0.43052, 0.96400, 1.16244, 0.96400}; /* w: g */
static const rgb copper_k = {6.06186, 2.60415, 2.32192, 2.60415};

/* The texture a "texture NAME" parameter names, of the given value type;
 * NULL when the parameter is not a texture. An unknown name is refused at
 * its place. */
static const texture *texture_param(param_list *pl, const texture_set *ts, const char *name,
                                    bool spectrum)
{
    const char *ref = params_texture(pl, name);
    if (!ref)
        return NULL;
    const texture *t = texture_set_find(ts, ref, spectrum);
    if (!t)
        params_reject(pl, name, "\"texture %s\": no %s texture named \"%s\" defined before it",
                      name, spectrum ? "spectrum" : "float", ref);
    return t;
}

/* PREFIX"roughness", or PREFIX"uroughness"/PREFIX"vroughness", to
 * Trowbridge-Reitz alphas (remapped unless "remaproughness" is false), as
 * pbrt-v4; float textures go to tex[0..1] (u, v), evaluated per hit. */
static tr_distribution read_roughness_of(param_list *pl, const char *prefix,
                                         const texture_set *ts, const texture **tex)
{
    char names[3][64];
    const char *base[3] = {"roughness", "uroughness", "vroughness"};
    for (int i = 0; i < 3; ++i)
        snprintf(names[i], sizeof names[i], "%s%s", prefix, base[i]);
    const texture *rt = texture_param(pl, ts, names[0], false);
    const texture *ut = texture_param(pl, ts, names[1], false);
    const texture *vt = texture_param(pl, ts, names[2], false);
    double r = rt ? 0.0 : params_float(pl, names[0], 0.0);
    double u = ut ? 0.0 : params_float(pl, names[1], r);
    double v = vt ? 0.0 : params_float(pl, names[2], r);
    tex[0] = ut ? ut : params_has(pl, names[1]) ? NULL : rt;
    tex[1] = vt ? vt : params_has(pl, names[2]) ? NULL : rt;
    bool remap = params_bool(pl, "remaproughness", true);
    const double vals[3] = {r, u, v};
    for (int i = 0; i < 3; ++i)
        if (!(isfinite(vals[i]) && vals[i] >= 0.0))
            params_reject(pl, names[i], "\"%s\" must be finite and >= 0, got %g", names[i],
                          vals[i]);
    return (tr_distribution){remap ? tr_roughness_to_alpha(u) : u,
                             remap ? tr_roughness_to_alpha(v) : v};
}

static void read_roughness(param_list *pl, const texture_set *ts, material *out)
{
    tr_distribution d = read_roughness_of(pl, "", ts, out->rough);
    out->alpha_x = d.alpha_x;
    out->alpha_y = d.alpha_y;
}

/* An index > 0: a float, or a spectrum taken at 550 nm (a named glass
 * too; spectral rendering disperses by the spectrum itself: eta_spec,
 * interface_eta_spec). */
static double read_eta(param_list *pl, const char *name)
{
    double eta = params_float_or_550(pl, name, 1.5);
    if (!(isfinite(eta) && eta > 0.0))
        params_reject(pl, name, "\"%s\" must be finite and > 0, got %g", name, eta);
    return eta;
}

/* A conductor's "reflectance" r as eta 1 and k = 2 sqrt(r) / sqrt(1 - r). */
static double k_of_reflectance1(double r)
{
    double ri = hz_clamp(r, 0.0, 0.9999);
    return 2.0 * sqrt(ri) / sqrt(1.0 - ri);
}
static rgb k_of_reflectance(rgb r) { return rgb_map(r, k_of_reflectance1); }

/* A metal's eta or k spectrum: parameter `name` as given, pbrt-v4's named
 * copper spectrum `copper` when absent; the RGB `value` when a texture
 * gives it. */
static spectrum_value metal_spectrum(param_list *pl, const char *name, const char *copper,
                                     rgb value, const texture *tex)
{
    if (tex)
        return spectrum_value_rgb(value, SPECTRUM_USE_UNBOUNDED);
    if (params_has(pl, name))
        return params_spectrum(pl, name, SPECTRUM_USE_UNBOUNDED, value);
    const named_spectrum_samples *cu = named_spectrum_find(copper);
    spectrum_value s = spectrum_value_rgb(value, SPECTRUM_USE_UNBOUNDED);
    if (cu) {
        s.kind = SPECTRUM_VALUE_SAMPLED;
        s.lambda = cu->lambda;
        s.value = cu->value;
        s.n = cu->n;
    }
    return s;
}

/* A conductor's eta and k (named NAME_ETA, NAME_K; default copper), or
 * "reflectance" r: eta 1 and k = 2 sqrt(r) / sqrt(1 - r), r within
 * [0, 0.9999] (as pbrt-v4). */
static hz_status read_metal(param_list *pl, const texture_set *ts, const char *name_eta,
                            const char *name_k, rgb *eta, rgb *k, material *out, hz_error *err)
{
    bool has_r = params_has(pl, "reflectance");
    out->metal_r_tex = texture_param(pl, ts, "reflectance", true);
    out->eta_tex = texture_param(pl, ts, name_eta, true);
    out->k_tex = texture_param(pl, ts, name_k, true);
    if (has_r && (params_has(pl, name_eta) || params_has(pl, name_k)))
        return hz_fail_at(err, params_loc(pl, "reflectance"),
                          "give \"reflectance\" or \"%s\" and \"%s\", not both (as pbrt-v4)",
                          name_eta, name_k);
    if (has_r) {
        rgb r = out->metal_r_tex ? rgb_grey(0.0)
                                 : params_reflectance(pl, "reflectance", rgb_grey(0.0));
        if (!(r.r >= 0 && r.g >= 0 && r.b >= 0 && r.r <= 1 && r.g <= 1 && r.b <= 1))
            params_reject(pl, "reflectance", "conductor reflectance must be within [0, 1]");
        *eta = rgb_grey(1.0);
        *k = k_of_reflectance(r);
        out->metal_by_reflectance = true;
        out->metal_r = r;
        return HZ_OK;
    }
    *eta = out->eta_tex ? copper_eta : params_rgb(pl, name_eta, copper_eta);
    *k = out->k_tex ? copper_k : params_rgb(pl, name_k, copper_k);
    out->eta_spec = metal_spectrum(pl, name_eta, "metal-Cu-eta", *eta, out->eta_tex);
    out->k_spec = metal_spectrum(pl, name_k, "metal-Cu-k", *k, out->k_tex);
    rgb e = *eta, kv = *k;
    if (!(e.r > 0 && e.g > 0 && e.b > 0 && isfinite(e.r + e.g + e.b)))
        params_reject(pl, name_eta, "conductor \"%s\" must be finite and > 0", name_eta);
    if (!(kv.r >= 0 && kv.g >= 0 && kv.b >= 0 && isfinite(kv.r + kv.g + kv.b)))
        params_reject(pl, name_k, "conductor \"%s\" must be finite and >= 0", name_k);
    return HZ_OK;
}

/* What the coated materials share: thickness (0.01), albedo (0) and g (0)
 * of the medium between the layers, maxdepth (10) and nsamples (1) of the
 * random walks. */
static rgb clamp01(rgb c);
static void read_layers(param_list *pl, const texture_set *ts, material *out)
{
    layered *l = &out->coat;
    /* Float textures for thickness and g, a spectrum texture for albedo, as
     * pbrt-v4 (kroken's materials give "texture thickness"). */
    out->thickness_tex = texture_param(pl, ts, "thickness", false);
    out->albedo_tex = texture_param(pl, ts, "albedo", true);
    out->g_tex = texture_param(pl, ts, "g", false);
    l->thickness = out->thickness_tex ? 0.01 : params_float(pl, "thickness", 0.01);
    if (!(isfinite(l->thickness) && l->thickness >= 0.0))
        params_reject(pl, "thickness", "\"thickness\" must be finite and >= 0, got %g",
                      l->thickness);
    l->thickness = fmax(l->thickness, 1e-300);
    rgb a = out->albedo_tex ? rgb_grey(0.0) : params_rgb(pl, "albedo", rgb_grey(0.0));
    l->albedo = clamp01(a);
    l->g = out->g_tex ? 0.0 : hz_clamp(params_float(pl, "g", 0.0), -1.0, 1.0);
    l->max_depth = params_int(pl, "maxdepth", 10);
    l->n_samples = params_int(pl, "nsamples", 1);
    /* Bounded: each costs a random walk per evaluation. */
    if (l->max_depth < 0 || l->max_depth > 10000)
        params_reject(pl, "maxdepth", "\"maxdepth\" must be within 0 .. 10000, got %d",
                      l->max_depth);
    if (l->n_samples < 1 || l->n_samples > 10000)
        params_reject(pl, "nsamples", "\"nsamples\" must be within 1 .. 10000, got %d",
                      l->n_samples);
}

/* A coating whose index `name` is a spectrum that varies: dispersive, as
 * pbrt-v4's coated materials (their interface index at the hero wavelength,
 * the others terminated). */
static void read_interface_spectrum(param_list *pl, const char *name, material *out)
{
    if (!params_is_spectrum(pl, name))
        return;
    out->interface_eta_spec =
        params_spectrum(pl, name, SPECTRUM_USE_UNBOUNDED, rgb_grey(out->coat.eta));
    out->dispersive = !spectrum_value_is_constant(&out->interface_eta_spec);
}

static hz_status read_coated_diffuse(param_list *pl, const texture_set *ts, material *out,
                                     hz_error *err)
{
    (void)err;
    out->kind = MATERIAL_COATED_DIFFUSE;
    layered *l = &out->coat;
    out->reflectance_tex = texture_param(pl, ts, "reflectance", true);
    rgb r = out->reflectance_tex ? rgb_grey(0.5) : params_rgb(pl, "reflectance", rgb_grey(0.5));
    l->reflectance = rgb_make(hz_clamp(r.r, 0, 1), hz_clamp(r.g, 0, 1), hz_clamp(r.b, 0, 1));
    l->top = read_roughness_of(pl, "", ts, out->rough);
    l->eta = read_eta(pl, "eta");
    read_interface_spectrum(pl, "eta", out);
    read_layers(pl, ts, out);
    return HZ_OK;
}

static hz_status read_coated_conductor(param_list *pl, const texture_set *ts, material *out,
                                       hz_error *err)
{
    out->kind = MATERIAL_COATED_CONDUCTOR;
    layered *l = &out->coat;
    l->conductor = true;
    l->top = read_roughness_of(pl, "interface.", ts, out->rough);
    l->bottom = read_roughness_of(pl, "conductor.", ts, out->rough + 2);
    l->eta = read_eta(pl, "interface.eta");
    read_interface_spectrum(pl, "interface.eta", out);
    if (read_metal(pl, ts, "conductor.eta", "conductor.k", &l->eta_rgb, &l->k, out, err) !=
        HZ_OK)
        return HZ_ERROR;
    /* The base sits under the coating: its index relative to it. */
    l->eta_rgb = rgb_scale(l->eta_rgb, 1.0 / l->eta);
    l->k = rgb_scale(l->k, 1.0 / l->eta);
    read_layers(pl, ts, out);
    return HZ_OK;
}

static hz_status read_conductor(param_list *pl, const texture_set *ts, material *out,
                                hz_error *err)
{
    out->kind = MATERIAL_CONDUCTOR;
    if (read_metal(pl, ts, "eta", "k", &out->eta_rgb, &out->k, out, err) != HZ_OK)
        return HZ_ERROR;
    read_roughness(pl, ts, out);
    return HZ_OK;
}

/* A dielectric's "eta": read_eta's index (RGB rendering's, at 550 nm for a
 * spectrum), and a spectrum that varies kept for spectral rendering. */
static void read_dielectric_eta(param_list *pl, material *out)
{
    out->eta = read_eta(pl, "eta");
    if (!params_is_spectrum(pl, "eta"))
        return;
    out->eta_spec = params_spectrum(pl, "eta", SPECTRUM_USE_UNBOUNDED, rgb_grey(out->eta));
    out->dispersive = !spectrum_value_is_constant(&out->eta_spec);
}

static hz_status read_dielectric(param_list *pl, const texture_set *ts, material *out,
                                 hz_error *err)
{
    (void)err;
    out->kind = MATERIAL_DIELECTRIC;
    read_dielectric_eta(pl, out);
    read_roughness(pl, ts, out);
    return HZ_OK;
}

static hz_status read_thin_dielectric(param_list *pl, const texture_set *ts, material *out,
                                      hz_error *err)
{
    (void)ts;
    (void)err;
    out->kind = MATERIAL_THIN_DIELECTRIC;
    read_dielectric_eta(pl, out);
    return HZ_OK;
}

/* pbrt-v4's HairMaterial: the absorption from exactly one of "sigma_a",
 * "reflectance" (or "color"), or "eumelanin"/"pheomelanin" (default:
 * eumelanin 1.3, brown); pbrt-v4 warns and takes the first when several are
 * given, haze refuses that. eta 1.55, beta_m 0.3, beta_n 0.3 (clamped to
 * [0.01, 1]), alpha 2 degrees. */
static hz_status read_hair(param_list *pl, const texture_set *ts, material *out, hz_error *err)
{
    (void)err;
    out->kind = MATERIAL_HAIR;
    out->eta = params_float(pl, "eta", 1.55);
    out->beta_m = params_float(pl, "beta_m", 0.3);
    out->beta_n = params_float(pl, "beta_n", 0.3);
    out->hair_alpha = params_float(pl, "alpha", 2.0);
    if (!(isfinite(out->eta) && out->eta > 0.0))
        params_reject(pl, "eta", "hair \"eta\" must be finite and > 0, got %g", out->eta);
    if (!isfinite(out->beta_m) || !isfinite(out->beta_n))
        params_reject(pl, isfinite(out->beta_m) ? "beta_n" : "beta_m",
                      "hair \"beta_m\" and \"beta_n\" must be finite");
    if (!(isfinite(out->hair_alpha) && fabs(out->hair_alpha) <= 90.0))
        params_reject(pl, "alpha", "hair \"alpha\" must be within [-90, 90] degrees, got %g",
                      out->hair_alpha);
    double bn = fmin(fmax(out->beta_n, 0.01), 1.0);
    const char *colour = params_has(pl, "reflectance") ? "reflectance" : "color";
    bool has_sigma = params_has(pl, "sigma_a"), has_colour = params_has(pl, colour);
    bool has_melanin = params_has(pl, "eumelanin") || params_has(pl, "pheomelanin");
    if (has_sigma + has_colour + has_melanin > 1)
        params_reject(pl, has_sigma ? "sigma_a" : colour,
                      "hair takes one of \"sigma_a\", \"reflectance\" (\"color\") and "
                      "\"eumelanin\"/\"pheomelanin\" (pbrt-v4 uses the first and ignores the "
                      "others with a warning)");
    if (has_sigma) {
        rgb s = params_rgb(pl, "sigma_a", rgb_grey(0.0));
        out->sigma_a = rgb_make(fmax(s.r, 0.0), fmax(s.g, 0.0), fmax(s.b, 0.0));
    } else if (has_colour) {
        out->reflectance_tex = texture_param(pl, ts, colour, true);
        rgb c = out->reflectance_tex ? rgb_grey(0.5) : params_rgb(pl, colour, rgb_grey(0.5));
        out->sigma_a = hair_sigma_a_from_reflectance(clamp01(c), bn);
    } else if (has_melanin) {
        out->sigma_a = hair_sigma_a_from_concentration(params_float(pl, "eumelanin", 0.0),
                                                       params_float(pl, "pheomelanin", 0.0));
    } else {
        out->sigma_a = hair_sigma_a_from_concentration(1.3, 0.0);
    }
    return HZ_OK;
}

static rgb clamp01(rgb c)
{
    return rgb_make(hz_clamp(c.r, 0, 1), hz_clamp(c.g, 0, 1), hz_clamp(c.b, 0, 1));
}

static double alpha_at(const material *m, const texture *t, double constant,
                       const texture_ctx *c)
{
    if (!t)
        return constant;
    double r = fmax(texture_eval_float(t, c), 0.0);
    return m->remap_roughness ? tr_roughness_to_alpha(r) : r;
}

/* The metal's eta and k at c (relative to `outside`, the coating's index). */
static void metal_at(const material *m, const texture_ctx *c, double outside, rgb *eta, rgb *k,
                     rgb *r)
{
    if (m->metal_r_tex) {
        *r = texture_eval(m->metal_r_tex, c);
        *eta = rgb_grey(1.0 / outside);
        *k = rgb_scale(k_of_reflectance(*r), 1.0 / outside);
        return;
    }
    if (m->eta_tex) {
        rgb e = texture_eval(m->eta_tex, c);
        *eta = rgb_scale(rgb_make(fmax(e.r, 1e-6), fmax(e.g, 1e-6), fmax(e.b, 1e-6)),
                         1.0 / outside);
    }
    if (m->k_tex) {
        rgb kk = texture_eval(m->k_tex, c);
        *k = rgb_scale(rgb_make(fmax(kk.r, 0), fmax(kk.g, 0), fmax(kk.b, 0)), 1.0 / outside);
    }
}

bool material_needs_hair_frame(const material *m)
{
    if (m->kind == MATERIAL_MIX)
        return (m->mix[0] && material_needs_hair_frame(m->mix[0])) ||
               (m->mix[1] && material_needs_hair_frame(m->mix[1]));
    return m->kind == MATERIAL_HAIR;
}

bool material_has_textures(const material *m)
{
    if (m->kind == MATERIAL_MIX)
        return m->amount_tex || (m->mix[0] && material_has_textures(m->mix[0])) ||
               (m->mix[1] && material_has_textures(m->mix[1]));
    return m->textured;
}

const material *material_textured(const material *m, const texture_ctx *c, material *scratch)
{
    if (!m->textured)
        return m;
    *scratch = *m;
    material *o = scratch;
    switch (m->kind) {
    case MATERIAL_DIFFUSE:
        if (m->reflectance_tex)
            o->reflectance = clamp01(texture_eval(m->reflectance_tex, c));
        break;
    case MATERIAL_DIFFUSE_TRANSMISSION:
        if (m->reflectance_tex)
            o->reflectance = clamp01(rgb_scale(texture_eval(m->reflectance_tex, c), m->amount));
        if (m->transmittance_tex)
            o->transmittance =
                clamp01(rgb_scale(texture_eval(m->transmittance_tex, c), m->amount));
        break;
    case MATERIAL_CONDUCTOR:
        metal_at(m, c, 1.0, &o->eta_rgb, &o->k, &o->metal_r);
        o->alpha_x = alpha_at(m, m->rough[0], m->alpha_x, c);
        o->alpha_y = alpha_at(m, m->rough[1], m->alpha_y, c);
        break;
    case MATERIAL_DIELECTRIC:
        o->alpha_x = alpha_at(m, m->rough[0], m->alpha_x, c);
        o->alpha_y = alpha_at(m, m->rough[1], m->alpha_y, c);
        break;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
        if (m->reflectance_tex)
            o->coat.reflectance = clamp01(texture_eval(m->reflectance_tex, c));
        if (m->kind == MATERIAL_COATED_CONDUCTOR)
            metal_at(m, c, m->coat.eta, &o->coat.eta_rgb, &o->coat.k, &o->metal_r);
        o->coat.top.alpha_x = alpha_at(m, m->rough[0], m->coat.top.alpha_x, c);
        o->coat.top.alpha_y = alpha_at(m, m->rough[1], m->coat.top.alpha_y, c);
        o->coat.bottom.alpha_x = alpha_at(m, m->rough[2], m->coat.bottom.alpha_x, c);
        o->coat.bottom.alpha_y = alpha_at(m, m->rough[3], m->coat.bottom.alpha_y, c);
        if (m->thickness_tex) { /* > 0 (1e-300 for none or NaN); infinite: the default */
            double th = texture_eval_float(m->thickness_tex, c);
            o->coat.thickness = th == INFINITY ? m->coat.thickness : fmax(th, 1e-300);
        }
        if (m->albedo_tex)
            o->coat.albedo = clamp01(texture_eval(m->albedo_tex, c));
        if (m->g_tex)
            o->coat.g = hz_clamp(texture_eval_float(m->g_tex, c), -1.0, 1.0);
        break;
    case MATERIAL_HAIR:
        if (m->reflectance_tex)
            o->sigma_a = hair_sigma_a_from_reflectance(clamp01(texture_eval(m->reflectance_tex, c)),
                                                       fmin(fmax(m->beta_n, 0.01), 1.0));
        break;
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_MEASURED:
    case MATERIAL_MIX:
    case MATERIAL_INTERFACE:
        break;
    }
    return o;
}

static hz_status read_diffuse(param_list *pl, const texture_set *ts, material *out,
                              hz_error *err)
{
    (void)err;
    out->kind = MATERIAL_DIFFUSE;
    out->reflectance_tex = texture_param(pl, ts, "reflectance", true);
    out->reflectance = out->reflectance_tex ? rgb_grey(0.5)
                                            : params_reflectance(pl, "reflectance", rgb_grey(0.5));
    rgb r = out->reflectance;
    if (r.r < 0 || r.g < 0 || r.b < 0 || r.r > 1 || r.g > 1 || r.b > 1)
        params_reject(pl, "reflectance", "diffuse reflectance must be within [0, 1]");
    return HZ_OK;
}

/* pbrt-v4: reflectance and transmittance 0.25, times "scale", clamped to
 * [0, 1]. */
static hz_status read_diffuse_transmission(param_list *pl, const texture_set *ts, material *out,
                                           hz_error *err)
{
    (void)err;
    out->kind = MATERIAL_DIFFUSE_TRANSMISSION;
    double scale = params_float(pl, "scale", 1.0);
    out->reflectance_tex = texture_param(pl, ts, "reflectance", true);
    out->transmittance_tex = texture_param(pl, ts, "transmittance", true);
    rgb r = out->reflectance_tex ? rgb_grey(0.25) : params_rgb(pl, "reflectance", rgb_grey(0.25));
    rgb t = out->transmittance_tex ? rgb_grey(0.25)
                                   : params_rgb(pl, "transmittance", rgb_grey(0.25));
    if (!(isfinite(scale) && scale >= 0.0))
        params_reject(pl, "scale", "\"scale\" must be finite and >= 0, got %g", scale);
    out->reflectance = rgb_make(hz_clamp(scale * r.r, 0, 1), hz_clamp(scale * r.g, 0, 1),
                                hz_clamp(scale * r.b, 0, 1));
    out->transmittance = rgb_make(hz_clamp(scale * t.r, 0, 1), hz_clamp(scale * t.g, 0, 1),
                                  hz_clamp(scale * t.b, 0, 1));
    out->amount = scale; /* the textures' scale */
    return HZ_OK;
}

/* The two materials are named here and found by material_resolve_mixes. */
static hz_status read_mix(param_list *pl, const texture_set *ts, material *out, hz_error *err)
{
    out->kind = MATERIAL_MIX;
    out->amount_tex = texture_param(pl, ts, "amount", false);
    out->amount = out->amount_tex ? 0.5 : params_float(pl, "amount", 0.5);
    if (!isfinite(out->amount))
        params_reject(pl, "amount", "\"amount\" must be finite, got %g", out->amount);
    size_t n = 0;
    char *const *names = params_strings(pl, "materials", &n);
    if (n != 2)
        return hz_fail_at(err, params_loc(pl, "materials"),
                          "Material \"mix\" needs \"string materials\" naming two "
                          "materials, got %zu",
                          n);
    out->mix_names[0] = names[0];
    out->mix_names[1] = names[1];
    return HZ_OK;
}

/* pbrt-v4 makes no material for "interface", "" and "none": rays pass the
 * surface, which only bounds media. */
static hz_status read_interface(param_list *pl, const texture_set *ts, material *out,
                                hz_error *err)
{
    (void)pl;
    (void)ts;
    (void)err;
    out->kind = MATERIAL_INTERFACE;
    return HZ_OK;
}

/* pbrt-v4's MeasuredMaterial: "string filename" names an RGL .bsdf file,
 * relative to the scene file's directory; each file is read once. */
static hz_status read_measured(param_list *pl, file_loc loc, measured_cache *mc, material *out,
                               hz_error *err)
{
    assert(mc);
    out->kind = MATERIAL_MEASURED;
    const char *name = params_string(pl, "filename", NULL);
    if (!name || !*name)
        return hz_fail_at(err, name ? params_loc(pl, "filename") : loc,
                          "Material \"measured\" needs \"string filename\" (an RGL .bsdf "
                          "file)");
    file_loc at = params_loc(pl, "filename");
    char *path = path_of_scene_file(at, name);
    if (!path)
        return hz_fail(err, "out of memory");
    hz_error e;
    hz_status st = measured_cache_get(mc, path, &out->measured, &e);
    free(path);
    if (st != HZ_OK)
        return hz_fail_at(err, at, "Material \"measured\": %s", e.message);
    return HZ_OK;
}

static const struct {
    const char *type;
    hz_status (*read)(param_list *pl, const texture_set *ts, material *out, hz_error *err);
} material_kinds[] = {
    {"diffuse", read_diffuse},
    {"diffusetransmission", read_diffuse_transmission},
    {"mix", read_mix},
    {"coateddiffuse", read_coated_diffuse},
    {"coatedconductor", read_coated_conductor},
    {"conductor", read_conductor},
    {"dielectric", read_dielectric},
    {"thindielectric", read_thin_dielectric},
    {"hair", read_hair},
    {"interface", read_interface},
    {"", read_interface},
    {"none", read_interface},
};

/* Every material with a surface takes pbrt-v4's "displacement" and
 * "normalmap"; mixes, interfaces and hair leave them unused (pbrt-v4's hair
 * has neither). */
static void read_surface_maps(param_list *pl, const texture_set *ts, material *out)
{
    if (out->kind == MATERIAL_MIX || out->kind == MATERIAL_INTERFACE ||
        out->kind == MATERIAL_HAIR)
        return;
    /* A float texture bumps the shading normal; a constant one changes
     * nothing (its gradient is 0, as in pbrt-v4). */
    out->displacement = texture_param(pl, ts, "displacement", false);
    if (!out->displacement && params_has(pl, "displacement"))
        params_float(pl, "displacement", 0.0);
    /* The image was read with the scene's textures; one that could not be
     * read was reported there (at this parameter): the material goes on
     * without it. */
    const char *nm = params_string(pl, "normalmap", NULL);
    if (nm)
        out->normal_map = texture_set_normal_map(ts, nm);
}

/* Whether the material's look varies over the surface (material_textured),
 * and every parameter used. */
static hz_status finish_material(param_list *pl, const char *type, material *out, hz_error *err)
{
    bool rough_tex = out->rough[0] || out->rough[1] || out->rough[2] || out->rough[3];
    /* Read already by the roughness, when there is one. */
    out->remap_roughness = rough_tex ? params_bool(pl, "remaproughness", true) : true;
    out->textured = out->reflectance_tex || out->transmittance_tex || out->eta_tex ||
                    out->k_tex || out->metal_r_tex || rough_tex || out->displacement ||
                    out->normal_map || out->thickness_tex || out->albedo_tex || out->g_tex;
    char what[128];
    snprintf(what, sizeof what, "Material \"%s\"", type);
    return params_finish(pl, what, err);
}

hz_status material_from_entity(material_entity *e, const texture_set *ts,
                               measured_cache *measured, material *out, hz_error *err)
{
    param_list *pl = &e->entity.params;
    const char *type = e->entity.type ? e->entity.type : "";
    /* MakeNamedMaterial carries its type as a "string type" parameter; accept
     * it here too in case the parser left it in the list. */
    if (params_has(pl, "type"))
        type = params_string(pl, "type", type);
    *out = (material){.kind = MATERIAL_INTERFACE};
    if (strcmp(type, "measured") == 0) {
        if (read_measured(pl, e->entity.loc, measured, out, err) != HZ_OK)
            return HZ_ERROR;
        read_surface_maps(pl, ts, out);
        return finish_material(pl, type, out, err);
    }
    for (size_t i = 0; i < sizeof material_kinds / sizeof material_kinds[0]; ++i)
        if (strcmp(type, material_kinds[i].type) == 0) {
            if (material_kinds[i].read(pl, ts, out, err) != HZ_OK)
                return HZ_ERROR;
            read_surface_maps(pl, ts, out);
            return finish_material(pl, type, out, err);
        }
    return hz_fail_at(err, e->entity.loc,
                      "Material \"%s\" is not supported (supported: \"diffuse\", "
                      "\"conductor\", \"dielectric\", \"thindielectric\", "
                      "\"diffusetransmission\", \"coateddiffuse\", \"coatedconductor\", "
                      "\"hair\", \"measured\", \"mix\", \"interface\", \"\" or \"none\" as "
                      "\"interface\")",
                      type);
}

/* Colour c of a material at the wavelengths: prepared once when constant. */
static rgb colour_at(const spectral_ctx *sp, const spectral_color *prepared, rgb c,
                     spectral_use use)
{
    return prepared->ready ? spectral_eval(sp, prepared) : spectral_from_rgb(sp, c, use);
}

/* A metal's eta and k at the wavelengths: from its reflectance per
 * wavelength when given so, else its indices: the spectra as given, or
 * (textured, RGB) unbounded spectra; relative to `outside` (the coating's
 * index) as they are. */
static void metal_spectral(const material *m, const spectral_ctx *sp, double outside, rgb *eta,
                           rgb *k)
{
    if (m->metal_by_reflectance) {
        *eta = rgb_grey(1.0 / outside);
        rgb r = colour_at(sp, &m->prepared.first, m->metal_r, SPECTRAL_ALBEDO);
        *k = rgb_scale(k_of_reflectance(r), 1.0 / outside);
        return;
    }
    *eta = m->eta_spec.kind == SPECTRUM_VALUE_RGB
               ? colour_at(sp, &m->prepared.eta, *eta, SPECTRAL_UNBOUNDED)
               : rgb_scale(spectral_from_value(sp, &m->eta_spec), 1.0 / outside);
    *k = m->k_spec.kind == SPECTRUM_VALUE_RGB
             ? colour_at(sp, &m->prepared.k, *k, SPECTRAL_UNBOUNDED)
             : rgb_scale(spectral_from_value(sp, &m->k_spec), 1.0 / outside);
}

const material *material_spectral(const material *m, const spectral_ctx *sp, material *scratch)
{
    if (!sp)
        return m;
    if (scratch != m)
        *scratch = *m;
    material *o = scratch;
    const material *p = o; /* its prepared colours (copied along) */
    o->spectral = sp;
    switch (m->kind) {
    case MATERIAL_DIFFUSE_TRANSMISSION:
        o->transmittance =
            colour_at(sp, &p->prepared.second, o->transmittance, SPECTRAL_ALBEDO);
        /* fall through */
    case MATERIAL_DIFFUSE:
        o->reflectance = colour_at(sp, &p->prepared.first, o->reflectance, SPECTRAL_ALBEDO);
        break;
    case MATERIAL_CONDUCTOR:
        metal_spectral(p, sp, 1.0, &o->eta_rgb, &o->k);
        break;
    case MATERIAL_COATED_CONDUCTOR:
        metal_spectral(p, sp, o->coat.eta, &o->coat.eta_rgb, &o->coat.k);
        o->coat.albedo = colour_at(sp, &p->prepared.second, o->coat.albedo, SPECTRAL_ALBEDO);
        break;
    case MATERIAL_COATED_DIFFUSE:
        o->coat.reflectance =
            colour_at(sp, &p->prepared.first, o->coat.reflectance, SPECTRAL_ALBEDO);
        o->coat.albedo = colour_at(sp, &p->prepared.second, o->coat.albedo, SPECTRAL_ALBEDO);
        break;
    case MATERIAL_HAIR:
        o->sigma_a = colour_at(sp, &p->prepared.first, o->sigma_a, SPECTRAL_UNBOUNDED);
        break;
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_MEASURED:
    case MATERIAL_MIX:
    case MATERIAL_INTERFACE:
        break;
    }
    return o;
}

void material_disperse(material *m, const spectral_ctx *sp, int lane)
{
    assert(m->dispersive && lane >= 0 && lane < WAVELENGTH_LANES);
    bool coated = m->kind == MATERIAL_COATED_DIFFUSE || m->kind == MATERIAL_COATED_CONDUCTOR;
    double eta = spectrum_value_eval(coated ? &m->interface_eta_spec : &m->eta_spec,
                                     sp->wl.lambda[lane]);
    /* A spectrum that reaches 0 or below somewhere: its 550 nm index. */
    if (!(isfinite(eta) && eta > 0.0))
        return;
    if (!coated) {
        m->eta = eta;
        return;
    }
    /* The conductor under a coating has its index relative to it. */
    double rel = m->coat.eta / eta;
    m->coat.eta_rgb = rgb_scale(m->coat.eta_rgb, rel);
    m->coat.k = rgb_scale(m->coat.k, rel);
    m->coat.eta = eta;
}

void material_prepare_spectral(material *m, const rgb2spec_table *t)
{
    spectral_color none = {0};
    m->prepared.first = m->prepared.second = m->prepared.eta = m->prepared.k = none;
    switch (m->kind) {
    case MATERIAL_DIFFUSE_TRANSMISSION:
        if (!m->transmittance_tex)
            m->prepared.second = spectral_prepare(t, m->transmittance, SPECTRAL_ALBEDO);
        /* fall through */
    case MATERIAL_DIFFUSE:
        if (!m->reflectance_tex)
            m->prepared.first = spectral_prepare(t, m->reflectance, SPECTRAL_ALBEDO);
        break;
    case MATERIAL_COATED_CONDUCTOR:
    case MATERIAL_CONDUCTOR: {
        bool coated = m->kind == MATERIAL_COATED_CONDUCTOR;
        if (m->metal_by_reflectance && !m->metal_r_tex)
            m->prepared.first = spectral_prepare(t, m->metal_r, SPECTRAL_ALBEDO);
        if (!m->metal_by_reflectance && !m->eta_tex)
            m->prepared.eta =
                spectral_prepare(t, coated ? m->coat.eta_rgb : m->eta_rgb, SPECTRAL_UNBOUNDED);
        if (!m->metal_by_reflectance && !m->k_tex)
            m->prepared.k = spectral_prepare(t, coated ? m->coat.k : m->k, SPECTRAL_UNBOUNDED);
        if (coated && !m->albedo_tex)
            m->prepared.second = spectral_prepare(t, m->coat.albedo, SPECTRAL_ALBEDO);
        break;
    }
    case MATERIAL_COATED_DIFFUSE:
        if (!m->reflectance_tex)
            m->prepared.first = spectral_prepare(t, m->coat.reflectance, SPECTRAL_ALBEDO);
        if (!m->albedo_tex)
            m->prepared.second = spectral_prepare(t, m->coat.albedo, SPECTRAL_ALBEDO);
        break;
    case MATERIAL_HAIR:
        if (!m->reflectance_tex)
            m->prepared.first = spectral_prepare(t, m->sigma_a, SPECTRAL_UNBOUNDED);
        break;
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_MEASURED:
    case MATERIAL_MIX:
    case MATERIAL_INTERFACE:
        break;
    }
}

static bool grey(rgb c) { return c.r == c.g && c.g == c.b; }
static bool tex_grey(const texture *t) { return !t || texture_is_grey(t); }

bool material_is_spectrally_nonlinear(const material *m)
{
    switch (m->kind) {
    case MATERIAL_CONDUCTOR:
    case MATERIAL_COATED_CONDUCTOR: {
        const layered *l = &m->coat;
        bool coated = m->kind == MATERIAL_COATED_CONDUCTOR;
        rgb eta = coated ? l->eta_rgb : m->eta_rgb, k = coated ? l->k : m->k;
        return (m->metal_by_reflectance ? !grey(m->metal_r) : !grey(eta) || !grey(k)) ||
               !tex_grey(m->metal_r_tex) || !tex_grey(m->eta_tex) || !tex_grey(m->k_tex) ||
               (coated && (!grey(l->albedo) || !tex_grey(m->albedo_tex)));
    }
    case MATERIAL_COATED_DIFFUSE:
        return !grey(m->coat.reflectance) || !grey(m->coat.albedo) ||
               !tex_grey(m->reflectance_tex) || !tex_grey(m->albedo_tex);
    case MATERIAL_HAIR:
        return !grey(m->sigma_a) || !tex_grey(m->reflectance_tex);
    case MATERIAL_MEASURED:
        return true;
    case MATERIAL_MIX:
        return (m->mix[0] && material_is_spectrally_nonlinear(m->mix[0])) ||
               (m->mix[1] && material_is_spectrally_nonlinear(m->mix[1]));
    case MATERIAL_DIFFUSE: /* a colour that scales the BSDF */
    case MATERIAL_DIFFUSE_TRANSMISSION:
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_INTERFACE:
        break;
    }
    return false;
}
