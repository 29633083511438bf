/* Loop subdivision (pbrt-v4's "loopsubdiv" shape): a triangle mesh refined
 * `levels` times by Loop's rules and its vertices moved to their limit
 * positions. */
#ifndef HAZE_SCENE_LOOPSUBDIV_H
#define HAZE_SCENE_LOOPSUBDIV_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

/* Each level: every edge gets a vertex (3/8 of its ends and 1/8 of the two
 * opposite corners; the midpoint on a boundary), every old vertex moves to
 * (1 - n beta) v + beta (its n neighbours), beta = 3/16 for n = 3 and 3/(8n)
 * otherwise (3/4 v + 1/8 of its two boundary neighbours on a boundary), and
 * each triangle becomes four. Then every vertex goes to its limit position
 * (gamma = 1/(n + 3/(8 beta)); 3/5 and 1/5 on a boundary), as pbrt-v4. The
 * normals are the area-weighted normals of the final triangles (pbrt-v4 takes
 * the limit surface's tangents; they agree to the refinement's accuracy).
 * *p (3 per vertex), *n (3 per vertex) and *idx (3 per triangle) are
 * malloc'd. Fails on an edge shared by more than two triangles, on an index
 * out of range, and when memory runs out. */
hz_status loop_subdivide(const double *p, size_t nv, const uint32_t *idx, size_t nt, int levels,
                         double **p_out, double **n_out, size_t *nv_out, uint32_t **idx_out,
                         size_t *nt_out, hz_error *err);

#endif
