/* The shadow cache (Integrator "singlescatter" or "volpath", "float
 * shadowcache" S): for each distant light shining into a grid medium, the
 * transmittance toward the light tabulated on a grid aligned with the light,
 * so that the scattering points in that medium (singlescatter's
 * in-scattering samples of camera rays, volpath's scattering vertices) look
 * it up instead of tracing a shadow ray (a deep shadow map, Lokovic & Veach
 * 2000).
 *
 * The grid's nodes are S voxels of the medium apart (the geometric mean of
 * its voxel's edges in render space) and cover the medium's support box; its
 * third axis points at the light, so each column of nodes lies on one shadow
 * ray. Each column is one walk toward the light through the whole scene, as a
 * shadow ray walks: media between crossings (interfaces switch the medium;
 * grids marched at the node spacing, one midpoint per piece between nodes),
 * surfaces block. A node keeps the optical depth above it (RGB) and whether a
 * surface lies above it; a lookup interpolates both, Catmull-Rom across the
 * light (4 x 4 columns) and linearly along it: T = V exp(-tau). A column starts below the support box in the cached
 * medium, so nodes outside the medium's interface (where no scattering
 * happens) read its density too; they matter only to points within one node
 * of a boundary that clips the grid.
 *
 * The error is the marching of the columns and the interpolation between
 * them: both shrink as S squared in smooth media; a surface's shadow edge is
 * blurred over one node. It replaces shadow rays, so it needs a static
 * scene (render_scene refuses it otherwise). A column is walked when a
 * lookup first needs it (its 4 x 4 neighbourhood), so a cache costs the
 * columns the render reaches. The same scene gives the same cache for any
 * thread count. */
#ifndef HAZE_INTEGRATOR_SHADOW_CACHE_H
#define HAZE_INTEGRATOR_SHADOW_CACHE_H

#include <stddef.h>
#include <stdio.h>

#include "core/error.h"
#include "integrator/path.h"
#include "scene/params.h"

/* Caches are capped at this many nodes each (16 bytes a node); a larger one
 * is built with a coarser spacing, with a warning. */
#define SHADOW_CACHE_MAX_NODES (1u << 23)

typedef struct shadow_cache shadow_cache;

/* An integrator's "float shadowcache" (default `dflt`): a node spacing in
 * voxels >= 0, 0 for no cache; anything else is refused at its place. */
double shadow_cache_spacing_param(param_list *pl, double dflt);

/* Every (grid medium, distant light) pair of a scene. */
typedef struct shadow_caches shadow_caches;

/* Makes the caches of every grid medium and distant light of `in` at
 * `spacing` voxels (> 0); their columns are built by the lookups (`in` must
 * outlive the caches), or, for columns too long for that, here on up to
 * `threads` threads (< 1: one per core). Says on `warn` (may be NULL) where
 * a cap coarsened one. */
hz_status shadow_caches_create(const integrator_inputs *in, double spacing, int threads,
                               FILE *warn, shadow_caches **out, hz_error *err);
void shadow_caches_destroy(shadow_caches *c);

/* The cache of grid medium `medium` and light `light`; NULL when that pair has
 * none (not a grid, not a distant light). `c` may be NULL. */
const shadow_cache *shadow_caches_get(const shadow_caches *c, int medium, size_t light);

/* Bytes the caches hold. */
size_t shadow_caches_bytes(const shadow_caches *c);

/* Transmittance from render-space point p toward the cache's light. */
rgb shadow_cache_transmittance(const shadow_cache *c, vec3 p, const spectral_ctx *sp);

#endif
