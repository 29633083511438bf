#define _POSIX_C_SOURCE 200809L
#include "render/progressive.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/clock.h"
#include "render/progress.h"
#include "render/progressive_error.h"

void render_stats_add_work(render_stats *total, const render_stats *pass)
{
    total->camera_rays += pass->camera_rays;
    total->shadow_rays += pass->shadow_rays;
    total->density_lookups += pass->density_lookups;
    total->majorant_steps += pass->majorant_steps;
    total->lost_paths += pass->lost_paths;
    total->time_busy_s += pass->time_busy_s;
    total->time_media_s += pass->time_media_s;
    total->time_film_s += pass->time_film_s;
}

/* With a target error, the error estimate and the mask of the pixels that
 * take the next pass (all, at first); without one *active stays NULL. */
static hz_status target_start(const progressive_goal *goal, film *f, size_t npix,
                              progressive_error *pe, unsigned char **active, hz_error *err)
{
    *active = NULL;
    if (!(goal->target_error > 0))
        return HZ_OK;
    if (progressive_error_init(pe, f, err) != HZ_OK)
        return HZ_ERROR;
    if (!(*active = malloc(npix ? npix : 1))) {
        progressive_error_free(pe);
        return hz_fail(err, "out of memory for the pixel mask (--target-error)");
    }
    memset(*active, 1, npix);
    return HZ_OK;
}

/* target_start, and the copy of the film a pass after the first is undone
 * from: from the second pass on (the first is never undone), and the halves
 * estimate starts at the second. NULL (nothing left to free) on failure. */
static film_snapshot *passes_start(const progressive_goal *goal, film *f, size_t npix,
                                   progressive_error *pe, unsigned char **active, hz_error *err)
{
    if (target_start(goal, f, npix, pe, active, err) != HZ_OK)
        return NULL;
    film_snapshot *snap = film_snapshot_alloc(f, err);
    if (!snap) {
        free(*active);
        progressive_error_free(pe);
    }
    return snap;
}

/* Whether a pass after the first starts at `start`: not cancelled, and
 * expected to end by the deadline. */
static bool next_pass_starts(const renderer_options *opt, double start, double deadline,
                             double last_seconds, double last_samples, double next_samples)
{
    return !(opt->cancel && *opt->cancel) &&
           progressive_pass_fits(start, deadline, last_seconds, last_samples, next_samples);
}

/* The work of a pass, and what every pass reports alike. */
static void add_pass_work(render_stats *total, const render_stats *pass)
{
    render_stats_add_work(total, pass);
    total->threads = pass->threads;
    total->tile_count = pass->tile_count;
    total->pixels_total = pass->pixels_total;
}

/* The first pass cut short: the tiles it rendered, as renderer_run reports
 * them. */
static void keep_interrupted_first(render_stats *total, const render_stats *pass, int end)
{
    total->tiles_done = pass->tiles_done;
    memcpy(total->tile_ranges, pass->tile_ranges, sizeof total->tile_ranges);
    total->pixels = pass->pixels;
    total->interrupted = true;
    total->spp = end;
    total->samples = pass->samples;
    total->passes = 0;
}

/* A completed pass, the `passes`th, that took the image to `done` samples. */
static void count_pass(render_stats *total, const render_stats *pass, int done, int passes)
{
    total->tiles_done = pass->tiles_done;
    total->pixels = pass->pixels;
    total->spp = done;
    total->samples += pass->samples;
    total->passes = passes;
}

static void print_pass(FILE *out, double t0, int passes, int done, int spp, bool target,
                       double estimate, long left)
{
    char el[32], px[96] = "";
    progress_format_duration(hz_clock_seconds() - t0, el, sizeof el);
    if (target)
        snprintf(px, sizeof px, ", estimated relMSE %.3g, %ld pixels go on", estimate, left);
    fprintf(out, "pass %d: %d of %d spp%s, %s elapsed\n", passes, done, spp, px, el);
}

hz_status renderer_run_progressive(render_scene *rs, const renderer_options *opt,
                                   const progressive_goal *goal, render_stats *stats,
                                   hz_error *err)
{
    film *f = render_scene_film(rs);
    const film_params *fp = film_get_params(f);
    int spp = render_scene_sampler(rs)->spp;
    double deadline = goal->deadline > 0 ? goal->deadline : INFINITY;
    double ratio = camera_imaging_ratio(render_scene_camera(rs), fp);
    size_t npix = (size_t)(fp->bounds.x1 - fp->bounds.x0) * (fp->bounds.y1 - fp->bounds.y0);
    unsigned char *active;
    progressive_error pe = {0};
    film_snapshot *snap = passes_start(goal, f, npix, &pe, &active, err);
    if (!snap)
        return HZ_ERROR;
    double t0 = hz_clock_seconds();
    render_stats total;
    memset(&total, 0, sizeof total);
    renderer_options o = *opt;
    o.progress = NULL;
    o.active = active;
    double last_seconds = 0.0, last_samples = 0.0;
    int done = 0, passes = 0;
    long left = (long)npix;
    hz_status st = HZ_OK;
    if (active)
        total.estimate = -1.0; /* until the first measure */
    while (done < spp && left > 0) {
        int end = active ? progressive_error_next_end(&pe, done, spp, goal)
                         : progressive_pass_end(done, spp);
        double start = hz_clock_seconds();
        /* The next pass's work, in samples, against the last one's. */
        double next_samples = (double)(end - done) * (double)left;
        if (passes > 0 && !next_pass_starts(opt, start, deadline, last_seconds, last_samples,
                                            next_samples))
            break;
        if (passes > 0)
            film_snapshot_save_pixels(snap, f, active); /* a pass renders only these */
        o.sample_begin = done;
        o.sample_end = end;
        o.deadline = passes > 0 ? goal->deadline : 0.0; /* the first pass always ends */
        render_stats pass;
        st = renderer_run(rs, &o, &pass, err);
        total.abandoned = pass.abandoned;
        if (st != HZ_OK)
            break;
        add_pass_work(&total, &pass);
        if (pass.interrupted) { /* abandoned workers stay off the film: undone as usual */
            if (passes == 0) /* the rendered tiles of one pass, as renderer_run */
                keep_interrupted_first(&total, &pass, end);
            else
                film_snapshot_restore_pixels(snap, f, active);
            break;
        }
        last_seconds = hz_clock_seconds() - start;
        last_samples = next_samples;
        done = end;
        ++passes;
        count_pass(&total, &pass, done, passes);
        double estimate = 0.0;
        if (active && done >= PROGRESSIVE_MIN_SPP) {
            progressive_error_measure(&pe, f, snap, active, o.sample_begin, done, ratio, opt->threads);
            left = progressive_error_select(&pe, f, goal, active, &estimate);
            total.estimate = estimate;
        }
        if (opt->progress)
            print_pass(opt->progress, t0, passes, done, spp, active != NULL, estimate, left);
    }
    film_snapshot_destroy(snap);
    if (total.abandoned == 0) /* else abandoned workers may still read it */
        free(active);
    progressive_error_free(&pe);
    total.wall_seconds = hz_clock_seconds() - t0;
    if (stats)
        *stats = total;
    return st;
}
