/* Participating media in render space: a closed set (homogeneous, grid)
 * dispatched with a switch. Built from MakeNamedMedium entities:
 *
 *   "homogeneous": sigma_a, sigma_s (spectra, default 1), scale (default 1),
 *                  g (Henyey–Greenstein, default 0).
 *   "nanovdb":     filename (.vdb or .nvdb, relative to the scene file that
 *                  declares the medium), gridname (default "density"), and the
 *                  same sigma_a, sigma_s, scale, g; the coefficients are per unit
 *                  density, so sigma_t(p) = (sigma_a + sigma_s) * scale * density(p).
 *
 * A medium is placed by the transform current at its MakeNamedMedium. A grid's
 * density is the trilinear field of its voxel values (values at integer index
 * points, background elsewhere); it is not clipped at the grid's bounding box,
 * so it reaches one voxel beyond the active voxels (pbrt-v4 clips at index
 * [min, max + 1]). */
#ifndef HAZE_MEDIA_MEDIUM_H
#define HAZE_MEDIA_MEDIUM_H

#include <stdbool.h>

#include "core/error.h"
#include "core/transform.h"
#include "core/vec.h"
#include "media/grid.h"
#include "scene/scene_desc.h"

typedef enum { MEDIUM_HOMOGENEOUS, MEDIUM_GRID } medium_kind;

typedef struct {
    medium_kind kind;
    const char *name;        /* the MakeNamedMedium name (points into the scene_desc) */
    rgb sigma_a, sigma_s;    /* `scale` applied; grid media: per unit density */
    double g;                /* Henyey–Greenstein asymmetry */
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
    } grid;                  /* MEDIUM_GRID only */
} medium;

/* Builds the medium of `e` in render space. Unknown types, missing or unreadable
 * files, a missing grid, non-float grids, negative coefficients and |g| >= 1
 * are errors naming the entity's file:line:column; unused parameters too.
 * Emission (pbrt-v4's "Le") is refused unless it is zero. */
/* `time_start`/`time_end` are the scene's TransformTimes (a medium whose start and
 * end transforms differ moves between them). */
hz_status medium_from_entity(medium_entity *e, transform render_from_world, double time_start,
                             double time_end, medium *out, hz_error *err);
void medium_free(medium *m);

static inline rgb medium_sigma_t(const medium *m) { return rgb_add(m->sigma_a, m->sigma_s); }

/* Clips the render-space ray o + t d, t in [*t0, *t1], to where the medium can
 * attenuate or scatter: unchanged for homogeneous media (and for grids with a
 * non-zero background), the support box for grids. False when nothing is left. */
bool medium_clip(const medium *m, vec3 o, vec3 d, double *t0, double *t1);

/* Trilinear density at an index-space point (grid media). */
static inline double medium_density_index(const medium *m, grid_accessor *a, vec3 p_index)
{
    return grid_density_index(m->grid.grid, a, p_index);
}

#endif
