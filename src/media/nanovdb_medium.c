/* "nanovdb": a density grid from a file: filename (.vdb or .nvdb, relative
 * to the scene file that declares the medium), gridname (default "density"),
 * and sigma_a, sigma_s, scale, g as every medium; the coefficients are per
 * unit density, so sigma_t(p) = (sigma_a + sigma_s) * scale * density(p).
 *   Motion blur from a velocity grid: velocityname (a vec3 grid of the same
 *   file; absent: none), velocityscale (default 1, >= 0), velocitytime
 *   (default: the TransformTimes start).
 *   Emission from a temperature grid, as pbrt-v4: temperaturename (default
 *   "temperature": used when the file has such a grid; named explicitly, it
 *   must exist), temperatureoffset (or its older name temperaturecutoff;
 *   default 0), temperaturescale (default 1), Lescale (default 1):
 *   Le(x) = Lescale B(T) with T = (value - offset) * scale, zero at or below
 *   100 K, B pbrt-v4's peak-normalised blackbody as its film sees it
 *   (media/blackbody.h). The temperature grid has its own transform and
 *   moves with the density (placement, velocity).
 *   haze's own: a free emission grid (emissionname, coloured by Le or by the
 *   temperature's blackbody, scaled by Lescale) and a colour grid
 *   (colorname) that scales the scattering albedo. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/path.h"
#include "media/grid_medium.h"
#include "media/medium.h"
#include "media/medium_params.h"

/* What MakeNamedMedium says about haze's own grids of a nanovdb medium. */
typedef struct {
    const char *emissionname; /* NULL: no free emission */
    rgb tint;                 /* luminance-normalised "Le" */
    double scale;             /* "Lescale" */
    const char *colorname;    /* NULL: no colour grid */
} extra_params;

static bool transforms_equal(const transform *a, const transform *b)
{
    return memcmp(&a->m, &b->m, sizeof a->m) == 0;
}

/* Loads the velocity grid `mp->velocityname` of `path` and derives what the
 * lookups and the motion bounds need. */
static hz_status load_velocity(medium_entity *e, const char *path, const grid_motion_params *mp,
                               grid *v, medium *out, hz_error *err)
{
    grid_medium *gm = grid_medium_of(out);
    const char *name = e->name ? e->name : "";
    file_loc loc = params_loc(&e->entity.params, "velocityname");
    double vmax = grid_max_value(v), vbg = grid_background(v);
    if (!isfinite(vmax) || !isfinite(vbg)) {
        grid_destroy(v);
        return hz_fail_at(err, loc,
                          "MakeNamedMedium \"%s\": velocity grid \"%s\" in %s has non-finite "
                          "values",
                          name, mp->velocityname, path);
    }
    vmax = fmax(vmax, vbg);
    const grid *d = gm->grid;
    transform d_world_from_index = grid_world_from_index_transform(d);
    transform v_world_from_index = grid_world_from_index_transform(v);
    gm->velocity = v;
    gm->velocity_aligned = transforms_equal(&d_world_from_index, &v_world_from_index);
    gm->vindex_from_index =
        transform_compose(transform_inverse(v_world_from_index), d_world_from_index);
    gm->velocity_scale = mp->scale;
    gm->velocity_time = mp->time;
    /* |displacement_i| <= |row_i(index_from_medium)| |v| |shift| (Cauchy–Schwarz). */
    const mat4 *r = &gm->index_from_medium.m;
    double row[3];
    for (int i = 0; i < 3; ++i)
        row[i] = vmax * sqrt(r->m[i][0] * r->m[i][0] + r->m[i][1] * r->m[i][1] +
                             r->m[i][2] * r->m[i][2]);
    vec3 lo, hi;
    gm->dilation = grid_support_bounds(d, &lo, &hi) ? v3(row[0], row[1], row[2])
                                                          : v3(0.0, 0.0, 0.0);
    if (!v3_is_finite(gm->dilation))
        return hz_fail_at(err, loc,
                          "MakeNamedMedium \"%s\": velocity grid \"%s\" in %s moves the "
                          "density too far (its bound is not finite)",
                          name, mp->velocityname, path);
    return HZ_OK;
}

/* Loads the temperature grid of `path` when there is one (or must be one),
 * and tabulates its blackbody over the range its values map to. */
static hz_status load_temperature(medium_entity *e, const char *path, const temperature_params *tp,
                                  bool colour_only, grid *t, medium *out, hz_error *err)
{
    grid_medium *gm = grid_medium_of(out);
    const char *name = e->name ? e->name : "";
    file_loc loc = tp->named ? params_loc(&e->entity.params, "temperaturename") : e->entity.loc;
    hz_error inner;
    if (!t) {
        /* No temperature grid: no emission, as pbrt-v4; but what would shape
         * it is not silently ignored. */
        static const char *const shaping[] = {"Lescale", "temperatureoffset", "temperaturecutoff",
                                              "temperaturescale"};
        /* Beside a free emission grid, Lescale scales that. */
        for (size_t i = colour_only ? 1 : 0; i < sizeof shaping / sizeof shaping[0]; ++i) {
            if (!params_has(&e->entity.params, shaping[i]))
                continue;
            if (colour_only)
                return hz_fail_at(err, params_loc(&e->entity.params, shaping[i]),
                                  "MakeNamedMedium \"%s\": \"%s\" needs a temperature grid "
                                  "(\"string temperaturename\") to colour the emission",
                                  name, shaping[i]);
            return hz_fail_at(err, params_loc(&e->entity.params, shaping[i]),
                              "MakeNamedMedium \"%s\": \"%s\" needs a temperature grid, "
                              "and %s has no grid \"%s\"",
                              name, shaping[i], path, tp->name);
        }
        return HZ_OK;
    }
    if (grid_check_finite(t, &inner) != HZ_OK) {
        grid_destroy(t);
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": temperature grid \"%s\" in %s: %s",
                          name, tp->name, path, inner.message);
    }
    transform d_world_from_index = grid_world_from_index_transform(gm->grid);
    transform t_world_from_index = grid_world_from_index_transform(t);
    gm->temperature_aligned = transforms_equal(&d_world_from_index, &t_world_from_index);
    gm->tindex_from_index =
        transform_compose(transform_inverse(t_world_from_index), d_world_from_index);
    gm->Le_scale = tp->Le_scale;
    bool emits = false;
    if (grid_medium_adopt_temperature(t, tp, gm, &emits, &inner) != HZ_OK)
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": temperature grid \"%s\" in %s: %s",
                          name, tp->name, path, inner.message);
    /* Beside a free emission grid the temperature only colours it. */
    gm->emission_by_temperature = colour_only;
    out->emissive = !colour_only && emits && tp->Le_scale > 0.0 && !rgb_is_black(out->sigma_a);
    return HZ_OK;
}

/* Grows the support box (density index space) by the support of the grid
 * whose index space `gindex_from_index` maps to: its box's corners mapped
 * back. */
static void grow_support(medium *out, const grid *g, const transform *gindex_from_index)
{
    grid_medium *gm = grid_medium_of(out);
    vec3 lo, hi;
    if (!grid_support_bounds(g, &lo, &hi))
        return;
    transform index_from_gindex = transform_inverse(*gindex_from_index);
    vec3 blo, bhi;
    transform_box(&index_from_gindex, lo, hi, &blo, &bhi);
    vec3 *slo = &gm->support_lo, *shi = &gm->support_hi;
    bool empty = !(slo->x <= shi->x);
    *slo = empty ? blo : v3(fmin(slo->x, blo.x), fmin(slo->y, blo.y), fmin(slo->z, blo.z));
    *shi = empty ? bhi : v3(fmax(shi->x, bhi.x), fmax(shi->y, bhi.y), fmax(shi->z, bhi.z));
}

/* Adopts the free emission grid E (the medium owns it from here): its values
 * are checked as a density's (finite, >= 0), and where it can glow joins the
 * support, so that neither clipping nor the majorant grid drops emission
 * where there is no density. */
static hz_status adopt_emission(medium_entity *e, const char *path, const extra_params *xp,
                                grid *E, medium *out, hz_error *err)
{
    grid_medium *gm = grid_medium_of(out);
    gm->emission = E;
    hz_error inner;
    if (grid_check_density(E, &inner) != HZ_OK)
        return hz_fail_at(err, params_loc(&e->entity.params, "emissionname"),
                          "MakeNamedMedium \"%s\": emission grid \"%s\" in %s: %s",
                          e->name ? e->name : "", xp->emissionname, path, inner.message);
    if (grid_background(E) != 0.0)
        return hz_fail_at(err, params_loc(&e->entity.params, "emissionname"),
                          "MakeNamedMedium \"%s\": emission grid \"%s\" in %s has background "
                          "%g; it must be 0 (all space would glow)",
                          e->name ? e->name : "", xp->emissionname, path, grid_background(E));
    gm->eindex_from_index =
        grid_medium_index_from_density_index(gm->grid, E, &gm->emission_aligned);
    gm->emission_tint = xp->tint;
    gm->emission_scale = xp->scale;
    out->free_emission = xp->scale > 0.0 && grid_max_value(E) > 0.0 &&
                         (gm->emission_by_temperature || !rgb_is_black(xp->tint));
    grow_support(out, E, &gm->eindex_from_index);
    return HZ_OK;
}

/* Adopts the colour grid C (a vec3 grid; the medium owns it from here).
 * Lookups clamp each channel to [0, 1], a NaN to 0, so no value can make an
 * albedo above 1 or below 0; non-finite statistics mark a broken file. */
static hz_status adopt_color(medium_entity *e, const char *path, const extra_params *xp, grid *C,
                             medium *out, hz_error *err)
{
    grid_medium *gm = grid_medium_of(out);
    gm->color = C;
    if (!isfinite(grid_max_value(C)) || !isfinite(grid_background(C)))
        return hz_fail_at(err, params_loc(&e->entity.params, "colorname"),
                          "MakeNamedMedium \"%s\": colour grid \"%s\" in %s has non-finite "
                          "values",
                          e->name ? e->name : "", xp->colorname, path);
    gm->cindex_from_index =
        grid_medium_index_from_density_index(gm->grid, C, &gm->color_aligned);
    out->coloured = !rgb_is_black(out->sigma_s);
    return HZ_OK;
}

/* Every grid the medium needs, read from its file at once. */
typedef struct {
    grid *grids[5]; /* density, velocity, temperature, emission, colour (as requested) */
    size_t at[5];   /* at[k]: where grid kind k is in grids, 0: absent */
    size_t count;
} grid_set;

/* Reads every grid the medium needs in one read of the file (one OpenVDB
 * reader process for a .vdb file): density, velocity, temperature (of the
 * file, as pbrt-v4, unless a free emission grid is named: then only when
 * named), emission, colour. */
static hz_status read_grids(medium_entity *e, const char *path, const char *gridname,
                            const grid_motion_params *mp, const temperature_params *tp,
                            const extra_params *xp, grid_set *set, hz_error *err)
{
    const char *name = medium_entity_name(e);
    grid_request req[5] = {{gridname, GRID_FLOAT, false}};
    const char *what[5] = {"grid", "velocity grid", "temperature grid", "emission grid",
                           "colour grid"};
    const char *param[5] = {NULL, "velocityname", "temperaturename", "emissionname",
                            "colorname"};
    *set = (grid_set){{NULL, NULL, NULL, NULL, NULL}, {0}, 1};
    if (mp->velocityname) {
        set->at[1] = set->count;
        req[set->count++] = (grid_request){mp->velocityname, GRID_VEC3, false};
    }
    if (!xp->emissionname || tp->named) {
        set->at[2] = set->count;
        req[set->count++] = (grid_request){tp->name, GRID_FLOAT, !tp->named};
    }
    if (xp->emissionname) {
        set->at[3] = set->count;
        req[set->count++] = (grid_request){xp->emissionname, GRID_FLOAT, false};
    }
    if (xp->colorname) {
        set->at[4] = set->count;
        req[set->count++] = (grid_request){xp->colorname, GRID_VEC3, false};
    }
    size_t failed = 0;
    hz_error inner;
    if (grid_load_set(path, req, set->count, set->grids, &failed, &inner) == HZ_OK)
        return HZ_OK;
    if (failed == 0)
        return hz_fail_at(err, e->entity.loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
    size_t k = 1;
    while (k < 4 && set->at[k] != failed)
        ++k;
    file_loc where = params_has(&e->entity.params, param[k])
                         ? params_loc(&e->entity.params, param[k])
                         : e->entity.loc;
    return hz_fail_at(err, where, "MakeNamedMedium \"%s\": %s: %s", name, what[k],
                      inner.message);
}

/* Checks and places the density grid g and adopts it with its support.
 * Densities must be finite and >= 0: the majorant-based trackers treat
 * sigma_t(p) / sigma_t_max as a probability, which a negative density breaks
 * (and pbrt-v4 has no meaning for it either), so grid_check_density refuses
 * such values (the voxels themselves, not the stored statistics) rather than
 * clamping them. On failure g is not adopted. */
static hz_status adopt_density(medium_entity *e, transform render_from_world, const char *path,
                               const char *gridname, const grid_motion_params *mp, grid *g,
                               grid_medium *gm, hz_error *err)
{
    file_loc loc = e->entity.loc;
    const char *name = medium_entity_name(e);
    hz_error inner;
    if (grid_check_density(g, &inner) != HZ_OK)
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": grid \"%s\" in %s: %s", name,
                          gridname, path, inner.message);
    vec3 lo, hi;
    bool nonempty = grid_support_bounds(g, &lo, &hi);
    /* grid_check_density refused non-finite and negative values (and
     * background): only a non-zero background is left to refuse. */
    double background = grid_background(g);
    if (background != 0.0)
        return hz_fail_at(err, loc,
                          "MakeNamedMedium \"%s\": grid \"%s\" in %s has background %g; haze "
                          "needs a fog volume with background 0 (the medium would otherwise "
                          "fill all space)",
                          name, gridname, path, background);
    if (grid_medium_place(e, render_from_world, g, mp, gm, err) != HZ_OK)
        return HZ_ERROR;
    gm->grid = g;
    gm->support_lo = nonempty ? lo : v3(1, 1, 1);
    gm->support_hi = nonempty ? hi : v3(-1, -1, -1);
    gm->background = background;
    gm->density_max = nonempty ? grid_max_value(g) : 0.0; /* values >= 0 = background */
    return HZ_OK;
}

/* Loads the grid and places it, with its velocity, temperature, emission
 * and colour grids. */
static hz_status load_grid(medium_entity *e, transform render_from_world, const char *filename,
                           const char *gridname, const grid_motion_params *mp,
                           const temperature_params *tp, const extra_params *xp, medium *out,
                           hz_error *err)
{
    char *path = path_of_scene_file(e->entity.loc, filename);
    if (!path)
        return hz_fail_at(err, e->entity.loc, "MakeNamedMedium \"%s\": out of memory",
                          medium_entity_name(e));
    grid_set set;
    hz_status st = read_grids(e, path, gridname, mp, tp, xp, &set, err);
    if (st == HZ_OK)
        st = adopt_density(e, render_from_world, path, gridname, mp, set.grids[0],
                           grid_medium_of(out), err);
    if (st != HZ_OK) {
        for (size_t i = 0; i < set.count; ++i)
            grid_destroy(set.grids[i]);
        free(path);
        return HZ_ERROR;
    }
    /* Each step takes its grid (adopts it, or destroys it); after a failure
     * the rest are destroyed. The caller frees what was adopted. */
    const size_t *at = set.at;
    grid **grids = set.grids;
    if (at[1])
        st = load_velocity(e, path, mp, grids[at[1]], out, err);
    bool colour_only = xp->emissionname != NULL;
    if (st == HZ_OK)
        st = load_temperature(e, path, tp, colour_only, at[2] ? grids[at[2]] : NULL, out, err);
    else if (at[2])
        grid_destroy(grids[at[2]]);
    if (st == HZ_OK && at[3])
        st = adopt_emission(e, path, xp, grids[at[3]], out, err);
    else if (at[3])
        grid_destroy(grids[at[3]]);
    if (st == HZ_OK && at[4])
        st = adopt_color(e, path, xp, grids[at[4]], out, err);
    else if (at[4])
        grid_destroy(grids[at[4]]);
    free(path);
    return st;
}

/* The nanovdb medium's own parameters (problems are recorded in pl). */
typedef struct {
    const char *filename, *gridname;
    grid_motion_params mp;
    temperature_params tp;
    extra_params xp;
} nanovdb_params;

static void read_motion(param_list *pl, grid_motion_params *mp)
{
    mp->velocityname = params_string(pl, "velocityname", NULL);
    mp->scale = params_float(pl, "velocityscale", 1.0);
    mp->time = params_float(pl, "velocitytime", mp->time_start);
    if (!mp->velocityname) {
        const char *p = params_has(pl, "velocityscale") ? "velocityscale" : "velocitytime";
        if (params_has(pl, p))
            params_reject(pl, p, "\"%s\" needs a velocity grid (\"string velocityname\")", p);
    } else if (!mp->velocityname[0]) {
        params_reject(pl, "velocityname", "\"velocityname\" is empty");
    }
    if (!(isfinite(mp->scale) && mp->scale >= 0.0))
        params_reject(pl, "velocityscale",
                      "\"velocityscale\" must be finite and non-negative, got %g", mp->scale);
    if (!isfinite(mp->time))
        params_reject(pl, "velocitytime", "\"velocitytime\" must be finite, got %g", mp->time);
}

static void read_nanovdb(param_list *pl, const medium_common_params *c, nanovdb_params *np)
{
    np->filename = params_string(pl, "filename", NULL);
    np->gridname = params_string(pl, "gridname", "density");
    read_motion(pl, &np->mp);
    /* Emission from a temperature grid of the file, as pbrt-v4. */
    temperature_params *tp = &np->tp;
    tp->named = params_has(pl, "temperaturename");
    tp->name = params_string(pl, "temperaturename", "temperature");
    if (!tp->name[0])
        params_reject(pl, "temperaturename", "\"temperaturename\" is empty");
    medium_params_temperature(pl, tp);
    tp->Le_scale = c->Le_scale;
    /* haze's own: a free emission grid and a colour grid. */
    extra_params *xp = &np->xp;
    *xp = (extra_params){NULL, c->Le, c->Le_scale, NULL};
    xp->emissionname = params_string(pl, "emissionname", NULL);
    xp->colorname = params_string(pl, "colorname", NULL);
    const char *names[2] = {"emissionname", "colorname"};
    const char *given[2] = {xp->emissionname, xp->colorname};
    for (int k = 0; k < 2; ++k)
        if (given[k] && !given[k][0])
            params_reject(pl, names[k], "\"%s\" is empty", names[k]);
    if (xp->emissionname && tp->named && params_has(pl, "Le"))
        params_reject(pl, "Le",
                      "give \"Le\" (one colour) or \"temperaturename\" (each voxel's "
                      "blackbody colour) to colour the emission grid, not both");
}

/* Says when a grid's inactive voxels held values other than the
 * background (grid_check_density and grid_check_finite made them hold it):
 * pbrt-v4 would read them. */
static void warn_folded(medium_entity *e, FILE *warn, const char *filename, const grid *g)
{
    uint64_t n = g ? grid_inactive_folded(g) : 0;
    if (n)
        hz_warn_at(warn, e->entity.loc,
                   "MakeNamedMedium \"%s\": grid \"%s\" in %s: %llu inactive voxels hold "
                   "values other than the background (%g); haze takes them as the background, "
                   "as OpenVDB defines inactive voxels (pbrt-v4 reads their values)",
                   medium_entity_name(e), grid_name(g), filename, (unsigned long long)n,
                   (double)grid_background(g));
}

static hz_status create(medium_entity *e, const medium_build *b, medium *out, hz_error *err)
{
    param_list *pl = &e->entity.params;
    /* On a medium with a free emission grid, "Le" is its colour. */
    bool free_emission = params_has(pl, "emissionname");
    medium_param_rules rules = {true, true, free_emission ? MEDIUM_LE_TINT : MEDIUM_LE_NONE, true};
    medium_common_params c;
    medium_params_read(pl, &rules, &c);
    medium_params_check_emission(pl, &c);
    nanovdb_params np;
    np.mp = (grid_motion_params){NULL, 1.0, b->times->transform_start,
                                 b->times->transform_start, b->times->transform_end};
    np.tp = (temperature_params){"temperature", false, 0.0, 1.0, 1.0};
    read_nanovdb(pl, &c, &np);
    if (medium_params_finish(e, &c, out, err) != HZ_OK)
        return HZ_ERROR;
    const char *name = medium_entity_name(e);
    if (!np.filename || !np.filename[0])
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": a \"nanovdb\" medium needs \"string filename\"",
                          name);
    if (!np.gridname[0])
        return hz_fail_at(err, params_loc(pl, "gridname"),
                          "MakeNamedMedium \"%s\": \"gridname\" is empty", name);
    if (!grid_medium_alloc(out))
        return hz_fail(err, "out of memory");
    if (load_grid(e, b->render_from_world, np.filename, np.gridname, &np.mp, &np.tp, &np.xp, out,
                  err) != HZ_OK)
        return HZ_ERROR;
    const grid_medium *gm = grid_medium_of(out);
    const grid *checked[3] = {gm->grid, gm->temperature, gm->emission};
    for (int k = 0; k < 3; ++k)
        warn_folded(e, b->warn, np.filename, checked[k]);
    return grid_medium_build_majorants(out, b->times, err);
}

const medium_ops medium_nanovdb_ops = {
    .name = "nanovdb",
    .create = create,
    GRID_MEDIUM_DENSITY_OPS,
};
