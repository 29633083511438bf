/* The render loop: tiles of the film's pixel bounds handed to a pool of
 * threads, a progress bar, and the figures for the final summary. Every pixel
 * sample draws from its own random stream, so the image does not depend on the
 * thread count. */
#ifndef HAZE_RENDER_RENDERER_H
#define HAZE_RENDER_RENDERER_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "core/error.h"
#include "render/render_scene.h"

/* Tiles are RENDERER_TILE_SIZE square (clipped at the bounds' right and
 * bottom edges), numbered row-major over the film's pixel bounds. */
enum { RENDERER_TILE_SIZE = 16 };

/* Seconds the tiles under way get to finish after a cancel before their
 * workers are abandoned (renderer_options.cancel). */
#define RENDERER_CANCEL_GRACE_S 1.0

/* Room for render_stats.tile_ranges, its NUL included. */
enum { RENDERER_TILE_RANGES = 1024 };

typedef struct {
    int threads;         /* <= 0: all cores */
    FILE *progress;      /* progress bar destination, or NULL for none */
    /* When not NULL and *cancel becomes non-zero (a signal handler sets it),
     * no further tile is started, and the tiles under way get
     * RENDERER_CANCEL_GRACE_S to finish. The workers still running then are
     * abandoned: they add nothing more to the film, renderer_run returns
     * without waiting for the sample each is computing, and
     * stats.abandoned counts them. Such a worker goes on reading the scene
     * and what these options point at (active, tile_ctx) until it ends, so
     * the caller must keep them until the process exits (exit with _exit:
     * library destructors would pull the scene from under it). The tile an
     * abandoned worker was in is not done; the done tiles (all of them the
     * first claimed unless some were abandoned) are listed in
     * stats.tile_ranges, each with all its samples, and when sample_begin is
     * 0 the film's other pixels are cleared, so it holds those tiles only. */
    const volatile sig_atomic_t *cancel;
    /* pbrt-v4's --disable-pixel-jitter: every camera ray through its pixel's
     * centre (filter offset 0, weight 1); the sample is still drawn, so the
     * other dimensions (time, lens, ...) are unchanged. */
    bool disable_pixel_jitter;
    /* Time media walks and film updates (render_stats.time_*); costs two clock
     * reads per media segment and per sample. */
    bool timing;
    /* Where tiles come from. NULL: this process renders every tile, claimed
     * in row-major order from a shared counter. Otherwise the worker threads
     * call next_tile(tile_ctx), concurrently, for the index of their next
     * tile, -1 when none is left (src/mpi: one image across processes), and
     * the progress bar shows tiles_shown(tile_ctx) when that is not NULL. */
    int (*next_tile)(void *tile_ctx);
    int (*tiles_shown)(void *tile_ctx);
    void *tile_ctx;
    /* The pixel samples to take: [sample_begin, sample_end) of every pixel
     * (sample_end 0: the sampler's count), so passes over the image add the
     * same samples in the same order as one render (src/render/progressive.h). */
    int sample_begin, sample_end;
    /* hz_clock_seconds() time after which no further tile is started (0:
     * none); tiles under way are finished however long they take (no worker
     * is abandoned) and stats.interrupted is set. */
    double deadline;
    /* Pixels to render (0: skip), one byte per pixel of the film's bounds,
     * row-major; NULL: all (src/render/progressive.h, --target-error). */
    const unsigned char *active;
} renderer_options;

typedef struct {
    int threads;
    int spp;              /* samples per pixel taken (of every rendered pixel) */
    int passes;           /* progressive passes completed (1 for one render) */
    long pixels;          /* rendered pixels (all of the bounds unless interrupted) */
    double samples;       /* pixel samples taken in all (spp * pixels unless adaptive) */
    long pixels_total;    /* pixels of the film's bounds */
    int tiles_done, tile_count;
    bool interrupted;     /* stopped by *cancel before every tile was rendered */
    /* Interrupted: the done tiles as ranges of tile indices, "0-41,43-45,47"
     * (each range first-last; a single tile alone), in increasing order.
     * Tiles that would not fit in it are not counted done. */
    char tile_ranges[RENDERER_TILE_RANGES];
    int abandoned;        /* render threads left running after a cancel */
    double wall_seconds;
    uint64_t camera_rays, shadow_rays;
    uint64_t density_lookups; /* grid media */
    uint64_t majorant_steps;  /* majorant-grid cells entered */
    uint64_t lost_paths;      /* camera or shadow rays dropped after too many interfaces */
    /* Thread seconds: busy (all work of the render threads), and within it
     * media walks and film updates (only with renderer_options.timing). */
    double time_busy_s, time_media_s, time_film_s;
    /* --target-error: the image's estimated relMSE (its noise, the step's
     * bias not included) after the last pass; < 0 when none was measured
     * (fewer than two samples a pixel); 0 without a target. */
    double estimate;
} render_stats;

/* Renders every tile of the film (or, once *opt->cancel is set, the tiles
 * already claimed, abandoning the slow ones). Worker threads block SIGINT,
 * SIGTERM and SIGHUP, so a handler runs on the calling thread. */
hz_status renderer_run(render_scene *rs, const renderer_options *opt, render_stats *stats,
                       hz_error *err);

/* The camera sample of pixel (px, py) drawn from `st` in pbrt-v4's order
 * (GetCameraSample): film position through the filter, time, lens. */
camera_sample renderer_camera_sample(const filter *flt, sampler_state *st, int px, int py);
/* What a camera sample needs to compute: without jitter the film position is
 * the pixel centre (renderer_options.disable_pixel_jitter); without motion the
 * time, and without a lens the lens point, are consumed but not computed
 * (their values would change nothing), so every later dimension, and the
 * image, stay the same. */
typedef struct {
    bool jitter, time, lens;
} camera_sample_needs;

camera_sample renderer_camera_sample_needs(const filter *flt, sampler_state *st, int px, int py,
                                           camera_sample_needs needs);

#endif
