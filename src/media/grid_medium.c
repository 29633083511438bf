/* The grid kinds' shared machinery (media/grid_medium.h): placement, the
 * majorant grid, rays and the density kinds' lookups. */
#include "media/grid_medium.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/box.h"
#include "media/medium_params.h"
#include "media/uniformgrid.h"

bool grid_medium_alloc(medium *out)
{
    out->state = calloc(1, sizeof(grid_medium));
    return out->state != NULL;
}

void grid_medium_destroy(medium *m)
{
    grid_medium *gm = grid_medium_of(m);
    if (!gm)
        return;
    for (int c = 0; c < 3; ++c) {
        grid_destroy(gm->rgb_sigma_a[c]);
        grid_destroy(gm->rgb_sigma_s[c]);
        grid_destroy(gm->rgb_Le[c]);
    }
    grid_destroy(gm->grid);
    grid_destroy(gm->velocity);
    grid_destroy(gm->temperature);
    grid_destroy(gm->Le_scale_grid);
    grid_destroy(gm->emission);
    grid_destroy(gm->color);
    blackbody_table_free(&gm->blackbody);
    majorant_grid_free(&gm->majorant);
    free(gm);
}

hz_status grid_medium_place(medium_entity *e, transform render_from_world, const grid *g,
                            const grid_motion_params *mp, grid_medium *gm, hz_error *err)
{
    transform world_from_index = grid_world_from_index_transform(g);
    gm->index_from_medium = transform_inverse(world_from_index);
    transform render_from_index = transform_compose(
        render_from_world, transform_compose(e->world_from_medium, world_from_index));
    gm->index_from_render = transform_inverse(render_from_index);
    bool finite = medium_transform_is_finite(&gm->index_from_render);
    animated_transform a = animated_transform_make(
        transform_compose(render_from_world, e->world_from_medium), mp->time_start,
        transform_compose(render_from_world, e->world_from_medium_end), mp->time_end);
    if (finite && a.animated) {
        gm->moving = true;
        gm->render_from_medium = a;
        transform end = transform_inverse(transform_compose(a.end, world_from_index));
        finite = medium_transform_is_finite(&end);
    }
    if (!finite)
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": the grid's placement (its transform times "
                          "the current transform) is singular or not finite",
                          medium_entity_name(e));
    return HZ_OK;
}

/* With a velocity grid the support grows by the largest displacement at any
 * ray time, and every cell's box of voxels read by as much, so one grid
 * bounds the density wherever it is carried, at every time. */
hz_status grid_medium_build_majorants(const medium *m, const medium_times *times, hz_error *err)
{
    grid_medium *gm = grid_medium_of(m);
    int32_t pad[3] = {0, 0, 0};
    vec3 lo = gm->support_lo, hi = gm->support_hi;
    if (gm->velocity && lo.x <= hi.x) {
        double t0 = fmin(times->ray_min, times->transform_start);
        double t1 = fmax(times->ray_max, times->transform_end);
        double shift = gm->velocity_scale *
                       fmax(fabs(t0 - gm->velocity_time), fabs(t1 - gm->velocity_time));
        const double d3[3] = {gm->dilation.x, gm->dilation.y, gm->dilation.z};
        for (int a = 0; a < 3; ++a) {
            double p = ceil(d3[a] * shift);
            pad[a] = p < (double)(1 << 28) ? (int32_t)p : (1 << 28);
        }
        lo = v3_sub(lo, v3(pad[0], pad[1], pad[2]));
        hi = v3_add(hi, v3(pad[0], pad[1], pad[2]));
    }
    majorant_emission em = {gm->emission, gm->emission_aligned, gm->eindex_from_index};
    return majorant_grid_build(gm->grid, m->free_emission ? &em : NULL, lo, hi, pad,
                               &gm->majorant, err);
}

transform grid_medium_index_from_density_index(const grid *density, const grid *g, bool *aligned)
{
    transform d_world_from_index = grid_world_from_index_transform(density);
    transform g_world_from_index = grid_world_from_index_transform(g);
    *aligned = memcmp(&d_world_from_index.m, &g_world_from_index.m,
                      sizeof d_world_from_index.m) == 0;
    return transform_compose(transform_inverse(g_world_from_index), d_world_from_index);
}

bool grid_medium_ray_make(const medium *m, vec3 o, vec3 d, double time, medium_ray *r)
{
    const grid_medium *gm = grid_medium_of(m);
    if (gm->moving) {
        /* The placement at this time: one interpolation per ray segment. */
        transform render_from_medium = animated_transform_at(&gm->render_from_medium, time);
        transform index_from_render =
            transform_compose(gm->index_from_medium, transform_inverse(render_from_medium));
        r->at.grid.o = transform_point(&index_from_render, o);
        r->at.grid.d = transform_vector(&index_from_render, d);
    } else {
        r->at.grid.o = transform_point(&gm->index_from_render, o);
        r->at.grid.d = transform_vector(&gm->index_from_render, d);
    }
    r->at.grid.lo = gm->support_lo;
    r->at.grid.hi = gm->support_hi;
    r->at.grid.shift = 0.0;
    if (gm->velocity) {
        r->at.grid.shift = gm->velocity_scale * (time - gm->velocity_time);
        vec3 grow = v3_scale(gm->dilation, fabs(r->at.grid.shift));
        r->at.grid.lo = v3_sub(r->at.grid.lo, grow);
        r->at.grid.hi = v3_add(r->at.grid.hi, grow);
        if (!isfinite(r->at.grid.shift) || !v3_is_finite(grow))
            return false;
    }
    return v3_is_finite(r->at.grid.o) && v3_is_finite(r->at.grid.d);
}

bool grid_medium_ray_clip(const medium *m, const medium_ray *r, double *t0, double *t1)
{
    if (!(*t0 <= *t1)) /* also NaN */
        return false;
    if (grid_medium_of(m)->background != 0.0)
        return true;
    /* The index-space ray against the support box; same t. The field is
     * zero on the support's boundary, so rounding at the ends loses
     * nothing. */
    return box_clip_ray(r->at.grid.o, r->at.grid.d, r->at.grid.lo, r->at.grid.hi, t0, t1);
}

void grid_medium_accessors_init(const medium *m, medium_ray *r)
{
    const grid_medium *gm = grid_medium_of(m);
    grid_accessor_init(gm->grid, &r->acc.density);
    if (gm->velocity)
        grid_accessor_init(gm->velocity, &r->acc.velocity);
    if (gm->temperature)
        grid_accessor_init(gm->temperature, &r->acc.temperature);
    if (gm->Le_scale_grid)
        grid_accessor_init(gm->Le_scale_grid, &r->acc.Le_scale);
    if (gm->emission)
        grid_accessor_init(gm->emission, &r->acc.emission);
    if (gm->color)
        grid_accessor_init(gm->color, &r->acc.color);
    if (!gm->rgb_channels)
        return;
    grid *const *g[3] = {gm->rgb_sigma_a, gm->rgb_sigma_s, gm->rgb_Le};
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c)
            if (g[k][c])
                grid_accessor_init(g[k][c], &r->acc.rgb[3 * k + c]);
}

bool grid_medium_clip(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1)
{
    medium_ray r;
    return grid_medium_ray_make(m, o, d, time, &r) && grid_medium_ray_clip(m, &r, t0, t1);
}

bool grid_medium_ray_start(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1,
                           medium_ray *r)
{
    if (!grid_medium_ray_make(m, o, d, time, r) || !grid_medium_ray_clip(m, r, t0, t1) ||
        !majorant_walk_start(&r->mw, &grid_medium_of(m)->majorant, r->at.grid.o, r->at.grid.d,
                             *t0, *t1))
        return false;
    r->m = m;
    r->dda = true;
    grid_medium_accessors_init(m, r);
    r->voxels_per_t = v3_length(r->at.grid.d);
    r->lookup = m->ops->density && r->at.grid.shift == 0.0 ? grid_medium_of(m)->grid : NULL;
    r->plain = r->lookup && !m->coloured && !m->emissive && !m->free_emission;
    return true;
}

bool grid_medium_clear_along(const medium *m, vec3 o, vec3 d, double t0, double t1, double time,
                             uint64_t *cells)
{
    if (grid_medium_of(m)->background != 0.0)
        return false;
    medium_ray r;
    if (!grid_medium_ray_make(m, o, d, time, &r))
        return false;
    double a = t0, b = t1;
    if (!grid_medium_ray_clip(m, &r, &a, &b) ||
        !majorant_walk_start(&r.mw, &grid_medium_of(m)->majorant, r.at.grid.o, r.at.grid.d, a,
                             b))
        return true; /* the ray misses where the density can be non-zero */
    majorant_segment seg;
    while (majorant_walk_next(&r.mw, &seg)) {
        ++*cells;
        if (seg.max > 0.0)
            return false;
    }
    return true;
}

double grid_medium_density_max(const medium *m) { return grid_medium_of(m)->density_max; }

bool grid_medium_support(const medium *m, vec3 corners[8], double *voxel)
{
    const grid_medium *gm = grid_medium_of(m);
    vec3 lo = gm->support_lo, hi = gm->support_hi;
    if (gm->background != 0.0 || !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
        return false;
    transform render_from_index = transform_inverse(gm->index_from_render);
    for (int k = 0; k < 8; ++k)
        corners[k] = transform_point(&render_from_index, v3(k & 1 ? hi.x : lo.x,
                                                            k & 2 ? hi.y : lo.y,
                                                            k & 4 ? hi.z : lo.z));
    /* The geometric mean of the render-space lengths of a voxel's edges. */
    *voxel = cbrt(fabs(transform_det3(&render_from_index)));
    return true;
}

medium_memory grid_medium_memory(const medium *m)
{
    const grid_medium *gm = grid_medium_of(m);
    medium_memory mem = {0.0, 0.0};
    for (int c = 0; c < 3; ++c) {
        const grid *g[3] = {gm->rgb_sigma_a[c], gm->rgb_sigma_s[c], gm->rgb_Le[c]};
        for (int k = 0; k < 3; ++k)
            mem.grids += g[k] ? (double)grid_buffer_bytes(g[k]) : 0.0;
    }
    mem.grids += (double)grid_buffer_bytes(gm->grid);
    if (gm->velocity)
        mem.grids += (double)grid_buffer_bytes(gm->velocity);
    mem.majorants += (double)majorant_grid_bytes(&gm->majorant);
    return mem;
}

medium_work grid_medium_work(const medium *m)
{
    majorant_work w = majorant_grid_work(&grid_medium_of(m)->majorant);
    return (medium_work){w.bricks, w.seconds};
}

bool grid_medium_moves(const medium *m)
{
    const grid_medium *gm = grid_medium_of(m);
    return gm->moving || gm->velocity != NULL;
}

hz_status grid_medium_adopt_temperature(grid *t, const temperature_params *tp, grid_medium *gm,
                                        bool *emits, hz_error *err)
{
    gm->temperature = t;
    gm->temperature_offset = tp->offset;
    gm->temperature_scale = tp->scale;
    double bg = grid_background(t);
    double v0 = fmin(grid_min_value(t), bg), v1 = fmax(grid_max_value(t), bg);
    double a = (v0 - tp->offset) * tp->scale, b = (v1 - tp->offset) * tp->scale;
    return blackbody_table_build(&gm->blackbody, fmin(a, b), fmax(a, b), emits, err);
}


/* The dense samples `values` (uniformgrid_params' counts) as the medium's
 * density grid: placed by the CTM, the support clipped to the box p0..p1, as
 * pbrt-v4's SampledGrid clips. */
hz_status grid_medium_adopt_dense(medium_entity *e, transform render_from_world,
                                 const uniformgrid_params *u, const double *values,
                                 const char *what, const medium_times *times, grid_medium *gm,
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
    grid_motion_params mp = {NULL, 1.0, times->transform_start, times->transform_start,
                        times->transform_end};
    if (grid_medium_place(e, render_from_world, g, &mp, gm, err) != HZ_OK) {
        grid_destroy(g);
        return HZ_ERROR;
    }
    gm->grid = g;
    vec3 lo, hi, blo, bhi;
    uniformgrid_support(u, &blo, &bhi);
    bool nonempty = grid_support_bounds(g, &lo, &hi);
    gm->support_lo = nonempty ? v3(fmax(lo.x, blo.x), fmax(lo.y, blo.y), fmax(lo.z, blo.z))
                                    : v3(1, 1, 1);
    gm->support_hi = nonempty ? v3(fmin(hi.x, bhi.x), fmin(hi.y, bhi.y), fmin(hi.z, bhi.z))
                                    : v3(-1, -1, -1);
    gm->background = 0.0;
    gm->density_max = nonempty ? grid_max_value(g) : 0.0;
    return HZ_OK;
}

/* ---- the density kinds' lookups ---- */

double grid_medium_density(medium_ray *r, double t, uint64_t *lookups)
{
    const grid_medium *gm = grid_medium_of(r->m);
    vec3 p = grid_medium_point_at(gm, r, t, lookups);
    ++*lookups;
    return grid_density_index(gm->grid, &r->acc.density, p);
}

void grid_medium_density_point(medium_ray *r, double t, medium_density_point *g,
                               uint64_t *lookups)
{
    const medium *m = r->m;
    const grid_medium *gm = grid_medium_of(m);
    g->Le = rgb_grey(0.0);
    g->eps = rgb_grey(0.0);
    g->C = rgb_grey(1.0);
    vec3 p = grid_medium_point_at(gm, r, t, lookups);
    ++*lookups;
    g->density = grid_density_index(gm->grid, &r->acc.density, p);
    if (m->free_emission)
        g->eps = grid_medium_emission(gm, r, p, lookups);
    if (g->density > 0.0 && m->emissive)
        g->Le = grid_medium_Le(m, gm, r, p, lookups);
    if (g->density > 0.0 && m->coloured)
        g->C = grid_medium_color(gm, r, p, lookups);
}

void grid_medium_sample(medium_ray *r, double t, bool emission, medium_props *ev,
                        uint64_t *lookups)
{
    const medium *m = r->m;
    const grid_medium *gm = grid_medium_of(m);
    vec3 p = grid_medium_point_at(gm, r, t, lookups);
    ++*lookups;
    double d = grid_density_index(gm->grid, &r->acc.density, p);
    ev->sigma_a = rgb_scale(m->sigma_a, d);
    ev->sigma_s = rgb_scale(m->sigma_s, d);
    ev->emission = rgb_grey(0.0);
    if (m->coloured && d > 0.0) {
        /* The albedo scaled per channel; what is not scattered is absorbed. */
        rgb C = grid_medium_color(gm, r, p, lookups);
        rgb ss = rgb_mul(m->sigma_s, C);
        ev->sigma_a = rgb_scale(rgb_add(m->sigma_a, rgb_sub(m->sigma_s, ss)), d);
        ev->sigma_s = rgb_scale(ss, d);
    }
    /* Absorbing emission keeps the medium's own sigma_a: the colour tints
     * the scattering, not the fire. */
    if (emission && m->emissive && d > 0.0)
        ev->emission = rgb_mul(rgb_scale(m->sigma_a, d), grid_medium_Le(m, gm, r, p, lookups));
    if (emission && m->free_emission)
        ev->emission = rgb_add(ev->emission, grid_medium_emission(gm, r, p, lookups));
}
