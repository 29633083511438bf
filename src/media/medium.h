/* Participating media in render space: a closed set (homogeneous, grid)
 * dispatched with a switch. Built from MakeNamedMedium entities:
 *
 *   "homogeneous": sigma_a, sigma_s (spectra, default 1), scale (default 1),
 *                  g (Henyey–Greenstein, default 0), Le (an illuminant
 *                  spectrum, default 0, normalised as a light's: "rgb Le"
 *                  stays that RGB, "blackbody Le" has luminance 1) times
 *                  Lescale (default 1).
 *
 * Emission is absorbing emission, as in pbrt-v4: the source term along a ray
 * is sigma_a(x) Le(x), so a medium that does not absorb does not glow.
 *   "uniformgrid": pbrt-v4's dense grid (media/uniformgrid.h): nx, ny, nz,
 *                  density (nx ny nz floats), p0, p1, the same sigma_a, sigma_s,
 *                  scale, g; emission from temperature (as many floats, with
 *                  temperatureoffset/cutoff and temperaturescale) or Le, times
 *                  the Lescale grid (as many floats; absent: one sample of 1
 *                  at the box's centre, which pbrt-v4 interpolates to 1/8 at
 *                  the corners).
 *   "cloud":       pbrt-v4's procedural cloud (media/cloud.h): density (1),
 *                  wispiness (1), frequency (5), p0, p1 (0 0 0, 1 1 1), the
 *                  same sigma_a, sigma_s, scale, g; rendered by volpath only.
 *   "rgbgrid":     pbrt-v4's grid of rgb sigma_a, sigma_s, Le samples (nx ny nz,
 *                  p0, p1, scale, Lescale, g), as uniformgrid places them;
 *                  rendered by volpath only.
 *   "nanovdb":     filename (.vdb or .nvdb, relative to the scene file that
 *                  declares the medium), gridname (default "density"), and the
 *                  same sigma_a, sigma_s, scale, g; the coefficients are per unit
 *                  density, so sigma_t(p) = (sigma_a + sigma_s) * scale * density(p).
 *                  Motion blur from a velocity grid: velocityname (a vec3 grid of
 *                  the same file; absent: none), velocityscale (default 1, >= 0),
 *                  velocitytime (default: the TransformTimes start).
 *                  Emission from a temperature grid, as pbrt-v4: temperaturename
 *                  (default "temperature": used when the file has such a grid;
 *                  named explicitly, it must exist), temperatureoffset (or its
 *                  older name temperaturecutoff; default 0), temperaturescale
 *                  (default 1), Lescale (default 1): Le(x) = Lescale B(T) with
 *                  T = (value - offset) * scale, zero at or below 100 K, B
 *                  pbrt-v4's peak-normalised blackbody as its film sees it
 *                  (media/blackbody.h). The temperature grid has its own
 *                  transform and moves with the density (placement, velocity).
 *
 * A medium is placed by the transform current at its MakeNamedMedium. A grid's
 * density is the trilinear field of its voxel values (values at integer index
 * points, background elsewhere); it is not clipped at the grid's bounding box,
 * so it reaches one voxel beyond the active voxels (pbrt-v4 clips at index
 * [min, max + 1]).
 *
 * Moving grids. A grid medium declared under an animated transform (start and
 * end CTMs differ) moves with it: a ray at scene time t sees the grid placed by
 * pbrt-v4's AnimatedTransform interpolation at t. With a velocity grid v, the
 * density at a point x (in the grid's world space, i.e. medium space) and time
 * t is density(x - v(x) * velocityscale * (t - velocitytime)): first-order
 * Eulerian motion blur. Both combine (the velocity is relative to the moving
 * frame). Static grids (equal keyframes, no velocity grid) run the same code
 * as before motion existed. */
#ifndef HAZE_MEDIA_MEDIUM_H
#define HAZE_MEDIA_MEDIUM_H

#include <stdbool.h>
#include <math.h>
#include <stdint.h>

#include "core/animated_transform.h"
#include "core/error.h"
#include "core/transform.h"
#include "core/vec.h"
#include "media/blackbody.h"
#include "media/cloud.h"
#include "media/grid.h"
#include "media/majorant.h"
#include "scene/scene_desc.h"

typedef enum { MEDIUM_HOMOGENEOUS, MEDIUM_GRID, MEDIUM_CLOUD, MEDIUM_RGBGRID } medium_kind;

typedef struct {
    medium_kind kind;
    const char *name;        /* the MakeNamedMedium name (points into the scene_desc) */
    rgb sigma_a, sigma_s;    /* `scale` applied; grid media: per unit density */
    double g;                /* Henyey–Greenstein asymmetry */
    rgb Le;                  /* homogeneous emission (Lescale applied); source sigma_a Le */
    bool emissive;           /* absorbing emission (sigma_a Le): the integrators gather it */
    bool free_emission;      /* emission whatever the density (grid.emission) */
    bool coloured;           /* a colour grid scales the scattering albedo */
    struct {
        grid *grid;                  /* owned */
        /* Grid index space from render space: affine, so a ray o + t d in render
         * space is (A o + b) + t (A d) in index space with the same t. */
        transform index_from_render;
        /* Where the density can differ from the background: the index-space
         * box [min - 1, max + 1] of the active voxels. With a zero background
         * the density is 0 outside it; lo > hi for an empty grid. */
        vec3 support_lo, support_hi;
        double background;           /* density outside the support */
        double density_max;          /* >= every density value of the field, >= 0 */
        /* Per-cell density bounds over the support, at every time of the
         * shutter (velocity displacement included): empty-space skipping
         * and local majorants for the estimators. */
        majorant_grid majorant;

        /* An animated placement: index_from_render above is the start's, and a
         * ray at time t uses index_from_medium ∘ inverse(render_from_medium(t)). */
        bool moving;
        animated_transform render_from_medium; /* moving only */
        /* The grid's own map (index from its world space, i.e. medium space). */
        transform index_from_medium;

        /* Temperature (emission); NULL: none. */
        grid *temperature;               /* owned; a float grid */
        bool temperature_aligned;        /* same index space as the density grid */
        transform tindex_from_index;     /* temperature index from density index */
        double temperature_offset, temperature_scale, Le_scale;
        blackbody_table blackbody;       /* over the grid's temperature range */
        /* uniformgrid: pbrt-v4's Lescale grid (NULL otherwise), the same index
         * space as the density or one sample spanning the box; emission is
         * Le_scale_grid(p) times the temperature's blackbody, or times Le. */
        grid *Le_scale_grid;             /* owned */
        transform lsindex_from_index;    /* its index from the density's index */

        /* Free emission ("emissionname"; NULL: none): radiance emitted per
         * unit length, emission_scale E(p) times a colour, whatever the
         * density: emission_tint, or (emission_by_temperature) the blackbody
         * colour, of luminance 1, of the temperature grid's kelvins. */
        grid *emission;                  /* owned; a float grid */
        bool emission_aligned;           /* same index space as the density grid */
        transform eindex_from_index;     /* its index from the density's index */
        rgb emission_tint;               /* luminance-normalised Le */
        double emission_scale;           /* Lescale */
        bool emission_by_temperature;
        /* A colour grid ("colorname"; NULL: none): per channel, the
         * scattering albedo times its value clamped to [0, 1]; sigma_t is
         * unchanged (what is not scattered is absorbed); absorbing emission
         * keeps the uncoloured sigma_a. */
        grid *color;                     /* owned; a vec3 grid */
        bool color_aligned;
        transform cindex_from_index;

        /* Velocity (Eulerian motion blur); NULL: none. */
        grid *velocity;                  /* owned; a vec3 grid, medium units per time */
        bool velocity_aligned;           /* same index space as the density grid */
        transform vindex_from_index;     /* velocity index from density index */
        double velocity_scale, velocity_time;
        /* Growth of the support box, in index units per unit of
         * |velocity_scale (t - velocity_time)|: the longest velocity times the
         * length of each row of index_from_medium's linear part. */
        vec3 dilation;
    } grid;                  /* MEDIUM_GRID only */
    struct {
        cloud_params params;
        vec3 p0, p1;                 /* the box, medium space */
        transform medium_from_render;
    } cloud;                 /* MEDIUM_CLOUD only: volpath renders it */
    /* MEDIUM_RGBGRID: pbrt-v4's rgbgrid. grid.grid holds, per sample, the
     * largest channel of sigma_a + sigma_s (scale applied): the placement,
     * support and majorant of grid media; these hold the channels (same
     * index space; NULL: 1 everywhere in the box for sigma_a/sigma_s, no
     * emission for Le). volpath renders it. */
    struct {
        grid *sigma_a[3], *sigma_s[3], *Le[3];
        double scale, Le_scale;
    } rgbg;
} medium;

/* When a medium lives: TransformTimes (a medium whose start and end
 * transforms differ moves between them; velocitytime defaults to the start),
 * and the times rays can have (the camera's shutter, which may reach beyond
 * them): a velocity grid's bounds cover its displacement at every ray time. */
typedef struct {
    double transform_start, transform_end;
    double ray_min, ray_max;
} medium_times;

/* Builds the medium of `e` in render space. Unknown types, missing or unreadable
 * files, a missing grid, non-float grids, negative coefficients and |g| >= 1
 * are errors naming the entity's file:line:column; unused parameters too. */
hz_status medium_from_entity(medium_entity *e, transform render_from_world,
                             const medium_times *times, medium *out, hz_error *err);
void medium_free(medium *m);

static inline rgb medium_sigma_t(const medium *m) { return rgb_add(m->sigma_a, m->sigma_s); }

/* A grid medium as one ray at one scene time sees it: what every lookup along
 * the ray needs, computed once per ray segment. */
typedef struct {
    vec3 o, d;         /* the ray in the density grid's index space: o + t d, same t */
    double shift;      /* velocity_scale (time - velocity_time); 0 without velocity */
    vec3 lo, hi;       /* where the density can be non-zero at this time (index space) */
} medium_grid_ray;

/* Maps the render-space ray o + t d at scene `time` into a grid medium. False
 * for a degenerate ray (non-finite in index space), which cannot sample the
 * field meaningfully. */
bool medium_grid_ray_make(const medium *m, vec3 o, vec3 d, double time, medium_grid_ray *out);

/* Clips [*t0, *t1] to the ray's support box (unchanged for a non-zero
 * background). False when nothing is left (also for an empty grid or NaN). */
bool medium_grid_ray_clip(const medium *m, const medium_grid_ray *r, double *t0, double *t1);

/* Clips the render-space ray o + t d at scene `time`, t in [*t0, *t1], to where
 * the medium can attenuate or scatter: unchanged for homogeneous media (and
 * for grids with a non-zero background), the support box at that time for
 * grids. False when nothing is left. */
bool medium_clip(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1);

/* Whether none of the n media has density anywhere along o + t d, t in
 * [t0, t1], at `time`: each is a grid with a zero background whose majorant
 * cells on the ray are all empty (or the ray misses its support). A shadow
 * ray from vacuum for which this holds passes all light through whatever
 * interfaces it crosses: an occlusion test decides it. *cells counts the
 * majorant cells visited. */
bool media_clear_along(const medium *media, size_t n, vec3 o, vec3 d, double t0, double t1,
                       double time, uint64_t *cells);

/* Clips the render-space ray o + t d, t in [*t0, *t1], to a cloud medium's
 * box. False when nothing is left. */
bool medium_cloud_clip(const medium *m, vec3 o, vec3 d, double *t0, double *t1);

/* Per-thread lookup caches of a grid medium's grids. */
typedef struct {
    grid_accessor density, velocity, temperature, Le_scale, emission, color;
    grid_accessor rgb[9]; /* rgbgrid: sigma_a, sigma_s, Le channels */
} medium_accessor;

void medium_accessor_init(const medium *m, medium_accessor *a);

/* Trilinear density at an index-space point (grid media), without motion. */
static inline double medium_density_index(const medium *m, grid_accessor *a, vec3 p_index)
{
    return grid_density_index(m->grid.grid, a, p_index);
}

/* The index-space point whose values o + t d of a grid ray shows: the ray's
 * point, moved back along the velocity field when the ray has a shift. Adds
 * the velocity lookup it made, if any, to *lookups. */
static inline vec3 medium_point_at(const medium *m, medium_accessor *a, const medium_grid_ray *r,
                                   double t, uint64_t *lookups)
{
    vec3 p = v3_add(r->o, v3_scale(r->d, t));
    if (r->shift != 0.0) {
        vec3 q = m->grid.velocity_aligned ? p : transform_point(&m->grid.vindex_from_index, p);
        vec3 v = grid_vec3_index(m->grid.velocity, &a->velocity, q);
        p = v3_sub(p, v3_scale(transform_vector(&m->grid.index_from_medium, v), r->shift));
        ++*lookups;
    }
    return p;
}

/* Density at o + t d of a grid ray (medium_point_at). Adds the grid lookups
 * it made (1, or 2 with a velocity lookup) to *lookups. */
static inline double medium_density_at(const medium *m, medium_accessor *a,
                                       const medium_grid_ray *r, double t, uint64_t *lookups)
{
    vec3 p = medium_point_at(m, a, r, t, lookups);
    ++*lookups;
    return grid_density_index(m->grid.grid, &a->density, p);
}

/* An rgbgrid's coefficients and emission at a density-index point p. */
static inline void medium_rgbgrid_at(const medium *m, medium_accessor *a, vec3 p, rgb *sigma_a,
                                     rgb *sigma_s, rgb *Le, uint64_t *lookups)
{
    double v[3][3];
    grid *const *g[3] = {m->rgbg.sigma_a, m->rgbg.sigma_s, m->rgbg.Le};
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) {
            if (g[k][c]) {
                ++*lookups;
                v[k][c] = grid_density_index(g[k][c], &a->rgb[3 * k + c], p);
            } else {
                v[k][c] = k < 2 ? 1.0 : 0.0;
            }
        }
    double s = m->rgbg.scale, e = m->rgbg.Le_scale;
    *sigma_a = rgb_make(s * v[0][0], s * v[0][1], s * v[0][2]);
    *sigma_s = rgb_make(s * v[1][0], s * v[1][1], s * v[1][2]);
    *Le = rgb_make(e * v[2][0], e * v[2][1], e * v[2][2]);
}

/* Emitted radiance at a density-index point p of an emissive grid medium
 * (the source term is sigma_a density Le). */
static inline rgb medium_grid_Le(const medium *m, medium_accessor *a, vec3 p, uint64_t *lookups)
{
    double s = m->grid.Le_scale;
    if (m->grid.Le_scale_grid) {
        ++*lookups;
        s *= grid_density_index(m->grid.Le_scale_grid, &a->Le_scale,
                                transform_point(&m->grid.lsindex_from_index, p));
        if (!(s > 0.0))
            return rgb_grey(0.0);
    }
    if (!m->grid.temperature)
        return rgb_scale(m->Le, s);
    vec3 q = m->grid.temperature_aligned ? p : transform_point(&m->grid.tindex_from_index, p);
    ++*lookups;
    double T = (grid_density_index(m->grid.temperature, &a->temperature, q) -
                m->grid.temperature_offset) *
               m->grid.temperature_scale;
    return rgb_scale(blackbody_table_at(&m->grid.blackbody, T), s);
}

/* Free emission at a density-index point p (m->free_emission): the radiance
 * emitted per unit length there. */
static inline rgb medium_grid_emission(const medium *m, medium_accessor *a, vec3 p,
                                       uint64_t *lookups)
{
    vec3 q = m->grid.emission_aligned ? p : transform_point(&m->grid.eindex_from_index, p);
    ++*lookups;
    double e = grid_density_index(m->grid.emission, &a->emission, q) * m->grid.emission_scale;
    if (!(e > 0.0))
        return rgb_grey(0.0);
    if (!m->grid.emission_by_temperature)
        return rgb_scale(m->grid.emission_tint, e);
    vec3 qt = m->grid.temperature_aligned ? p : transform_point(&m->grid.tindex_from_index, p);
    ++*lookups;
    double T = (grid_density_index(m->grid.temperature, &a->temperature, qt) -
                m->grid.temperature_offset) *
               m->grid.temperature_scale;
    rgb c = blackbody_table_at(&m->grid.blackbody, T);
    double y = rgb_luminance(c);
    return y > 0.0 ? rgb_scale(c, e / y) : rgb_grey(0.0);
}

/* The colour grid's albedo scale at a density-index point p (m->coloured),
 * each channel clamped to [0, 1]. */
static inline rgb medium_grid_color(const medium *m, medium_accessor *a, vec3 p,
                                    uint64_t *lookups)
{
    vec3 q = m->grid.color_aligned ? p : transform_point(&m->grid.cindex_from_index, p);
    ++*lookups;
    vec3 c = grid_vec3_index(m->grid.color, &a->color, q);
    return rgb_make(fmin(fmax(c.x, 0.0), 1.0), fmin(fmax(c.y, 0.0), 1.0),
                    fmin(fmax(c.z, 0.0), 1.0));
}

#endif
