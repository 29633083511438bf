#include "media/medium.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/box.h"
#include "core/path.h"
#include "media/presets.h"
#include "media/uniformgrid.h"
#include "scene/spectrum.h"

static bool rgb_is_finite(rgb c) { return isfinite(c.r) && isfinite(c.g) && isfinite(c.b); }

/* A coefficient spectrum: finite and non-negative in every channel. */
static rgb read_sigma(param_list *pl, const char *name)
{
    rgb s = params_rgb(pl, name, rgb_grey(1.0));
    if (!rgb_is_finite(s) || s.r < 0.0 || s.g < 0.0 || s.b < 0.0)
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

static bool transform_is_finite(const transform *t)
{
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (!isfinite(t->m.m[r][c]) || !isfinite(t->m_inv.m[r][c]))
                return false;
    return true;
}

/* What MakeNamedMedium says about a grid's emission. */
typedef struct {
    const char *name;     /* temperaturename */
    bool named;           /* given explicitly: the grid must exist */
    double offset, scale; /* temperatureoffset (or temperaturecutoff), temperaturescale */
    double Le_scale;      /* Lescale */
} temperature_params;

/* What MakeNamedMedium says about haze's own grids of a nanovdb medium. */
typedef struct {
    const char *emissionname; /* NULL: no free emission */
    rgb tint;                 /* luminance-normalised "Le" */
    double scale;             /* "Lescale" */
    const char *colorname;    /* NULL: no colour grid */
} extra_params;

/* What MakeNamedMedium says about a grid's motion. */
typedef struct {
    const char *velocityname; /* NULL: no velocity grid */
    double scale, time;       /* velocityscale, velocitytime */
    double time_start, time_end; /* TransformTimes */
} motion_params;

static bool transforms_equal(const transform *a, const transform *b)
{
    return memcmp(&a->m, &b->m, sizeof a->m) == 0;
}

/* The placement of the grid at both keyframes: animated when they differ. */
static hz_status place_grid(medium_entity *e, transform render_from_world, const grid *g,
                            const motion_params *mp, medium *out, hz_error *err)
{
    const char *name = e->name ? e->name : "";
    transform world_from_index = grid_world_from_index_transform(g);
    out->grid.index_from_medium = transform_inverse(world_from_index);
    transform render_from_index = transform_compose(
        render_from_world, transform_compose(e->world_from_medium, world_from_index));
    out->grid.index_from_render = transform_inverse(render_from_index);
    bool finite = transform_is_finite(&out->grid.index_from_render);
    animated_transform a = animated_transform_make(
        transform_compose(render_from_world, e->world_from_medium), mp->time_start,
        transform_compose(render_from_world, e->world_from_medium_end), mp->time_end);
    if (finite && a.animated) {
        out->grid.moving = true;
        out->grid.render_from_medium = a;
        transform end = transform_inverse(transform_compose(a.end, world_from_index));
        finite = transform_is_finite(&end);
    }
    if (!finite)
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": the grid's placement (its transform times "
                          "the current transform) is singular or not finite",
                          name);
    return HZ_OK;
}

/* Loads the velocity grid `mp->velocityname` of `path` and derives what the
 * lookups and the motion bounds need. */
static hz_status load_velocity(medium_entity *e, const char *path, const motion_params *mp,
                               grid *v, medium *out, hz_error *err)
{
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
    const grid *d = out->grid.grid;
    transform d_world_from_index = grid_world_from_index_transform(d);
    transform v_world_from_index = grid_world_from_index_transform(v);
    out->grid.velocity = v;
    out->grid.velocity_aligned = transforms_equal(&d_world_from_index, &v_world_from_index);
    out->grid.vindex_from_index =
        transform_compose(transform_inverse(v_world_from_index), d_world_from_index);
    out->grid.velocity_scale = mp->scale;
    out->grid.velocity_time = mp->time;
    /* |displacement_i| <= |row_i(index_from_medium)| |v| |shift| (Cauchy–Schwarz). */
    const mat4 *r = &out->grid.index_from_medium.m;
    double row[3];
    for (int i = 0; i < 3; ++i)
        row[i] = vmax * sqrt(r->m[i][0] * r->m[i][0] + r->m[i][1] * r->m[i][1] +
                             r->m[i][2] * r->m[i][2]);
    vec3 lo, hi;
    out->grid.dilation = grid_support_bounds(d, &lo, &hi) ? v3(row[0], row[1], row[2])
                                                          : v3(0.0, 0.0, 0.0);
    if (!v3_is_finite(out->grid.dilation))
        return hz_fail_at(err, loc,
                          "MakeNamedMedium \"%s\": velocity grid \"%s\" in %s moves the "
                          "density too far (its bound is not finite)",
                          name, mp->velocityname, path);
    return HZ_OK;
}

/* The temperature grid t (its values lie within the active values and the
 * background, trilinear values too) adopted by `out`: the offset and scale,
 * and the blackbody tabulated over the kelvins they map to. *emits: some of
 * them are above 100 K. */
static hz_status adopt_temperature(grid *t, const temperature_params *tp, medium *out,
                                   bool *emits, hz_error *err)
{
    out->grid.temperature = t;
    out->grid.temperature_offset = tp->offset;
    out->grid.temperature_scale = tp->scale;
    double bg = grid_background(t);
    double v0 = fmin(grid_min_value(t), bg), v1 = fmax(grid_max_value(t), bg);
    double a = (v0 - tp->offset) * tp->scale, b = (v1 - tp->offset) * tp->scale;
    return blackbody_table_build(&out->grid.blackbody, fmin(a, b), fmax(a, b), emits, err);
}

/* Loads the temperature grid of `path` when there is one (or must be one),
 * and tabulates its blackbody over the range its values map to. */
static hz_status load_temperature(medium_entity *e, const char *path, const temperature_params *tp,
                                  bool colour_only, grid *t, medium *out, hz_error *err)
{
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
    transform d_world_from_index = grid_world_from_index_transform(out->grid.grid);
    transform t_world_from_index = grid_world_from_index_transform(t);
    out->grid.temperature_aligned = transforms_equal(&d_world_from_index, &t_world_from_index);
    out->grid.tindex_from_index =
        transform_compose(transform_inverse(t_world_from_index), d_world_from_index);
    out->grid.Le_scale = tp->Le_scale;
    bool emits = false;
    if (adopt_temperature(t, tp, out, &emits, &inner) != HZ_OK)
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": temperature grid \"%s\" in %s: %s",
                          name, tp->name, path, inner.message);
    /* Beside a free emission grid the temperature only colours it. */
    out->grid.emission_by_temperature = colour_only;
    out->emissive = !colour_only && emits && tp->Le_scale > 0.0 && !rgb_is_black(out->sigma_a);
    return HZ_OK;
}

/* The transform from the density grid's index space to `g`'s, and whether
 * they are the same. */
static transform index_from_density_index(const grid *density, const grid *g, bool *aligned)
{
    transform d_world_from_index = grid_world_from_index_transform(density);
    transform g_world_from_index = grid_world_from_index_transform(g);
    *aligned = transforms_equal(&d_world_from_index, &g_world_from_index);
    return transform_compose(transform_inverse(g_world_from_index), d_world_from_index);
}

/* Grows the support box (density index space) by the support of the grid
 * whose index space `gindex_from_index` maps to: its box's corners mapped
 * back. */
static void grow_support(medium *out, const grid *g, const transform *gindex_from_index)
{
    vec3 lo, hi;
    if (!grid_support_bounds(g, &lo, &hi))
        return;
    transform index_from_gindex = transform_inverse(*gindex_from_index);
    vec3 blo, bhi;
    transform_box(&index_from_gindex, lo, hi, &blo, &bhi);
    vec3 *slo = &out->grid.support_lo, *shi = &out->grid.support_hi;
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
    out->grid.emission = E;
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
    out->grid.eindex_from_index =
        index_from_density_index(out->grid.grid, E, &out->grid.emission_aligned);
    out->grid.emission_tint = xp->tint;
    out->grid.emission_scale = xp->scale;
    out->free_emission = xp->scale > 0.0 && grid_max_value(E) > 0.0 &&
                         (out->grid.emission_by_temperature || !rgb_is_black(xp->tint));
    grow_support(out, E, &out->grid.eindex_from_index);
    return HZ_OK;
}

/* Adopts the colour grid C (a vec3 grid; the medium owns it from here).
 * Lookups clamp each channel to [0, 1], a NaN to 0, so no value can make an
 * albedo above 1 or below 0; non-finite statistics mark a broken file. */
static hz_status adopt_color(medium_entity *e, const char *path, const extra_params *xp, grid *C,
                             medium *out, hz_error *err)
{
    out->grid.color = C;
    if (!isfinite(grid_max_value(C)) || !isfinite(grid_background(C)))
        return hz_fail_at(err, params_loc(&e->entity.params, "colorname"),
                          "MakeNamedMedium \"%s\": colour grid \"%s\" in %s has non-finite "
                          "values",
                          e->name ? e->name : "", xp->colorname, path);
    out->grid.cindex_from_index =
        index_from_density_index(out->grid.grid, C, &out->grid.color_aligned);
    out->coloured = !rgb_is_black(out->sigma_s);
    return HZ_OK;
}

/* Loads the grid and places it. Densities must be finite and >= 0: the
 * majorant-based trackers treat sigma_t(p) / sigma_t_max as a probability,
 * which a negative density breaks (and pbrt-v4 has no meaning for it either),
 * so grid_check_density refuses such values (the voxels themselves, not the
 * stored statistics) rather than clamping them. */
static hz_status load_grid(medium_entity *e, transform render_from_world, const char *filename,
                           const char *gridname, const motion_params *mp,
                           const temperature_params *tp, const extra_params *xp, medium *out,
                           hz_error *err)
{
    file_loc loc = e->entity.loc;
    const char *name = e->name ? e->name : "";
    char *path = path_of_scene_file(loc, filename);
    if (!path)
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": out of memory", name);
    /* Every grid the medium needs, in one read of the file (one OpenVDB
     * reader process for a .vdb file): density, velocity, temperature (of
     * the file, as pbrt-v4, unless a free emission grid is named: then only
     * when named), emission, colour. Index 0 (the density) marks the absent. */
    grid_request req[5] = {{gridname, GRID_FLOAT, false}};
    const char *what[5] = {"grid", "velocity grid", "temperature grid", "emission grid",
                           "colour grid"};
    const char *param[5] = {NULL, "velocityname", "temperaturename", "emissionname",
                            "colorname"};
    size_t nreq = 1, at[5] = {0}; /* at[k]: where grid kind k is in req, 0: absent */
    if (mp->velocityname) {
        at[1] = nreq;
        req[nreq++] = (grid_request){mp->velocityname, GRID_VEC3, false};
    }
    if (!xp->emissionname || tp->named) {
        at[2] = nreq;
        req[nreq++] = (grid_request){tp->name, GRID_FLOAT, !tp->named};
    }
    if (xp->emissionname) {
        at[3] = nreq;
        req[nreq++] = (grid_request){xp->emissionname, GRID_FLOAT, false};
    }
    if (xp->colorname) {
        at[4] = nreq;
        req[nreq++] = (grid_request){xp->colorname, GRID_VEC3, false};
    }
    grid *grids[5] = {NULL, NULL, NULL, NULL, NULL};
    size_t failed = 0;
    hz_error inner;
    hz_status st = grid_load_set(path, req, nreq, grids, &failed, &inner);
    if (st != HZ_OK) {
        free(path);
        if (failed == 0)
            return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
        size_t k = 1;
        while (k < 4 && at[k] != failed)
            ++k;
        file_loc where = params_has(&e->entity.params, param[k])
                             ? params_loc(&e->entity.params, param[k])
                             : e->entity.loc;
        return hz_fail_at(err, where, "MakeNamedMedium \"%s\": %s: %s", name, what[k],
                          inner.message);
    }
    grid *g = grids[0];

    if (grid_check_density(g, &inner) != HZ_OK) {
        st = hz_fail_at(err, loc, "MakeNamedMedium \"%s\": grid \"%s\" in %s: %s", name,
                        gridname, path, inner.message);
        grid_destroy(g);
        free(path);
        return st;
    }
    vec3 lo, hi;
    bool nonempty = grid_support_bounds(g, &lo, &hi);
    /* grid_check_density refused non-finite and negative values (and
     * background): only a non-zero background is left to refuse. */
    double background = grid_background(g);
    if (background != 0.0)
        st = hz_fail_at(err, loc,
                        "MakeNamedMedium \"%s\": grid \"%s\" in %s has background %g; haze "
                        "needs a fog volume with background 0 (the medium would otherwise fill "
                        "all space)",
                        name, gridname, path, background);
    if (st == HZ_OK)
        st = place_grid(e, render_from_world, g, mp, out, err);
    if (st != HZ_OK) {
        free(path);
        for (size_t i = 0; i < nreq; ++i)
            grid_destroy(grids[i]);
        return HZ_ERROR;
    }

    out->grid.grid = g;
    if (nonempty) {
        out->grid.support_lo = lo;
        out->grid.support_hi = hi;
    } else {
        out->grid.support_lo = v3(1, 1, 1);
        out->grid.support_hi = v3(-1, -1, -1);
    }
    out->grid.background = background;
    out->grid.density_max = nonempty ? grid_max_value(g) : 0.0; /* values >= 0 = background */
    /* Each step takes its grid (adopts it, or destroys it); after a failure
     * the rest are destroyed. The caller frees what was adopted. */
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

/* The majorant grid over the support; with a velocity grid the support
 * grows by the largest displacement at any ray time, and every cell's box of
 * voxels read by as much, so one grid bounds the density wherever it is
 * carried, at every time. */
static hz_status build_majorants(medium *m, const medium_times *times, hz_error *err)
{
    int32_t pad[3] = {0, 0, 0};
    vec3 lo = m->grid.support_lo, hi = m->grid.support_hi;
    if (m->grid.velocity && lo.x <= hi.x) {
        double t0 = fmin(times->ray_min, times->transform_start);
        double t1 = fmax(times->ray_max, times->transform_end);
        double shift = m->grid.velocity_scale * fmax(fabs(t0 - m->grid.velocity_time),
                                                     fabs(t1 - m->grid.velocity_time));
        const double d3[3] = {m->grid.dilation.x, m->grid.dilation.y, m->grid.dilation.z};
        for (int a = 0; a < 3; ++a) {
            double p = ceil(d3[a] * shift);
            pad[a] = p < (double)(1 << 28) ? (int32_t)p : (1 << 28);
        }
        lo = v3_sub(lo, v3(pad[0], pad[1], pad[2]));
        hi = v3_add(hi, v3(pad[0], pad[1], pad[2]));
    }
    majorant_emission em = {m->grid.emission, m->grid.emission_aligned,
                            m->grid.eindex_from_index};
    return majorant_grid_build(m->grid.grid, m->free_emission ? &em : NULL, lo, hi, pad,
                               &m->grid.majorant, err);
}

/* The dense samples `values` (uniformgrid_params' counts) as the medium's
 * density grid: placed by the CTM, the support clipped to the box p0..p1, as
 * pbrt-v4's SampledGrid clips. */
static hz_status adopt_dense_grid(medium_entity *e, transform render_from_world,
                                  const uniformgrid_params *u, const double *values,
                                  const char *what, const medium_times *times, medium *out,
                                  hz_error *err)
{
    size_t count = (size_t)u->n[0] * (size_t)u->n[1] * (size_t)u->n[2];
    hz_error inner;
    grid *g = NULL;
    if (uniformgrid_make(u, values, count, what, &g, &inner) != HZ_OK ||
        grid_check_density(g, &inner) != HZ_OK) {
        grid_destroy(g);
        return hz_fail_at(err, e->entity.loc, "MakeNamedMedium \"%s\": %s",
                          e->name ? e->name : "", inner.message);
    }
    motion_params mp = {NULL, 1.0, times->transform_start, times->transform_start,
                        times->transform_end};
    if (place_grid(e, render_from_world, g, &mp, out, err) != HZ_OK) {
        grid_destroy(g);
        return HZ_ERROR;
    }
    out->grid.grid = g;
    vec3 lo, hi, blo, bhi;
    uniformgrid_support(u, &blo, &bhi);
    bool nonempty = grid_support_bounds(g, &lo, &hi);
    out->grid.support_lo = nonempty ? v3(fmax(lo.x, blo.x), fmax(lo.y, blo.y), fmax(lo.z, blo.z))
                                    : v3(1, 1, 1);
    out->grid.support_hi = nonempty ? v3(fmin(hi.x, bhi.x), fmin(hi.y, bhi.y), fmin(hi.z, bhi.z))
                                    : v3(-1, -1, -1);
    out->grid.background = 0.0;
    out->grid.density_max = nonempty ? grid_max_value(g) : 0.0;
    return HZ_OK;
}

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
    if (adopt_dense_grid(e, render_from_world, u, u->density, "density", times, out, err) !=
        HZ_OK)
        return HZ_ERROR;
    grid *g = out->grid.grid;

    const double one = 1.0;
    grid *ls = NULL;
    if (uniformgrid_make(u, u->Le_scale ? u->Le_scale : &one, u->Le_scale ? count : 1, "Lescale",
                         &ls, &inner) != HZ_OK)
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
    out->grid.Le_scale_grid = ls;
    out->grid.Le_scale = 1.0;
    transform d_world_from_index = grid_world_from_index_transform(g);
    out->grid.lsindex_from_index =
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
        out->grid.temperature_aligned = true;
        out->grid.tindex_from_index = transform_identity();
        if (adopt_temperature(t, tp, out, &emits, &inner) != HZ_OK)
            return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": temperature: %s", name,
                              inner.message);
    } else {
        out->Le = Le;
    }
    out->emissive = emits && grid_max_value(ls) > 0.0f && !rgb_is_black(out->sigma_a);
    return build_majorants(out, times, err);
}

/* pbrt-v4's "rgbgrid": grid.grid holds the largest channel of
 * sigma_a + sigma_s per sample (the majorant's source; an absent array
 * counts 1), the channels are grids of their own in the same index space. */
static hz_status build_rgbgrid(medium_entity *e, transform render_from_world,
                               const rgbgrid_params *r, double scale, double Le_scale,
                               const medium_times *times, medium *out, hz_error *err)
{
    file_loc loc = e->entity.loc;
    const char *name = e->name ? e->name : "";
    const uniformgrid_params *u = &r->box;
    size_t count = (size_t)u->n[0] * (size_t)u->n[1] * (size_t)u->n[2];
    out->kind = MEDIUM_RGBGRID;
    /* sigma_t = 1 per unit of grid.grid: the majorant is the grid's bound. */
    out->sigma_a = rgb_grey(0.0);
    out->sigma_s = rgb_grey(1.0);
    out->rgbg.scale = scale;
    /* pbrt-v4 takes each sample's Le as an RGB illuminant spectrum without
     * dividing it by its luminance (unlike a light's or a homogeneous
     * medium's Le): its film sees rgb (1, 1, 1) as luminance 106.86. */
    out->rgbg.Le_scale = Le_scale * SPECTRUM_CIE_Y_INTEGRAL;
    double *mx = malloc(count * sizeof *mx);
    if (!mx)
        return hz_fail(err, "out of memory");
    for (size_t i = 0; i < count; ++i) {
        double a = 1.0, b = 1.0;
        if (r->sigma_a)
            a = fmax(r->sigma_a[3 * i], fmax(r->sigma_a[3 * i + 1], r->sigma_a[3 * i + 2]));
        if (r->sigma_s)
            b = fmax(r->sigma_s[3 * i], fmax(r->sigma_s[3 * i + 1], r->sigma_s[3 * i + 2]));
        mx[i] = scale * (a + b);
    }
    hz_error inner;
    hz_status st =
        adopt_dense_grid(e, render_from_world, u, mx, "sigma_a + sigma_s", times, out, err);
    free(mx);
    if (st != HZ_OK)
        return HZ_ERROR;
    const double *arrays[3] = {r->sigma_a, r->sigma_s, r->Le};
    const char *names[3] = {"sigma_a", "sigma_s", "Le"};
    grid **slots[3] = {out->rgbg.sigma_a, out->rgbg.sigma_s, out->rgbg.Le};
    for (int k = 0; k < 3; ++k)
        for (int c = 0; arrays[k] && c < 3; ++c)
            if (uniformgrid_make_channel(u, arrays[k], c, names[k], &slots[k][c], &inner) !=
                HZ_OK)
                return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
    out->emissive = r->Le && Le_scale > 0.0;
    return build_majorants(out, times, err);
}

/* The temperature parameters of a nanovdb or uniformgrid medium (problems
 * are recorded in pl). */
static void read_temperature_params(param_list *pl, temperature_params *tp)
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

hz_status medium_from_entity(medium_entity *e, transform render_from_world,
                             const medium_times *times, medium *out, hz_error *err)
{
    double time_start = times->transform_start, time_end = times->transform_end;
    memset(out, 0, sizeof *out);
    param_list *pl = &e->entity.params;
    const char *type = e->entity.type ? e->entity.type : "";
    const char *name = e->name ? e->name : "";
    /* pbrt-v4-scenes' explosion writes "LeScale" (pbrt-v4 itself refuses it
     * as unused): the same parameter as "Lescale". */
    if (params_has(pl, "LeScale") && params_has(pl, "Lescale"))
        params_reject(pl, "LeScale", "give one of \"Lescale\" and \"LeScale\", not both");
    else if (!params_rename(pl, "LeScale", "Lescale"))
        return hz_fail(err, "out of memory");
    bool is_grid, uniform = false, cloud = false, rgbgrid = false;
    if (strcmp(type, "homogeneous") == 0)
        is_grid = false;
    else if (strcmp(type, "rgbgrid") == 0)
        is_grid = rgbgrid = true;
    else if (strcmp(type, "cloud") == 0)
        is_grid = cloud = true;
    else if (strcmp(type, "nanovdb") == 0)
        is_grid = true;
    else if (strcmp(type, "uniformgrid") == 0)
        is_grid = uniform = true;
    else
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": medium type \"%s\" is not supported "
                          "(supported: \"homogeneous\", \"nanovdb\", \"uniformgrid\", "
                          "\"cloud\", \"rgbgrid\")",
                          name, type);

    rgb sigma_a, sigma_s;
    if (params_has(pl, "preset"))
        read_preset(pl, is_grid, &sigma_a, &sigma_s);
    else {
        sigma_a = rgbgrid ? rgb_grey(0.0) : read_sigma(pl, "sigma_a");
        sigma_s = rgbgrid ? rgb_grey(1.0) : read_sigma(pl, "sigma_s");
    }
    double scale = params_float(pl, "scale", 1.0);
    if (!isfinite(scale) || scale < 0.0)
        params_reject(pl, "scale", "\"scale\" must be finite and non-negative, got %g", scale);
    double g = params_float(pl, "g", 0.0);
    if (!(fabs(g) < 1.0))
        params_reject(pl, "g", "\"g\" must lie in (-1, 1), got %g", g);
    /* Emission: pbrt-v4's "Le" (homogeneous media only) times "Lescale"; on
     * a nanovdb medium with a free emission grid, "Le" is its colour. */
    bool free_emission = strcmp(type, "nanovdb") == 0 && params_has(pl, "emissionname");
    rgb Le = free_emission                ? params_illuminant(pl, "Le", rgb_grey(1.0))
             : is_grid && !uniform ? rgb_grey(0.0)
                                   : params_illuminant(pl, "Le", rgb_grey(0.0));
    double Le_scale = uniform || cloud ? 1.0 : params_float(pl, "Lescale", 1.0);
    rgbgrid_params rg = {{{1, 1, 1}, {0, 0, 0}, {1, 1, 1}, NULL, NULL, NULL}, NULL, NULL, NULL};
    if (rgbgrid)
        rgbgrid_read(pl, &rg);
    if (!(isfinite(Le_scale) && Le_scale >= 0.0))
        params_reject(pl, "Lescale", "\"Lescale\" must be finite and non-negative, got %g",
                      Le_scale);
    else if (!(rgb_is_finite(rgb_scale(Le, Le_scale)) && Le.r >= 0.0 && Le.g >= 0.0 &&
               Le.b >= 0.0))
        params_reject(pl, "Le", "\"Le\" times \"Lescale\" must be finite and non-negative");

    const char *filename = NULL, *gridname = NULL;
    motion_params mp = {NULL, 1.0, time_start, time_start, time_end};
    temperature_params tp = {"temperature", false, 0.0, 1.0, 1.0};
    extra_params xp = {NULL, Le, Le_scale, NULL};
    uniformgrid_params ug = {{1, 1, 1}, {0, 0, 0}, {1, 1, 1}, NULL, NULL, NULL};
    cloud_params cp = {1.0f, 1.0f, 5.0f};
    vec3 cp0 = v3(0, 0, 0), cp1 = v3(1, 1, 1);
    if (cloud) {
        double v[3] = {params_float(pl, "density", 1.0), params_float(pl, "wispiness", 1.0),
                       params_float(pl, "frequency", 5.0)};
        const char *names[3] = {"density", "wispiness", "frequency"};
        for (int k = 0; k < 3; ++k)
            if (!(isfinite(v[k]) && v[k] >= 0.0 && v[k] < 1e30))
                params_reject(pl, names[k], "\"%s\" must be finite and >= 0", names[k]);
        cp = (cloud_params){(float)v[0], (float)v[1], (float)v[2]};
        cp0 = params_point3(pl, "p0", cp0);
        cp1 = params_point3(pl, "p1", cp1);
        if (!(cp0.x < cp1.x && cp0.y < cp1.y && cp0.z < cp1.z) || !v3_is_finite(cp0) ||
            !v3_is_finite(cp1))
            params_reject(pl, "p1", "the box \"p0\" .. \"p1\" must be finite and non-empty");
        if (memcmp(&e->world_from_medium.m, &e->world_from_medium_end.m,
                   sizeof e->world_from_medium.m) != 0)
            params_reject(pl, "density", "a moving \"cloud\" medium is not supported");
    } else if (rgbgrid) {
        /* read above, before Le (an rgb array here) */
    } else if (uniform) {
        uniformgrid_read(pl, &ug);
        read_temperature_params(pl, &tp);
        tp.Le_scale = 1.0;
        if (ug.temperature && params_has(pl, "Le"))
            params_reject(pl, "Le", "give \"Le\" or \"temperature\", not both (as pbrt-v4)");
    } else if (is_grid) {
        filename = params_string(pl, "filename", NULL);
        gridname = params_string(pl, "gridname", "density");
        mp.velocityname = params_string(pl, "velocityname", NULL);
        mp.scale = params_float(pl, "velocityscale", 1.0);
        mp.time = params_float(pl, "velocitytime", time_start);
        if (!mp.velocityname) {
            const char *p = params_has(pl, "velocityscale") ? "velocityscale" : "velocitytime";
            if (params_has(pl, p))
                params_reject(pl, p, "\"%s\" needs a velocity grid (\"string velocityname\")",
                              p);
        } else if (!mp.velocityname[0]) {
            params_reject(pl, "velocityname", "\"velocityname\" is empty");
        }
        if (!(isfinite(mp.scale) && mp.scale >= 0.0))
            params_reject(pl, "velocityscale",
                          "\"velocityscale\" must be finite and non-negative, got %g", mp.scale);
        if (!isfinite(mp.time))
            params_reject(pl, "velocitytime", "\"velocitytime\" must be finite, got %g", mp.time);
        /* Emission from a temperature grid of the file, as pbrt-v4. */
        tp.named = params_has(pl, "temperaturename");
        tp.name = params_string(pl, "temperaturename", "temperature");
        if (!tp.name[0])
            params_reject(pl, "temperaturename", "\"temperaturename\" is empty");
        read_temperature_params(pl, &tp);
        tp.Le_scale = Le_scale;
        /* haze's own: a free emission grid and a colour grid. */
        xp.emissionname = params_string(pl, "emissionname", NULL);
        xp.colorname = params_string(pl, "colorname", NULL);
        const char *names[2] = {"emissionname", "colorname"};
        const char *given[2] = {xp.emissionname, xp.colorname};
        for (int k = 0; k < 2; ++k)
            if (given[k] && !given[k][0])
                params_reject(pl, names[k], "\"%s\" is empty", names[k]);
        if (xp.emissionname && tp.named && params_has(pl, "Le"))
            params_reject(pl, "Le",
                          "give \"Le\" (one colour) or \"temperaturename\" (each voxel's "
                          "blackbody colour) to colour the emission grid, not both");
    }

    rgb sa = rgb_scale(sigma_a, scale), ss = rgb_scale(sigma_s, scale);
    if (!rgb_is_finite(sa) || !rgb_is_finite(ss))
        params_reject(pl, "scale", "\"scale\" times \"sigma_a\" or \"sigma_s\" overflows");

    char what[300];
    snprintf(what, sizeof what, "MakeNamedMedium \"%s\" (\"%s\")", name, type);
    if (params_finish(pl, what, err) != HZ_OK)
        return HZ_ERROR;

    out->kind = is_grid ? MEDIUM_GRID : MEDIUM_HOMOGENEOUS;
    out->name = e->name;
    out->sigma_a = sa;
    out->sigma_s = ss;
    out->g = g;
    if (!is_grid) {
        out->Le = rgb_scale(Le, Le_scale);
        out->emissive = !rgb_is_black(out->Le) && !rgb_is_black(sa);
        return HZ_OK;
    }

    if (rgbgrid) {
        if (build_rgbgrid(e, render_from_world, &rg, scale, Le_scale, times, out, err) != HZ_OK) {
            medium_free(out);
            memset(out, 0, sizeof *out);
            return HZ_ERROR;
        }
        return HZ_OK;
    }
    if (cloud) {
        out->kind = MEDIUM_CLOUD;
        out->cloud.params = cp;
        out->cloud.p0 = cp0;
        out->cloud.p1 = cp1;
        out->cloud.medium_from_render =
            transform_inverse(transform_compose(render_from_world, e->world_from_medium));
        if (!transform_is_finite(&out->cloud.medium_from_render)) {
            memset(out, 0, sizeof *out);
            return hz_fail_at(err, e->entity.loc,
                              "MakeNamedMedium \"%s\": the cloud's placement is singular or not "
                              "finite",
                              name);
        }
        return HZ_OK;
    }
    if (uniform) {
        if (build_uniformgrid(e, render_from_world, &ug, &tp, Le, times, out, err) != HZ_OK) {
            medium_free(out);
            memset(out, 0, sizeof *out);
            return HZ_ERROR;
        }
        return HZ_OK;
    }
    if (!filename || !filename[0]) {
        memset(out, 0, sizeof *out);
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": a \"nanovdb\" medium needs \"string filename\"",
                          name);
    }
    if (!gridname[0]) {
        memset(out, 0, sizeof *out);
        return hz_fail_at(err, params_loc(pl, "gridname"),
                          "MakeNamedMedium \"%s\": \"gridname\" is empty", name);
    }
    if (load_grid(e, render_from_world, filename, gridname, &mp, &tp, &xp, out, err) != HZ_OK ||
        build_majorants(out, times, err) != HZ_OK) {
        medium_free(out);
        memset(out, 0, sizeof *out);
        return HZ_ERROR;
    }
    return HZ_OK;
}

void medium_free(medium *m)
{
    if (!m)
        return;
    if (m->kind == MEDIUM_RGBGRID)
        for (int c = 0; c < 3; ++c) {
            grid_destroy(m->rgbg.sigma_a[c]);
            grid_destroy(m->rgbg.sigma_s[c]);
            grid_destroy(m->rgbg.Le[c]);
            m->rgbg.sigma_a[c] = m->rgbg.sigma_s[c] = m->rgbg.Le[c] = NULL;
        }
    if (m->kind == MEDIUM_GRID || m->kind == MEDIUM_RGBGRID) {
        grid_destroy(m->grid.grid);
        grid_destroy(m->grid.velocity);
        grid_destroy(m->grid.temperature);
        grid_destroy(m->grid.Le_scale_grid);
        grid_destroy(m->grid.emission);
        grid_destroy(m->grid.color);
        blackbody_table_free(&m->grid.blackbody);
        majorant_grid_free(&m->grid.majorant);
    }
    m->grid.grid = NULL;
    m->grid.velocity = NULL;
    m->grid.temperature = NULL;
    m->grid.Le_scale_grid = NULL;
    m->grid.emission = NULL;
    m->grid.color = NULL;
}

bool medium_grid_ray_make(const medium *m, vec3 o, vec3 d, double time, medium_grid_ray *out)
{
    if (m->grid.moving) {
        /* The placement at this time: one interpolation per ray segment. */
        transform render_from_medium = animated_transform_at(&m->grid.render_from_medium, time);
        transform index_from_render =
            transform_compose(m->grid.index_from_medium, transform_inverse(render_from_medium));
        out->o = transform_point(&index_from_render, o);
        out->d = transform_vector(&index_from_render, d);
    } else {
        out->o = transform_point(&m->grid.index_from_render, o);
        out->d = transform_vector(&m->grid.index_from_render, d);
    }
    out->lo = m->grid.support_lo;
    out->hi = m->grid.support_hi;
    out->shift = 0.0;
    if (m->grid.velocity) {
        out->shift = m->grid.velocity_scale * (time - m->grid.velocity_time);
        vec3 grow = v3_scale(m->grid.dilation, fabs(out->shift));
        out->lo = v3_sub(out->lo, grow);
        out->hi = v3_add(out->hi, grow);
        if (!isfinite(out->shift) || !v3_is_finite(grow))
            return false;
    }
    return v3_is_finite(out->o) && v3_is_finite(out->d);
}

bool medium_grid_ray_clip(const medium *m, const medium_grid_ray *r, double *t0, double *t1)
{
    if (!(*t0 <= *t1)) /* also NaN */
        return false;
    if (m->grid.background != 0.0)
        return true;
    /* The index-space ray against the support box; same t. The field is
     * zero on the support's boundary, so rounding at the ends loses
     * nothing. */
    return box_clip_ray(r->o, r->d, r->lo, r->hi, t0, t1);
}

bool media_clear_along(const medium *media, size_t n, vec3 o, vec3 d, double t0, double t1,
                       double time, uint64_t *cells)
{
    for (size_t i = 0; i < n; ++i) {
        const medium *m = &media[i];
        if (m->kind != MEDIUM_GRID || m->grid.background != 0.0)
            return false;
        medium_grid_ray r;
        if (!medium_grid_ray_make(m, o, d, time, &r))
            return false;
        double a = t0, b = t1;
        majorant_walk w;
        if (!medium_grid_ray_clip(m, &r, &a, &b) ||
            !majorant_walk_start(&w, &m->grid.majorant, r.o, r.d, a, b))
            continue; /* the ray misses where the density can be non-zero */
        majorant_segment seg;
        while (majorant_walk_next(&w, &seg)) {
            ++*cells;
            if (seg.max > 0.0)
                return false;
        }
    }
    return true;
}

bool medium_clip(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1)
{
    if (!(*t0 <= *t1)) /* also NaN */
        return false;
    if (m->kind == MEDIUM_HOMOGENEOUS || (m->kind == MEDIUM_GRID && m->grid.background != 0.0))
        return true;
    if (m->kind == MEDIUM_CLOUD)
        return medium_cloud_clip(m, o, d, t0, t1);
    medium_grid_ray r;
    return medium_grid_ray_make(m, o, d, time, &r) && medium_grid_ray_clip(m, &r, t0, t1);
}

void medium_accessor_init(const medium *m, medium_accessor *a)
{
    grid_accessor_init(m->grid.grid, &a->density);
    if (m->grid.velocity)
        grid_accessor_init(m->grid.velocity, &a->velocity);
    if (m->grid.temperature)
        grid_accessor_init(m->grid.temperature, &a->temperature);
    if (m->grid.Le_scale_grid)
        grid_accessor_init(m->grid.Le_scale_grid, &a->Le_scale);
    if (m->grid.emission)
        grid_accessor_init(m->grid.emission, &a->emission);
    if (m->grid.color)
        grid_accessor_init(m->grid.color, &a->color);
    if (m->kind == MEDIUM_RGBGRID) {
        grid *const *g[3] = {m->rgbg.sigma_a, m->rgbg.sigma_s, m->rgbg.Le};
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c)
                if (g[k][c])
                    grid_accessor_init(g[k][c], &a->rgb[3 * k + c]);
    }
}

bool medium_cloud_clip(const medium *m, vec3 o, vec3 d, double *t0, double *t1)
{
    vec3 om = transform_point(&m->cloud.medium_from_render, o);
    vec3 dm = transform_vector(&m->cloud.medium_from_render, d);
    return box_clip_ray(om, dm, m->cloud.p0, m->cloud.p1, t0, t1);
}
