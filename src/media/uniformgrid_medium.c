/* "uniformgrid": pbrt-v4's dense grid (media/uniformgrid.h): nx, ny, nz,
 * density (nx ny nz floats), p0, p1, and sigma_a, sigma_s, scale, g as every
 * medium; emission from temperature (as many floats, with
 * temperatureoffset/cutoff and temperaturescale) or Le, times the Lescale
 * grid (as many floats; absent: one sample of 1 at the box's centre, which
 * pbrt-v4 interpolates to 1/8 at the corners). */
#include <math.h>

#include "media/grid_medium.h"
#include "media/medium.h"
#include "media/medium_params.h"
#include "media/uniformgrid.h"

/* pbrt-v4's "uniformgrid" (media/uniformgrid.h): the dense arrays as NanoVDB
 * grids placed in medium space, the support clipped to the box p0..p1, the
 * Lescale grid (one sample of 1 when absent, as pbrt-v4) and the temperature
 * or Le. */
static hz_status build_uniformgrid(medium_entity *e, transform render_from_world,
                                   const uniformgrid_params *u, const temperature_params *tp,
                                   rgb Le, const medium_times *times, medium *out, hz_error *err)
{
    file_loc loc = e->entity.loc;
    const char *name = e->name ? e->name : "";
    size_t count = (size_t)u->n[0] * (size_t)u->n[1] * (size_t)u->n[2];
    hz_error inner;
    grid_medium *gm = grid_medium_of(out);
    if (grid_medium_adopt_dense(e, render_from_world, u, u->density, "density", times, gm, err) !=
        HZ_OK)
        return HZ_ERROR;
    grid *g = gm->grid;

    const double one = 1.0;
    grid *ls = NULL;
    if (uniformgrid_make(u, u->Le_scale ? u->Le_scale : &one, u->Le_scale ? count : 1, "Lescale",
                         &ls, &inner) != HZ_OK)
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
    gm->Le_scale_grid = ls;
    gm->Le_scale = 1.0;
    transform d_world_from_index = grid_world_from_index_transform(g);
    gm->lsindex_from_index =
        transform_compose(transform_inverse(grid_world_from_index_transform(ls)),
                          d_world_from_index);
    bool emits = !rgb_is_black(Le);
    if (u->temperature) {
        grid *t = NULL;
        if (uniformgrid_make(u, u->temperature, count, "temperature", &t, &inner) != HZ_OK ||
            grid_check_finite(t, &inner) != HZ_OK) {
            grid_destroy(t);
            return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
        }
        gm->temperature_aligned = true;
        gm->tindex_from_index = transform_identity();
        if (grid_medium_adopt_temperature(t, tp, gm, &emits, &inner) != HZ_OK)
            return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": temperature: %s", name,
                              inner.message);
    } else {
        out->Le = Le;
    }
    out->emissive = emits && grid_max_value(ls) > 0.0f && !rgb_is_black(out->sigma_a);
    return grid_medium_build_majorants(out, times, err);
}

static hz_status create(medium_entity *e, const medium_build *b, medium *out, hz_error *err)
{
    param_list *pl = &e->entity.params;
    medium_param_rules rules = {true, true, MEDIUM_LE_READ, false};
    medium_common_params c;
    medium_params_read(pl, &rules, &c);
    medium_params_check_emission(pl, &c);
    uniformgrid_params ug = {{1, 1, 1}, {0, 0, 0}, {1, 1, 1}, NULL, NULL, NULL};
    temperature_params tp = {"temperature", false, 0.0, 1.0, 1.0};
    uniformgrid_read(pl, &ug);
    medium_params_temperature(pl, &tp);
    tp.Le_scale = 1.0;
    if (ug.temperature && params_has(pl, "Le"))
        params_reject(pl, "Le", "give \"Le\" or \"temperature\", not both (as pbrt-v4)");
    if (medium_params_finish(e, &c, out, err) != HZ_OK)
        return HZ_ERROR;
    if (!grid_medium_alloc(out))
        return hz_fail(err, "out of memory");
    return build_uniformgrid(e, b->render_from_world, &ug, &tp, c.Le, b->times, out, err);
}

const medium_ops medium_uniformgrid_ops = {
    .name = "uniformgrid",
    .create = create,
    GRID_MEDIUM_DENSITY_OPS,
};
