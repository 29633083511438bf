/* What the grid kinds (nanovdb, uniformgrid, rgbgrid) share: a density grid
 * placed in render space (animated or not), where its density can be
 * non-zero, its majorant grid, the optional grids that ride on it
 * (velocity, temperature, Lescale, emission, colour, rgbgrid's channels),
 * and the lookups along a ray. Private to src/media (and its unit tests):
 * the rest of haze sees media through media/medium.h only.
 *
 * A grid's density is the trilinear field of its voxel values (values at
 * integer index points, background elsewhere); it is not clipped at the
 * grid's bounding box, so it reaches one voxel beyond the active voxels
 * (pbrt-v4 clips at index [min, max + 1]).
 *
 * Moving grids. A grid medium declared under an animated transform (start and
 * end CTMs differ) moves with it: a ray at scene time t sees the grid placed by
 * pbrt-v4's AnimatedTransform interpolation at t. With a velocity grid v, the
 * density at a point x (in the grid's world space, i.e. medium space) and time
 * t is density(x - v(x) * velocityscale * (t - velocitytime)): first-order
 * Eulerian motion blur. Both combine (the velocity is relative to the moving
 * frame). Static grids (equal keyframes, no velocity grid) run the same code
 * as before motion existed. */
#ifndef HAZE_MEDIA_GRID_MEDIUM_H
#define HAZE_MEDIA_GRID_MEDIUM_H

#include <math.h>
#include <stdbool.h>

#include "core/animated_transform.h"
#include "media/blackbody.h"
#include "media/medium.h"
#include "media/medium_params.h"
#include "media/uniformgrid.h"
#include "scene/params.h"

typedef struct {
    grid *grid; /* the density (rgbgrid: the largest channel of sigma_t); owned */
    /* Grid index space from render space: affine, so a ray o + t d in render
     * space is (A o + b) + t (A d) in index space with the same t. */
    transform index_from_render;
    /* Where the density can differ from the background: the index-space
     * box [min - 1, max + 1] of the active voxels. With a zero background
     * the density is 0 outside it; lo > hi for an empty grid. */
    vec3 support_lo, support_hi;
    double background;  /* density outside the support */
    double density_max; /* >= every density value of the field, >= 0 */
    /* Per-cell density bounds over the support, at every time of the
     * shutter (velocity displacement included). */
    majorant_grid majorant;

    /* An animated placement: index_from_render above is the start's, and a
     * ray at time t uses index_from_medium ∘ inverse(render_from_medium(t)). */
    bool moving;
    animated_transform render_from_medium; /* moving only */
    /* The grid's own map (index from its world space, i.e. medium space). */
    transform index_from_medium;

    /* Temperature (emission); NULL: none. */
    grid *temperature;           /* owned; a float grid */
    bool temperature_aligned;    /* same index space as the density grid */
    transform tindex_from_index; /* temperature index from density index */
    double temperature_offset, temperature_scale, Le_scale;
    blackbody_table blackbody; /* over the grid's temperature range */
    /* uniformgrid: pbrt-v4's Lescale grid (NULL otherwise), the same index
     * space as the density or one sample spanning the box; emission is
     * Le_scale_grid(p) times the temperature's blackbody, or times Le. */
    grid *Le_scale_grid;          /* owned */
    transform lsindex_from_index; /* its index from the density's index */

    /* Free emission ("emissionname"; NULL: none): radiance emitted per
     * unit length, emission_scale E(p) times a colour, whatever the
     * density: emission_tint, or (emission_by_temperature) the blackbody
     * colour, of luminance 1, of the temperature grid's kelvins. */
    grid *emission;              /* owned; a float grid */
    bool emission_aligned;       /* same index space as the density grid */
    transform eindex_from_index; /* its index from the density's index */
    rgb emission_tint;           /* luminance-normalised Le */
    double emission_scale;       /* Lescale */
    bool emission_by_temperature;
    /* A colour grid ("colorname"; NULL: none): per channel, the
     * scattering albedo times its value clamped to [0, 1]; sigma_t is
     * unchanged (what is not scattered is absorbed); absorbing emission
     * keeps the uncoloured sigma_a. */
    grid *color; /* owned; a vec3 grid */
    bool color_aligned;
    transform cindex_from_index;

    /* Velocity (Eulerian motion blur); NULL: none. */
    grid *velocity;              /* owned; a vec3 grid, medium units per time */
    bool velocity_aligned;       /* same index space as the density grid */
    transform vindex_from_index; /* velocity index from density index */
    double velocity_scale, velocity_time;
    /* Growth of the support box, in index units per unit of
     * |velocity_scale (t - velocity_time)|: the longest velocity times the
     * length of each row of index_from_medium's linear part. */
    vec3 dilation;

    /* rgbgrid: the channels (same index space; NULL: 1 everywhere in the box
     * for sigma_a/sigma_s, no emission for Le). */
    bool rgb_channels; /* an rgbgrid: the channels below are its coefficients */
    grid *rgb_sigma_a[3], *rgb_sigma_s[3], *rgb_Le[3];
    double rgb_scale, rgb_Le_scale;
} grid_medium;

static inline grid_medium *grid_medium_of(const medium *m) { return (grid_medium *)m->state; }

/* What MakeNamedMedium says about a grid's motion. */
typedef struct {
    const char *velocityname;    /* NULL: no velocity grid */
    double scale, time;          /* velocityscale, velocitytime */
    double time_start, time_end; /* TransformTimes */
} grid_motion_params;

/* Allocates the kind's state of out (zeroed); false when out of memory. */
bool grid_medium_alloc(medium *out);
/* The ops every grid kind shares. */
void grid_medium_destroy(medium *m);
bool grid_medium_clip(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1);
bool grid_medium_ray_start(const medium *m, vec3 o, vec3 d, double time, double *t0,
                           double *t1, medium_ray *r);
bool grid_medium_support(const medium *m, vec3 corners[8], double *voxel);
double grid_medium_density_max(const medium *m);
bool grid_medium_clear_along(const medium *m, vec3 o, vec3 d, double t0, double t1,
                             double time, uint64_t *cells);
medium_memory grid_medium_memory(const medium *m);
medium_work grid_medium_work(const medium *m);
bool grid_medium_moves(const medium *m);

/* The placement of grid g at both keyframes: animated when they differ. */
hz_status grid_medium_place(medium_entity *e, transform render_from_world, const grid *g,
                            const grid_motion_params *mp, grid_medium *gm, hz_error *err);
/* The majorant grid over the support (grown by a velocity field's reach at
 * every ray time). */
hz_status grid_medium_build_majorants(const medium *m, const medium_times *times,
                                      hz_error *err);
/* The transform from the density grid's index space to g's, and whether
 * they are the same. */
transform grid_medium_index_from_density_index(const grid *density, const grid *g,
                                               bool *aligned);

/* The temperature grid t (its values lie within the active values and the
 * background, trilinear values too) adopted by gm: the offset and scale,
 * and the blackbody tabulated over the kelvins they map to. *emits: some of
 * them are above 100 K. */
hz_status grid_medium_adopt_temperature(grid *t, const temperature_params *tp, grid_medium *gm,
                                        bool *emits, hz_error *err);

/* The dense samples `values` (uniformgrid_params' counts) as gm's density
 * grid: placed by the CTM, the support clipped to the box p0..p1, as
 * pbrt-v4's SampledGrid clips. */
hz_status grid_medium_adopt_dense(medium_entity *e, transform render_from_world,
                                 const uniformgrid_params *u, const double *values,
                                 const char *what, const medium_times *times, grid_medium *gm,
                                 hz_error *err);

/* A grid medium's ray at one scene time (the index-space ray, the velocity
 * shift, the support at that time) into r->at.grid. False for a degenerate
 * ray (non-finite in index space). */
bool grid_medium_ray_make(const medium *m, vec3 o, vec3 d, double time, medium_ray *r);
/* Clips [*t0, *t1] to the ray's support box (unchanged for a non-zero
 * background). False when nothing is left (also for an empty grid or NaN). */
bool grid_medium_ray_clip(const medium *m, const medium_ray *r, double *t0, double *t1);
void grid_medium_accessors_init(const medium *m, medium_ray *r);

/* The index-space point whose values o + t d of a grid ray shows: the ray's
 * point, moved back along the velocity field when the ray has a shift. Adds
 * the velocity lookup it made, if any, to *lookups. */
static inline vec3 grid_medium_point_at(const grid_medium *gm, medium_ray *r, double t,
                                        uint64_t *lookups)
{
    vec3 p = v3_add(r->at.grid.o, v3_scale(r->at.grid.d, t));
    if (r->at.grid.shift != 0.0) {
        vec3 q = gm->velocity_aligned ? p : transform_point(&gm->vindex_from_index, p);
        vec3 v = grid_vec3_index(gm->velocity, &r->acc.velocity, q);
        p = v3_sub(p, v3_scale(transform_vector(&gm->index_from_medium, v), r->at.grid.shift));
        ++*lookups;
    }
    return p;
}

/* Emitted radiance at a density-index point p of an emissive grid medium
 * (the source term is sigma_a density Le). */
static inline rgb grid_medium_Le(const medium *m, const grid_medium *gm, medium_ray *r, vec3 p,
                                 uint64_t *lookups)
{
    double s = gm->Le_scale;
    if (gm->Le_scale_grid) {
        ++*lookups;
        s *= grid_density_index(gm->Le_scale_grid, &r->acc.Le_scale,
                                transform_point(&gm->lsindex_from_index, p));
        if (!(s > 0.0))
            return rgb_grey(0.0);
    }
    if (!gm->temperature)
        return rgb_scale(m->Le, s);
    vec3 q = gm->temperature_aligned ? p : transform_point(&gm->tindex_from_index, p);
    ++*lookups;
    double T = (grid_density_index(gm->temperature, &r->acc.temperature, q) -
                gm->temperature_offset) *
               gm->temperature_scale;
    rgb c = blackbody_table_at(&gm->blackbody, T);
    if (m->spectral)
        c = spectral_from_rgb(m->spectral, c, SPECTRAL_ILLUMINANT);
    return rgb_scale(c, s);
}

/* Free emission at a density-index point p: the radiance emitted per unit
 * length there. */
static inline rgb grid_medium_emission(const grid_medium *gm, medium_ray *r, vec3 p,
                                       uint64_t *lookups)
{
    vec3 q = gm->emission_aligned ? p : transform_point(&gm->eindex_from_index, p);
    ++*lookups;
    double e = grid_density_index(gm->emission, &r->acc.emission, q) * gm->emission_scale;
    if (!(e > 0.0))
        return rgb_grey(0.0);
    if (!gm->emission_by_temperature)
        return r->m->spectral ? spectral_from_rgb(r->m->spectral, rgb_scale(gm->emission_tint, e),
                                                  SPECTRAL_ILLUMINANT)
                              : rgb_scale(gm->emission_tint, e);
    vec3 qt = gm->temperature_aligned ? p : transform_point(&gm->tindex_from_index, p);
    ++*lookups;
    double T = (grid_density_index(gm->temperature, &r->acc.temperature, qt) -
                gm->temperature_offset) *
               gm->temperature_scale;
    rgb c = blackbody_table_at(&gm->blackbody, T);
    double y = rgb_luminance(c);
    if (!(y > 0.0))
        return rgb_grey(0.0);
    c = rgb_scale(c, e / y);
    return r->m->spectral ? spectral_from_rgb(r->m->spectral, c, SPECTRAL_ILLUMINANT) : c;
}

/* The colour grid's albedo scale at a density-index point p, each channel
 * clamped to [0, 1]. */
static inline rgb grid_medium_color(const grid_medium *gm, medium_ray *r, vec3 p,
                                    uint64_t *lookups)
{
    vec3 q = gm->color_aligned ? p : transform_point(&gm->cindex_from_index, p);
    ++*lookups;
    vec3 c = grid_vec3_index(gm->color, &r->acc.color, q);
    rgb C = rgb_make(fmin(fmax(c.x, 0.0), 1.0), fmin(fmax(c.y, 0.0), 1.0),
                     fmin(fmax(c.z, 0.0), 1.0));
    return r->m->spectral ? spectral_from_rgb(r->m->spectral, C, SPECTRAL_ALBEDO) : C;
}

/* The density kinds' (nanovdb, uniformgrid) lookups: medium_ops' sample,
 * density and density_point. */
#define GRID_MEDIUM_DENSITY_OPS                                                                    \
    .density_grid = true, .destroy = grid_medium_destroy, .clip = grid_medium_clip,               \
    .ray_start = grid_medium_ray_start, .sample = grid_medium_sample,                              \
    .density = grid_medium_density, .density_point = grid_medium_density_point,                    \
    .support = grid_medium_support, .density_max = grid_medium_density_max,                        \
    .clear_along = grid_medium_clear_along,                                                        \
    .memory = grid_medium_memory, .work = grid_medium_work, .moves = grid_medium_moves
void grid_medium_sample(medium_ray *r, double t, bool emission, medium_props *p,
                        uint64_t *lookups);
double grid_medium_density(medium_ray *r, double t, uint64_t *lookups);
void grid_medium_density_point(medium_ray *r, double t, medium_density_point *p,
                               uint64_t *lookups);

#endif
