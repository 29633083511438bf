#include "integrator/integrator.h"

#include <assert.h>

#include <string.h>

/* A scene with no Integrator directive (its default entity sits at line 0)
 * renders with "singlescatter". */
/* pbrt-v4's materials that only volpath renders. */
static bool volpath_material(const char *type)
{
    return type && (strcmp(type, "conductor") == 0 || strcmp(type, "dielectric") == 0 ||
                    strcmp(type, "thindielectric") == 0 ||
                    strcmp(type, "diffusetransmission") == 0 ||
                    strcmp(type, "coateddiffuse") == 0 || strcmp(type, "coatedconductor") == 0 ||
                    strcmp(type, "measured") == 0 || strcmp(type, "mix") == 0);
}

integrator_kind integrator_default_kind(const scene_desc *sd, const char **why, const char **what)
{
    *why = *what = NULL;
    for (size_t i = 0; i < sd->material_count; ++i)
        if (volpath_material(sd->materials[i].entity.type)) {
            *why = sd->materials[i].entity.type;
            *what = "material";
            return INTEGRATOR_VOLPATH;
        }
    for (size_t i = 0; i < sd->medium_count; ++i) {
        const char *type = sd->media[i].entity.type;
        if (medium_type_volpath_only(type)) {
            *why = type;
            *what = "medium";
            return INTEGRATOR_VOLPATH;
        }
    }
    return INTEGRATOR_SINGLESCATTER;
}

/* pbrt-v4's other integrators of the light transport volpath computes (the
 * same converged image, other noise): rendered by volpath, with a warning.
 * `media`: pbrt-v4's renders participating media (the others ignore them,
 * as "path" does, which haze does not: refused with media). `tuning`: the
 * parameters that tune only their own noise or speed, read and named in the
 * warning as not used (each "T name", T the type: i integer, f float, b
 * bool). */
static const struct {
    const char *name;
    bool media, regularize;
    const char *tuning[5];
} volpath_stand_ins[] = {
    {"bdpt", true, true, {NULL}},
    {"mlt", true, true,
     {"i bootstrapsamples", "i chains", "i mutationsperpixel", "f largestepprobability",
      "f sigma"}},
    {"simplevolpath", true, false, {NULL}},
    {"sppm", false, false, {"i photonsperiteration", "f radius", "i seed"}},
    {"simplepath", false, false, {"b samplelights"}},
    {"randomwalk", false, false, {NULL}},
    {"lightpath", false, false, {NULL}},
};

static hz_status stand_in_settings(scene_desc *sd, size_t k, FILE *warn, volpath_settings *out,
                                   hz_error *err)
{
    scene_entity *e = &sd->integrator;
    param_list *pl = &e->params;
    const char *type = volpath_stand_ins[k].name;
    if (!volpath_stand_ins[k].media && sd->medium_count > 0)
        return hz_fail_at(err, e->loc,
                          "Integrator \"%s\" with media: pbrt-v4's %s integrator ignores media, "
                          "haze does not render them away; use \"volpath\"",
                          type, type);
    *out = (volpath_settings){.light_sampler = LIGHT_SAMPLER_BVH, .medium_splits = 1};
    out->max_depth = params_int(pl, "maxdepth", 5);
    if (out->max_depth < 0)
        params_reject(pl, "maxdepth", "\"maxdepth\" must be >= 0");
    if (volpath_stand_ins[k].regularize)
        out->regularize = params_bool(pl, "regularize", false);
    if (strcmp(type, "bdpt") == 0) {
        static const char *views[2] = {"visualizestrategies", "visualizeweights"};
        for (int i = 0; i < 2; ++i)
            if (params_bool(pl, views[i], false))
                params_reject(pl, views[i],
                              "\"%s\" shows BDPT's strategies one by one, a debugging view: haze "
                              "renders \"bdpt\" with volpath, which has none",
                              views[i]);
    }
    if (strcmp(type, "simplepath") == 0 && !params_bool(pl, "samplebsdf", true))
        params_reject(pl, "samplebsdf",
                      "\"samplebsdf\" false leaves only light seen directly and through one "
                      "light sample: haze renders \"simplepath\" with volpath, whose paths "
                      "always continue");
    char unused[256] = "";
    for (int i = 0; i < 5 && volpath_stand_ins[k].tuning[i]; ++i) {
        const char *name = volpath_stand_ins[k].tuning[i] + 2;
        if (!params_has(pl, name))
            continue;
        switch (volpath_stand_ins[k].tuning[i][0]) { /* read with its type */
        case 'i':
            (void)params_int(pl, name, 0);
            break;
        case 'f':
            (void)params_float(pl, name, 0.0);
            break;
        default:
            (void)params_bool(pl, name, false);
            break;
        }
        size_t n = strlen(unused);
        snprintf(unused + n, sizeof unused - n, "%s\"%s\"", n ? ", " : "", name);
    }
    hz_warn_at(warn, e->loc,
               "Integrator \"%s\" renders with haze's volpath (the same converged image, other "
               "noise; an image clamped by the Film's maxcomponentvalue differs)%s%s%s",
               type, unused[0] ? "; " : "", unused, unused[0] ? " not used" : "");
    char what[64];
    snprintf(what, sizeof what, "Integrator \"%s\"", type);
    return params_finish(pl, what, err);
}

hz_status integrator_params_from_scene(scene_desc *sd, FILE *warn, integrator_params *out,
                                       hz_error *err)
{
    scene_entity *e = &sd->integrator;
    param_list *pl = &e->params;
    const char *type = e->type ? e->type : "volpath";
    *out = (integrator_params){.kind = INTEGRATOR_SINGLESCATTER,
                               .singlescatter = singlescatter_settings_default()};
    const char *why, *what;
    if (e->loc.line == 0 && integrator_default_kind(sd, &why, &what) == INTEGRATOR_SINGLESCATTER)
        return params_finish(pl, "Integrator", err);
    /* pbrt-v4's "path" is its volpath without media (the same estimator and
     * parameters); with media it ignores them, which haze does not do. */
    bool path = strcmp(type, "path") == 0;
    if (path && sd->medium_count > 0)
        return hz_fail_at(err, e->loc,
                          "Integrator \"path\" with media: pbrt-v4's path integrator ignores "
                          "media, haze does not render them away; use \"volpath\"");
    if (path || strcmp(type, "volpath") == 0) {
        out->kind = INTEGRATOR_VOLPATH;
        if (volpath_settings_from_entity(e, warn, &out->volpath, err) != HZ_OK)
            return HZ_ERROR;
        return params_finish(pl, path ? "Integrator \"path\"" : "Integrator \"volpath\"", err);
    }
    if (strcmp(type, "singlescatter") == 0) {
        if (singlescatter_settings_from_entity(e, &out->singlescatter, err) != HZ_OK)
            return HZ_ERROR;
        return params_finish(pl, "Integrator \"singlescatter\"", err);
    }
    for (size_t k = 0; k < sizeof volpath_stand_ins / sizeof volpath_stand_ins[0]; ++k)
        if (strcmp(type, volpath_stand_ins[k].name) == 0) {
            out->kind = INTEGRATOR_VOLPATH;
            return stand_in_settings(sd, k, warn, &out->volpath, err);
        }
    return hz_fail_at(err, e->loc,
                      "Integrator \"%s\" is not supported (supported: \"volpath\", \"path\" "
                      "(without media), \"singlescatter\"; rendered by volpath: \"bdpt\", "
                      "\"mlt\", \"sppm\", \"simplevolpath\", \"simplepath\", \"randomwalk\", "
                      "\"lightpath\")",
                      type);
}

hz_status integrator_init(integrator *out, const integrator_params *p,
                          const integrator_inputs *in, hz_error *err)
{
    out->kind = p->kind;
    switch (p->kind) {
    case INTEGRATOR_SINGLESCATTER:
        out->singlescatter = singlescatter_scene_make(in, p->singlescatter);
        return HZ_OK;
    case INTEGRATOR_VOLPATH:
        return volpath_scene_init(&out->volpath, in, p->volpath, err);
    }
    return hz_fail(err, "unknown integrator kind %d", (int)p->kind);
}

void integrator_free(integrator *it)
{
    switch (it->kind) {
    case INTEGRATOR_SINGLESCATTER:
        break;
    case INTEGRATOR_VOLPATH:
        volpath_scene_free(&it->volpath);
        break;
    }
}

void integrator_set_footprint_scale(integrator *it, double scale)
{
    switch (it->kind) {
    case INTEGRATOR_SINGLESCATTER: /* shades the camera ray's hit only */
        it->singlescatter.in.footprint_scale = scale;
        break;
    case INTEGRATOR_VOLPATH:
        it->volpath.in.footprint_scale = scale;
        break;
    }
}

rgb integrator_li(const integrator *it, const ray_differential *rd, const spectral_ctx *sp,
                  sampler_state *st, double *depth, film_surface *vs,
                  integrator_counters *counters)
{
    switch (it->kind) {
    case INTEGRATOR_SINGLESCATTER:
        return singlescatter_li(&it->singlescatter, rd, sp, st, depth, vs, counters);
    case INTEGRATOR_VOLPATH:
        return volpath_li(&it->volpath, rd, sp, st, depth, vs, counters);
    }
    return rgb_grey(0.0);
}
