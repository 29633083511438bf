/* Participating media: the one interface every other module uses (pbrt-v4's
 * base/medium.h, Mitsuba 3's Medium). A medium answers three questions:
 *   - its coefficients at a point of a ray, at the ray's time (sample):
 *     sigma_a, sigma_s and the emission there;
 *   - the majorant segments along a ray: intervals [t0, t1] with a bound of
 *     the density in each, sigma_maj = medium_sigma_t(m) * max, in order
 *     (medium_ray_next), so estimators skip empty space;
 *   - what it costs and whether it moves (medium_bytes, medium_moves).
 * Estimators differ only in what they do at each tentative collision; none
 * sees a medium's kind.
 *
 * Kinds (one file each, a row each in medium_kinds.c's table; the
 * parameters of each are in docs/scene-format.md and docs/media.md):
 *   homogeneous.c       "homogeneous": constant coefficients (closed forms)
 *   nanovdb_medium.c    "nanovdb": a NanoVDB/OpenVDB density grid, with
 *                       velocity, temperature, emission and colour grids
 *   uniformgrid_medium.c "uniformgrid": pbrt-v4's dense density grid
 *   rgbgrid.c           "rgbgrid": pbrt-v4's grid of RGB coefficients
 *   cloud_medium.c      "cloud": pbrt-v4's procedural cloud
 * The three grid kinds share the placement, support and majorant grid of
 * media/grid_medium.h.
 *
 * Emission is absorbing emission, as in pbrt-v4: the source term along a ray
 * is sigma_a(x) Le(x), so a medium that does not absorb does not glow;
 * haze's free emission grids add radiance per unit length whatever the
 * density. A medium is placed by the transform current at its
 * MakeNamedMedium. */
#ifndef HAZE_MEDIA_MEDIUM_H
#define HAZE_MEDIA_MEDIUM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "color/spectral.h"
#include "core/error.h"
#include "core/transform.h"
#include "core/vec.h"
#include "media/grid.h"
#include "media/majorant.h"
#include "scene/scene_desc.h"

typedef struct medium medium;
typedef struct medium_ray medium_ray;

/* When a medium lives: TransformTimes (a medium whose start and end
 * transforms differ moves between them; velocitytime defaults to the start),
 * and the times rays can have (the camera's shutter, which may reach beyond
 * them): a velocity grid's bounds cover its displacement at every ray time. */
typedef struct {
    double transform_start, transform_end;
    double ray_min, ray_max;
} medium_times;

/* What a kind's create gets besides the entity. */
typedef struct {
    transform render_from_world;
    const medium_times *times;
    FILE *warn; /* warnings (NULL: none) */
} medium_build;

/* pbrt-v4's MediumProperties: the coefficients at a point (density applied)
 * and the source term there, per unit length (sigma_a Le plus free
 * emission; 0 unless asked for). */
typedef struct {
    rgb sigma_a, sigma_s, emission;
} medium_props;

/* A density-grid medium's point, as haze's marching estimators take it
 * apart: the density (sigma_t = density * medium_sigma_t), and where they
 * apply the absorbing emission's Le (density > 0), the free emission per
 * unit length, and the colour grid's albedo scale C (density > 0; 1
 * elsewhere). */
typedef struct {
    double density;
    rgb Le, eps, C;
} medium_density_point;

/* Memory a medium holds: its grids' buffers, its majorant grid. */
typedef struct {
    double grids, majorants;
} medium_memory;

/* Work a medium does on demand while rendering: the majorant bricks whose
 * cells were bounded at their first use, and the time that took on the
 * threads that did it (seconds summed over threads). */
typedef struct {
    size_t majorant_bricks;
    double majorant_seconds;
} medium_work;

/* What a kind implements. Properties are what the integrators may ask:
 * `homogeneous` (constant coefficients everywhere: closed forms apply) and
 * `density_grid` (a voxel density times constant coefficients: singlescatter's
 * marching estimators, its step sizes in voxels and the shadow cache apply);
 * a kind that is neither is rendered by volpath only. */
typedef struct {
    const char *name; /* the MakeNamedMedium type */
    bool homogeneous, density_grid;
    /* sigma_a and sigma_s are RGB values looked up per point, whose
     * majorant is their largest channel (rgbgrid) */
    bool rgb_coefficients;
    /* Reads e's parameters (errors name their file:line:column) and builds
     * the medium into *out, whose common fields medium_create has zeroed. */
    hz_status (*create)(medium_entity *e, const medium_build *b, medium *out, hz_error *err);
    void (*destroy)(medium *m);
    /* Clips [*t0, *t1] of o + t d at `time` to where the medium can be
     * non-zero then (NULL: everywhere); false when nothing is left. */
    bool (*clip)(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1);
    /* Starts r on o + t d at `time` over [*t0, *t1], clipped as `clip`
     * does; false when nothing is left. */
    bool (*ray_start)(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1,
                      medium_ray *r);
    void (*sample)(medium_ray *r, double t, bool emission, medium_props *p, uint64_t *lookups);
    /* density_grid kinds only (NULL otherwise). */
    double (*density)(medium_ray *r, double t, uint64_t *lookups);
    void (*density_point)(medium_ray *r, double t, medium_density_point *p, uint64_t *lookups);
    /* Where the density can be non-zero (render space box corners at time
     * 0) and a voxel's length; false when unbounded or empty. */
    bool (*support)(const medium *m, vec3 corners[8], double *voxel);
    /* density_grid kinds: a bound >= every density value of the field. */
    double (*density_max)(const medium *m);
    /* True when o + t d, t in [t0, t1], meets no density at `time`. */
    bool (*clear_along)(const medium *m, vec3 o, vec3 d, double t0, double t1, double time,
                        uint64_t *cells);
    medium_memory (*memory)(const medium *m);
    medium_work (*work)(const medium *m); /* NULL: none */
    bool (*moves)(const medium *m);
} medium_ops;

/* A medium in render space. The common fields are what every kind has;
 * `state` is the kind's own (owned; opaque outside its file). */
struct medium {
    const medium_ops *ops;   /* NULL: an empty slot (a refused medium) */
    const char *name;        /* the MakeNamedMedium name (points into the scene_desc) */
    rgb sigma_a, sigma_s;    /* `scale` applied; density grids: per unit density */
    double g;                /* Henyey–Greenstein asymmetry */
    rgb Le;                  /* constant emission (Lescale applied); source sigma_a Le */
    bool emissive;           /* absorbing emission (sigma_a Le): the integrators gather it */
    bool free_emission;      /* emission whatever the density (nanovdb's emission grid) */
    bool coloured;           /* a colour grid scales the scattering albedo */
    /* sigma_a, sigma_s and Le as the scene gave them: each of the rgb
     * fields above is a multiple of its spectrum's rgb (spectral rendering
     * evaluates the spectrum at the path's wavelengths, medium_spectral). */
    spectrum_value sigma_a_spec, sigma_s_spec, Le_spec;
    /* Spectral rendering: sigma_a, sigma_s and Le's RGB spectra looked up
     * once (medium_prepare_spectral). */
    struct {
        spectral_color sigma_a, sigma_s, Le;
    } prepared;
    /* Spectral rendering: a path's copy of the medium (medium_spectral)
     * holds its coefficients at these wavelengths, and the kinds turn the
     * colours they look up into them; NULL: RGB. */
    const spectral_ctx *spectral;
    void *state;
};

/* A ray in one medium: its majorant iterator (one segment for media without
 * a majorant grid, pbrt-v4's HomogeneousMajorantIterator; otherwise a DDA
 * over the majorant grid) and what lookups along it need (the kind's). */
struct medium_ray {
    const medium *m;
    double voxels_per_t; /* density grids: voxels per unit t (the step sizes' unit) */
    /* Non-NULL when the density at o + t d is this grid's trilinear value at
     * at.grid.o + t at.grid.d (a density grid that does not move along the
     * ray): medium_ray_density looks it up inline, without a call through
     * the kind's ops. `plain`: and its coefficients are that density times
     * sigma_a and sigma_s, with no emission (no colour or emission grids),
     * so medium_ray_sample is inline too. */
    const grid *lookup;
    bool plain;
    bool dda, single_left;
    majorant_segment single;
    majorant_walk mw;
    /* the kind's state for lookups */
    union {
        struct {
            vec3 o, d;    /* the ray in the density grid's index space: o + t d, same t */
            double shift; /* velocity_scale (time - velocity_time); 0 without velocity */
            vec3 lo, hi;  /* where the density can be non-zero at this time (index space) */
        } grid;
        struct {
            vec3 o, d; /* the ray in medium space, same t */
        } cloud;
    } at;
    struct {
        grid_accessor density, velocity, temperature, Le_scale, emission, color;
        grid_accessor rgb[9]; /* rgbgrid: sigma_a, sigma_s, Le channels */
    } acc;
};

/* Builds the medium of `e` in render space, by its type's row of the kinds'
 * table. Unknown types and the kind's parameter errors name the entity's
 * file:line:column; unused parameters too. Warnings go to `warn` (NULL:
 * none). */
hz_status medium_create(medium_entity *e, transform render_from_world, const medium_times *times,
                        FILE *warn, medium *out, hz_error *err);
void medium_destroy(medium *m);

/* The kind named `type`, NULL when there is none. */
const medium_ops *medium_kind(const char *type);
/* Whether a medium of `type` is rendered by volpath only (false for unknown
 * types: medium_create refuses them). */
bool medium_type_volpath_only(const char *type);

static inline rgb medium_sigma_t(const medium *m) { return rgb_add(m->sigma_a, m->sigma_s); }
static inline bool medium_is_homogeneous(const medium *m) { return m->ops->homogeneous; }
static inline bool medium_is_density_grid(const medium *m) { return m->ops->density_grid; }
static inline const char *medium_type(const medium *m) { return m->ops->name; }
static inline bool medium_moves(const medium *m)
{
    return m->ops && m->ops->moves && m->ops->moves(m);
}
medium_memory medium_bytes(const medium *m);
/* The work m did on demand so far (zero for kinds that do none). */
medium_work medium_work_done(const medium *m);

/* Whether m's coefficients differ between channels (constant ones not
 * grey, per-point RGB coefficients, a colour grid): where spectral and RGB
 * rendering differ. */
bool medium_is_chromatic(const medium *m);

/* Looks up the RGB spectra of m's coefficients once (m->prepared). */
void medium_prepare_spectral(medium *m, const rgb2spec_table *t);

/* m at the wavelengths of `sp`, for one path: a copy whose sigma_a and
 * sigma_s are unbounded spectra and whose Le is an illuminant spectrum
 * there (color/spectral.h), with `spectral` set so the kinds convert what
 * they look up; m itself when sp is NULL. */
const medium *medium_spectral(const medium *m, const spectral_ctx *sp, medium *copy);

/* Starts a ray in m: o + t d at scene `time`, t in [*t0, *t1] clipped to
 * where the medium can attenuate, scatter or emit. False when nothing is
 * left (also for a degenerate ray). */
static inline bool medium_ray_start(const medium *m, vec3 o, vec3 d, double time, double *t0,
                                    double *t1, medium_ray *r)
{
    return m->ops->ray_start(m, o, d, time, t0, t1, r);
}

/* The next majorant segment, or false at the end of the ray's span.
 * Segments are contiguous; *steps counts majorant-grid cells crossed. */
static inline bool medium_ray_next(medium_ray *r, majorant_segment *seg, uint64_t *steps)
{
    if (r->dda) {
        if (!majorant_walk_next(&r->mw, seg))
            return false;
        ++*steps;
        return true;
    }
    if (!r->single_left)
        return false;
    r->single_left = false;
    *seg = r->single;
    return true;
}

/* Before the first medium_ray_next: the caller samples the ray every
 * `voxels` voxels or more and needs of a segment's bounds only whether they
 * are 0, so segments may be coarser (majorant_walk_coarsen). */
static inline void medium_ray_coarsen(medium_ray *r, double voxels)
{
    if (r->dda)
        majorant_walk_coarsen(&r->mw, voxels);
}

/* pbrt-v4's SamplePoint at o + t d; `emission`: fill p->emission. Adds its
 * lookups to *lookups. */
static inline void medium_ray_sample(medium_ray *r, double t, bool emission, medium_props *p,
                                     uint64_t *lookups)
{
    if (r->plain) {
        ++*lookups;
        double d = grid_density_index(r->lookup, &r->acc.density,
                                      v3_add(r->at.grid.o, v3_scale(r->at.grid.d, t)));
        p->sigma_a = rgb_scale(r->m->sigma_a, d);
        p->sigma_s = rgb_scale(r->m->sigma_s, d);
        p->emission = rgb_grey(0.0);
        return;
    }
    r->m->ops->sample(r, t, emission, p, lookups);
}

/* Density grids: the density at o + t d, and the point taken apart. */
static inline double medium_ray_density(medium_ray *r, double t, uint64_t *lookups)
{
    if (r->lookup) {
        ++*lookups;
        return grid_density_index(r->lookup, &r->acc.density,
                                  v3_add(r->at.grid.o, v3_scale(r->at.grid.d, t)));
    }
    return r->m->ops->density(r, t, lookups);
}
static inline void medium_ray_density_point(medium_ray *r, double t, medium_density_point *p,
                                            uint64_t *lookups)
{
    r->m->ops->density_point(r, t, p, lookups);
}

/* For kinds without a majorant grid: r's iterator yields the one segment
 * [t0, t1] with density bounds [min, max]. */
static inline void medium_ray_single(medium_ray *r, const medium *m, double t0, double t1,
                                     double max, double min)
{
    r->m = m;
    r->lookup = NULL;
    r->plain = false;
    r->voxels_per_t = 0.0;
    r->dda = false;
    r->single_left = true;
    r->single = (majorant_segment){t0, t1, max, min, 0.0};
}

/* The properties of m's coefficients scaled by density d, with absorbing
 * emission sigma_a Le when `emission`. */
static inline void medium_props_scaled(const medium *m, double d, bool emission, medium_props *p)
{
    p->sigma_a = rgb_scale(m->sigma_a, d);
    p->sigma_s = rgb_scale(m->sigma_s, d);
    p->emission = emission ? rgb_mul(p->sigma_a, m->Le) : rgb_grey(0.0);
}

/* Clips the render-space ray o + t d at scene `time`, t in [*t0, *t1], to where
 * the medium can attenuate or scatter. False when nothing is left. */
bool medium_clip(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1);

/* Density grids with a bounded support: its box's corners in render space
 * and the geometric mean of a voxel's edges; false otherwise. */
bool medium_support(const medium *m, vec3 corners[8], double *voxel);
/* Density grids: a bound >= every density value (sigma_t = density *
 * medium_sigma_t at most this times it); 0 for other kinds. */
double medium_density_max(const medium *m);

/* Whether none of the n media has density anywhere along o + t d, t in
 * [t0, t1], at `time`: each is a grid with a zero background whose majorant
 * cells on the ray are all empty (or the ray misses its support). A shadow
 * ray from vacuum for which this holds passes all light through whatever
 * interfaces it crosses: an occlusion test decides it. *cells counts the
 * majorant cells visited. */
bool media_clear_along(const medium *media, size_t n, vec3 o, vec3 d, double t0, double t1,
                       double time, uint64_t *cells);

#endif
