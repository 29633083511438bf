/* pbrt-v4's BVHLightSampler, haze's way: lights with bounds (point, spot,
 * static area lights) in a binary tree of light bounds (box, power, cone of
 * emission directions), built with pbrt-v4's bucketed cost; a light is chosen
 * by walking down the tree with probabilities proportional to each child's
 * importance at the shading point (power over distance², cut by the cones and
 * by the surface normal). Unbounded lights (distant; area lights on moving
 * shapes, whose bounds change over the shutter) are chosen uniformly with
 * probability count / (count + 1 if there is a tree), as pbrt-v4 does for
 * its infinite lights. The sky is never chosen (light_sampler.h).
 *
 * haze's area lights are whole shapes (pbrt-v4 makes one light per triangle):
 * a mesh's bounds hold all its triangles, its normal cone all their normals. */
#ifndef HAZE_LIGHTS_LIGHT_BVH_H
#define HAZE_LIGHTS_LIGHT_BVH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "lights/lights.h"

typedef struct {
    vec3 lo, hi;        /* box (render space) */
    double phi;         /* power bound (0: empty) */
    vec3 w;             /* unit axis of the emission cone */
    double cos_o, cos_e; /* normal spread and emission falloff about w */
    bool two_sided;
} light_bounds;

typedef struct {
    light_bounds b;
    size_t index; /* interior: second child's node; leaf: the scene light */
    bool leaf;
} light_bvh_node;

typedef struct {
    light_bvh_node *nodes;
    size_t node_count;
    size_t *unbounded;  /* scene indices */
    size_t unbounded_count;
    uint64_t *trail;    /* per scene light: its path from the root (bit d: second child);
                         * the tree is at most 64 levels deep for it */
    uint8_t *where;     /* per scene light: 0 never chosen, 1 unbounded, 2 in the tree */
} light_bvh;

hz_status light_bvh_build(const light *lights, size_t light_count, light_bvh *out,
                          hz_error *err);
void light_bvh_free(light_bvh *b);

/* `p` the shading point, `n` its unit normal (zero in a medium). */
bool light_bvh_sample(const light_bvh *b, vec3 p, vec3 n, double u, size_t *light, double *pmf);
double light_bvh_pmf(const light_bvh *b, vec3 p, vec3 n, size_t light);

/* pbrt-v4's LightBounds::Importance (exposed for tests). */
double light_bounds_importance(const light_bounds *b, vec3 p, vec3 n);

#endif
