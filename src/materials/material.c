#include "materials/material.h"

#include <stdio.h>
#include <string.h>

material material_default(void)
{
    return (material){MATERIAL_DIFFUSE, rgb_grey(0.5)};
}

/* Textures are not a parameter type haze knows, so a "texture reflectance"
 * reaches us as a string-valued parameter; name the problem plainly. */
static bool reflectance_is_texture(const param_list *pl)
{
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, "reflectance") == 0 && pl->items[i].type == PARAM_STRING)
            return true;
    return false;
}

hz_status material_from_entity(material_entity *e, material *out, hz_error *err)
{
    param_list *pl = &e->entity.params;
    const char *type = e->entity.type ? e->entity.type : "";
    /* MakeNamedMaterial carries its type as a "string type" parameter; accept
     * it here too in case the parser left it in the list. */
    if (params_has(pl, "type"))
        type = params_string(pl, "type", type);

    if (strcmp(type, "diffuse") == 0) {
        if (reflectance_is_texture(pl))
            return hz_fail_at(err, params_loc(pl, "reflectance"),
                              "textures are not supported: give \"rgb reflectance\" a constant "
                              "value");
        out->kind = MATERIAL_DIFFUSE;
        out->reflectance = params_rgb(pl, "reflectance", rgb_grey(0.5));
        rgb r = out->reflectance;
        if (r.r < 0 || r.g < 0 || r.b < 0 || r.r > 1 || r.g > 1 || r.b > 1)
            params_reject(pl, "reflectance", "diffuse reflectance must be within [0, 1]");
    } else if (strcmp(type, "interface") == 0 || strcmp(type, "") == 0 ||
               strcmp(type, "none") == 0) {
        /* pbrt-v4 makes no material for all three: rays pass the surface,
         * which only bounds media. */
        out->kind = MATERIAL_INTERFACE;
        out->reflectance = rgb_grey(0.0);
    } else {
        return hz_fail_at(err, e->entity.loc,
                          "Material \"%s\" is not supported (supported: \"diffuse\", "
                          "\"interface\", \"\" or \"none\" as \"interface\")",
                          type);
    }
    char what[128];
    snprintf(what, sizeof what, "Material \"%s\"", type);
    return params_finish(pl, what, err);
}
