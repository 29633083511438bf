#include "integrator/integrator.h"

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
                    strcmp(type, "mix") == 0);
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
        if (type && (strcmp(type, "cloud") == 0 || strcmp(type, "rgbgrid") == 0)) {
            *why = type;
            *what = "medium";
            return INTEGRATOR_VOLPATH;
        }
    }
    return INTEGRATOR_SINGLESCATTER;
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
    return hz_fail_at(err, e->loc,
                      "Integrator \"%s\" is not supported (supported: \"volpath\", \"path\" "
                      "(without media), \"singlescatter\")",
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

rgb integrator_li(const integrator *it, const ray_differential *rd, sampler_state *st,
                  double *depth, film_surface *vs, integrator_counters *counters)
{
    switch (it->kind) {
    case INTEGRATOR_SINGLESCATTER:
        return singlescatter_li(&it->singlescatter, rd, st, depth, vs, counters);
    case INTEGRATOR_VOLPATH:
        return volpath_li(&it->volpath, rd, st, depth, vs, counters);
    }
    return rgb_grey(0.0);
}
