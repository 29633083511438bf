/* "rgbgrid": pbrt-v4's grid of rgb sigma_a, sigma_s, Le samples (nx ny nz,
 * p0, p1, scale, Lescale, g), as uniformgrid places them. The medium's
 * density grid holds, per sample, the largest channel of sigma_a + sigma_s
 * (scale applied): the placement, support and majorant of grid media; the
 * channels are grids of their own in the same index space. Rendered by
 * volpath only. */
#include <math.h>
#include <stdlib.h>

#include "media/grid_medium.h"
#include "media/medium.h"
#include "media/medium_params.h"
#include "media/uniformgrid.h"
#include "scene/spectrum.h"

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
    grid_medium *gm = grid_medium_of(out);
    gm->rgb_channels = true;
    /* sigma_t = 1 per unit of grid.grid: the majorant is the grid's bound. */
    out->sigma_a = rgb_grey(0.0);
    out->sigma_s = rgb_grey(1.0);
    gm->rgb_scale = scale;
    /* pbrt-v4 takes each sample's Le as an RGB illuminant spectrum without
     * dividing it by its luminance (unlike a light's or a homogeneous
     * medium's Le): its film sees rgb (1, 1, 1) as luminance 106.86. */
    gm->rgb_Le_scale = Le_scale * SPECTRUM_CIE_Y_INTEGRAL;
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
        grid_medium_adopt_dense(e, render_from_world, u, mx, "sigma_a + sigma_s", times, gm, err);
    free(mx);
    if (st != HZ_OK)
        return HZ_ERROR;
    const double *arrays[3] = {r->sigma_a, r->sigma_s, r->Le};
    const char *names[3] = {"sigma_a", "sigma_s", "Le"};
    grid **slots[3] = {gm->rgb_sigma_a, gm->rgb_sigma_s, gm->rgb_Le};
    for (int k = 0; k < 3; ++k)
        for (int c = 0; arrays[k] && c < 3; ++c)
            if (uniformgrid_make_channel(u, arrays[k], c, names[k], &slots[k][c], &inner) !=
                HZ_OK)
                return hz_fail_at(err, loc, "MakeNamedMedium \"%s\": %s", name, inner.message);
    out->emissive = r->Le && Le_scale > 0.0;
    return grid_medium_build_majorants(out, times, err);
}

static hz_status create(medium_entity *e, const medium_build *b, medium *out, hz_error *err)
{
    param_list *pl = &e->entity.params;
    medium_param_rules rules = {true, false, MEDIUM_LE_NONE, true};
    medium_common_params c;
    medium_params_read(pl, &rules, &c);
    rgbgrid_params rg;
    rgbgrid_read(pl, &rg);
    medium_params_check_emission(pl, &c);
    if (medium_params_finish(e, &c, out, err) != HZ_OK)
        return HZ_ERROR;
    if (!grid_medium_alloc(out))
        return hz_fail(err, "out of memory");
    return build_rgbgrid(e, b->render_from_world, &rg, c.scale, c.Le_scale, b->times, out, err);
}

/* The coefficients and emission at o + t d: each channel's grid. */
static void sample(medium_ray *r, double t, bool emission, medium_props *p, uint64_t *lookups)
{
    const grid_medium *gm = grid_medium_of(r->m);
    vec3 q = grid_medium_point_at(gm, r, t, lookups);
    double v[3][3];
    grid *const *g[3] = {gm->rgb_sigma_a, gm->rgb_sigma_s, gm->rgb_Le};
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) {
            if (g[k][c]) {
                ++*lookups;
                v[k][c] = grid_density_index(g[k][c], &r->acc.rgb[3 * k + c], q);
            } else {
                v[k][c] = k < 2 ? 1.0 : 0.0;
            }
        }
    double s = gm->rgb_scale, e = gm->rgb_Le_scale;
    p->sigma_a = rgb_make(s * v[0][0], s * v[0][1], s * v[0][2]);
    p->sigma_s = rgb_make(s * v[1][0], s * v[1][1], s * v[1][2]);
    rgb Le = rgb_make(e * v[2][0], e * v[2][1], e * v[2][2]);
    const spectral_ctx *sp = r->m->spectral;
    if (sp) {
        p->sigma_a = spectral_from_rgb(sp, p->sigma_a, SPECTRAL_UNBOUNDED);
        p->sigma_s = spectral_from_rgb(sp, p->sigma_s, SPECTRAL_UNBOUNDED);
        if (emission)
            Le = spectral_from_rgb(sp, Le, SPECTRAL_ILLUMINANT);
    }
    p->emission = emission ? rgb_mul(p->sigma_a, Le) : rgb_grey(0.0);
}

const medium_ops medium_rgbgrid_ops = {
    .rgb_coefficients = true,
    .name = "rgbgrid",
    .create = create,
    .destroy = grid_medium_destroy,
    .clip = grid_medium_clip,
    .ray_start = grid_medium_ray_start,
    .sample = sample,
    .memory = grid_medium_memory,
    .work = grid_medium_work,
    .moves = grid_medium_moves,
};
