/* The render loop: tiles of the film's pixel bounds handed to a pool of
 * threads, a progress bar, and the figures for the final summary. Every pixel
 * sample draws from its own random stream, so the image does not depend on the
 * thread count. */
#ifndef HAZE_RENDER_RENDERER_H
#define HAZE_RENDER_RENDERER_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "core/error.h"
#include "render/render_scene.h"

typedef struct {
    int threads;         /* <= 0: all cores */
    FILE *progress;      /* progress bar destination, or NULL for none */
} renderer_options;

typedef struct {
    int threads;
    int spp;
    long pixels;
    double wall_seconds;
    uint64_t camera_rays, shadow_rays;
    uint64_t density_lookups; /* grid media */
} render_stats;

hz_status renderer_run(render_scene *rs, const renderer_options *opt, render_stats *stats,
                       hz_error *err);

/* The camera sample of pixel (px, py) drawn from `st` in pbrt-v4's order
 * (GetCameraSample): film position through the filter, time, lens. */
camera_sample renderer_camera_sample(const filter *flt, sampler_state *st, int px, int py);

/* Number of online processors (at least 1). */
int renderer_default_threads(void);

#endif
