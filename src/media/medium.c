#include "media/medium.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

static bool transform_is_finite(const transform *t)
{
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (!isfinite(t->m.m[r][c]) || !isfinite(t->m_inv.m[r][c]))
                return false;
    return true;
}

/* `name` relative to the directory of the scene file `base` (absolute names, and
 * names from scenes without a directory, e.g. parsed from a string, as they are). */
static char *resolve_path(const char *base, const char *name)
{
    const char *slash = base ? strrchr(base, '/') : NULL;
    size_t dir = (name[0] != '/' && slash) ? (size_t)(slash - base) + 1 : 0;
    size_t n = strlen(name);
    char *path = malloc(dir + n + 1);
    if (!path)
        return NULL;
    memcpy(path, base, dir);
    memcpy(path + dir, name, n + 1);
    return path;
}

/* Loads the grid and places it. Densities must be >= 0: the majorant-based
 * trackers treat sigma_t(p) / sigma_t_max as a probability, which a negative
 * density breaks (and pbrt-v4 has no meaning for it either), so grids with a
 * negative active value or background are refused rather than clamped. */
static hz_status load_grid(medium_entity *e, transform render_from_world, const char *filename,
                           const char *gridname, medium *out, hz_error *err)
{
    file_loc loc = e->entity.loc;
    const char *name = e->name ? e->name : "";
    char *path = resolve_path(loc.file, filename);
    if (!path)
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": out of memory", name);
    hz_error inner;
    grid *g = NULL;
    hz_status st = grid_load(path, gridname, &g, &inner);
    if (st != HZ_OK) {
        free(path);
        return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
    }

    vec3 lo, hi;
    bool nonempty = grid_support_bounds(g, &lo, &hi);
    double background = grid_background(g);
    double vmin = grid_min_value(g), vmax = grid_max_value(g);
    if (!isfinite(background) || (nonempty && (!isfinite(vmin) || !isfinite(vmax))))
        st = hz_fail_at(err, loc, "MakeNamedMedium \"%s\": grid \"%s\" in %s has non-finite values",
                        name, gridname, path);
    else if (background != 0.0)
        st = hz_fail_at(err, loc,
                        "MakeNamedMedium \"%s\": grid \"%s\" in %s has background %g; haze "
                        "needs a fog volume with background 0 (the medium would otherwise fill "
                        "all space)",
                        name, gridname, path, background);
    else if (background < 0.0 || (nonempty && vmin < 0.0))
        st = hz_fail_at(err, loc,
                        "MakeNamedMedium \"%s\": grid \"%s\" in %s has negative densities "
                        "(min %g, background %g); densities must be >= 0",
                        name, gridname, path, nonempty ? vmin : background, background);
    if (st == HZ_OK) {
        transform world_from_index = grid_world_from_index_transform(g);
        transform render_from_index = transform_compose(
            render_from_world, transform_compose(e->world_from_medium, world_from_index));
        out->grid.index_from_render = transform_inverse(render_from_index);
        if (!transform_is_finite(&out->grid.index_from_render))
            st = hz_fail_at(err, loc,
                            "MakeNamedMedium \"%s\": the grid's placement (its transform times "
                            "the current transform) is singular or not finite",
                            name);
    }
    free(path);
    if (st != HZ_OK) {
        grid_destroy(g);
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
    out->grid.density_max = fmax(nonempty ? fmax(vmax, background) : background, 0.0);
    return HZ_OK;
}

hz_status medium_from_entity(medium_entity *e, transform render_from_world, double time_start,
                             double time_end, medium *out, hz_error *err)
{
    (void)time_start; /* media are static for now */
    (void)time_end;
    memset(out, 0, sizeof *out);
    param_list *pl = &e->entity.params;
    const char *type = e->entity.type ? e->entity.type : "";
    const char *name = e->name ? e->name : "";
    bool is_grid;
    if (strcmp(type, "homogeneous") == 0)
        is_grid = false;
    else if (strcmp(type, "nanovdb") == 0)
        is_grid = true;
    else
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": medium type \"%s\" is not supported "
                          "(supported: \"homogeneous\", \"nanovdb\")",
                          name, type);

    if (params_has(pl, "preset"))
        params_reject(pl, "preset",
                      "named scattering properties (\"preset\") are not supported; give "
                      "\"sigma_a\" and \"sigma_s\"");
    rgb sigma_a = read_sigma(pl, "sigma_a");
    rgb sigma_s = read_sigma(pl, "sigma_s");
    double scale = params_float(pl, "scale", 1.0);
    if (!isfinite(scale) || scale < 0.0)
        params_reject(pl, "scale", "\"scale\" must be finite and non-negative, got %g", scale);
    double g = params_float(pl, "g", 0.0);
    if (!(fabs(g) < 1.0))
        params_reject(pl, "g", "\"g\" must lie in (-1, 1), got %g", g);
    /* Emission: pbrt-v4's "Le" times "Lescale". Only zero emission is accepted. */
    rgb Le = params_rgb(pl, "Le", rgb_grey(0.0));
    double Le_scale = params_float(pl, "Lescale", 1.0);
    if (!isfinite(Le_scale))
        params_reject(pl, "Lescale", "\"Lescale\" must be finite, got %g", Le_scale);
    else if (!rgb_is_black(Le) && Le_scale != 0.0)
        params_reject(pl, "Le", "emission (\"Le\") is not supported");

    const char *filename = NULL, *gridname = NULL;
    if (is_grid) {
        filename = params_string(pl, "filename", NULL);
        gridname = params_string(pl, "gridname", "density");
        /* pbrt-v4 turns a "temperature" grid into emission with these; emission is
         * not supported, so they are read (to be accepted) and ignored. */
        (void)params_float(pl, "temperaturecutoff", 0.0);
        (void)params_float(pl, "temperatureoffset", 0.0);
        (void)params_float(pl, "temperaturescale", 1.0);
        (void)params_string(pl, "temperaturename", "temperature");
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
    if (!is_grid)
        return HZ_OK;

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
    if (load_grid(e, render_from_world, filename, gridname, out, err) != HZ_OK) {
        memset(out, 0, sizeof *out);
        return HZ_ERROR;
    }
    return HZ_OK;
}

void medium_free(medium *m)
{
    if (!m)
        return;
    if (m->kind == MEDIUM_GRID)
        grid_destroy(m->grid.grid);
    m->grid.grid = NULL;
}

bool medium_clip(const medium *m, vec3 o, vec3 d, double *t0, double *t1)
{
    double lo = *t0, hi = *t1;
    if (!(lo <= hi)) /* also NaN */
        return false;
    if (m->kind == MEDIUM_HOMOGENEOUS || m->grid.background != 0.0)
        return true;

    /* Slab test of the index-space ray against the support box; same t. */
    vec3 oi = transform_point(&m->grid.index_from_render, o);
    vec3 di = transform_vector(&m->grid.index_from_render, d);
    if (!v3_is_finite(oi) || !v3_is_finite(di))
        return false; /* a degenerate ray: it cannot sample the field meaningfully */
    const double o3[3] = {oi.x, oi.y, oi.z}, d3[3] = {di.x, di.y, di.z};
    const double lo3[3] = {m->grid.support_lo.x, m->grid.support_lo.y, m->grid.support_lo.z};
    const double hi3[3] = {m->grid.support_hi.x, m->grid.support_hi.y, m->grid.support_hi.z};
    for (int a = 0; a < 3; ++a) {
        if (!(lo3[a] <= hi3[a]))
            return false; /* empty grid */
        if (d3[a] == 0.0) {
            /* Parallel to the slab: all inside or all outside. */
            if (!(o3[a] >= lo3[a] && o3[a] <= hi3[a]))
                return false;
            continue;
        }
        /* Divisions (not a reciprocal times a difference): with a finite non-zero
         * d, (bound - o) / d is never NaN; a tiny d gives ±inf, which is right.
         * The field is zero on the support's boundary, so rounding at the ends
         * loses nothing. */
        double tn = (lo3[a] - o3[a]) / d3[a];
        double tf = (hi3[a] - o3[a]) / d3[a];
        if (tn > tf) {
            double t = tn;
            tn = tf;
            tf = t;
        }
        if (tn > lo)
            lo = tn;
        if (tf < hi)
            hi = tf;
        if (!(lo <= hi))
            return false;
    }
    *t0 = lo;
    *t1 = hi;
    return true;
}
