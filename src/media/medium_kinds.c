/* The kinds' table: name -> operations, and medium_create, which picks the
 * row of an entity's type. A kind is its own file (media/medium.h lists
 * them), its extern here and its row in the table; the kinds' files do not
 * include this one, so the table depends on them and not the other way. */
#include "media/medium.h"

#include <string.h>

extern const medium_ops medium_homogeneous_ops, medium_nanovdb_ops, medium_uniformgrid_ops,
    medium_cloud_ops, medium_rgbgrid_ops;

/* Name -> operations. */
static const medium_ops *const kinds[] = {
    &medium_homogeneous_ops, &medium_nanovdb_ops, &medium_uniformgrid_ops,
    &medium_cloud_ops,       &medium_rgbgrid_ops,
};
#define KIND_COUNT (sizeof kinds / sizeof kinds[0])

const medium_ops *medium_kind(const char *type)
{
    for (size_t i = 0; type && i < KIND_COUNT; ++i)
        if (strcmp(type, kinds[i]->name) == 0)
            return kinds[i];
    return NULL;
}

bool medium_type_volpath_only(const char *type)
{
    const medium_ops *ops = medium_kind(type);
    return ops && !ops->homogeneous && !ops->density_grid;
}

hz_status medium_create(medium_entity *e, transform render_from_world, const medium_times *times,
                        FILE *warn, medium *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    param_list *pl = &e->entity.params;
    const char *type = e->entity.type ? e->entity.type : "";
    /* pbrt-v4-scenes' explosion writes "LeScale" (pbrt-v4 itself refuses it
     * as unused): the same parameter as "Lescale". */
    if (params_has(pl, "LeScale") && params_has(pl, "Lescale"))
        params_reject(pl, "LeScale", "give one of \"Lescale\" and \"LeScale\", not both");
    else if (!params_rename(pl, "LeScale", "Lescale"))
        return hz_fail(err, "out of memory");
    const medium_ops *ops = medium_kind(type);
    if (!ops) {
        char names[200] = "";
        for (size_t i = 0; i < KIND_COUNT; ++i) {
            strcat(names, i ? ", \"" : "\"");
            strcat(names, kinds[i]->name);
            strcat(names, "\"");
        }
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": medium type \"%s\" is not supported "
                          "(supported: %s)",
                          e->name ? e->name : "", type, names);
    }
    medium_build b = {render_from_world, times, warn};
    out->ops = ops;
    if (ops->create(e, &b, out, err) != HZ_OK) {
        medium_destroy(out);
        memset(out, 0, sizeof *out);
        return HZ_ERROR;
    }
    return HZ_OK;
}

