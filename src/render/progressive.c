#define _POSIX_C_SOURCE 200809L
#include "render/progressive.h"

#include <stdlib.h>
#include <string.h>

#include "core/clock.h"
#include "render/progress.h"

int progressive_pass_end(int begin, int spp)
{
    if (begin <= 0)
        return spp < 1 ? spp : 1;
    return begin <= spp / 2 ? 2 * begin : spp;
}

bool progressive_pass_fits(double now, double deadline, double last_seconds, int last_samples,
                           int samples)
{
    if (last_samples <= 0)
        return now < deadline;
    return now + last_seconds * ((double)samples / last_samples) <= deadline;
}

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

/* A copy of the film's accumulators, to undo a pass cut short. */
typedef struct {
    double *doubles[3];
    uint32_t *counts;
    long nonfinite;
} film_snapshot;

static void snapshot_free(film_snapshot *s)
{
    for (int i = 0; i < 3; ++i)
        free(s->doubles[i]);
    free(s->counts);
    memset(s, 0, sizeof *s);
}

static hz_status snapshot_alloc(film *f, film_snapshot *s, hz_error *err)
{
    memset(s, 0, sizeof *s);
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    bool ok = true;
    for (int i = 0; i < 3; ++i)
        if (acc.doubles[i] && !(s->doubles[i] = malloc(acc.double_count[i] * sizeof(double))))
            ok = false;
    if (acc.counts && !(s->counts = malloc(acc.count_count * sizeof(uint32_t))))
        ok = false;
    if (!ok) {
        snapshot_free(s);
        return hz_fail(err, "out of memory for a copy of the film (--time-limit)");
    }
    return HZ_OK;
}

/* save: film -> snapshot; otherwise snapshot -> film. */
static void snapshot_copy(film *f, film_snapshot *s, bool save)
{
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    for (int i = 0; i < 3; ++i)
        if (acc.doubles[i]) {
            size_t n = acc.double_count[i] * sizeof(double);
            if (save)
                memcpy(s->doubles[i], acc.doubles[i], n);
            else
                memcpy(acc.doubles[i], s->doubles[i], n);
        }
    if (acc.counts) {
        size_t n = acc.count_count * sizeof(uint32_t);
        if (save)
            memcpy(s->counts, acc.counts, n);
        else
            memcpy(acc.counts, s->counts, n);
    }
    if (save)
        s->nonfinite = film_nonfinite_count(f);
    else
        film_add_nonfinite(f, s->nonfinite - film_nonfinite_count(f));
}

hz_status renderer_run_progressive(render_scene *rs, const renderer_options *opt, double deadline,
                                   render_stats *stats, hz_error *err)
{
    film *f = render_scene_film(rs);
    int spp = render_scene_sampler(rs)->spp;
    film_snapshot snap;
    if (snapshot_alloc(f, &snap, err) != HZ_OK)
        return HZ_ERROR;
    double t0 = hz_clock_seconds();
    render_stats total;
    memset(&total, 0, sizeof total);
    renderer_options o = *opt;
    o.progress = NULL;
    double last_seconds = 0.0;
    int done = 0, passes = 0, last_samples = 0;
    hz_status st = HZ_OK;
    while (done < spp) {
        int end = progressive_pass_end(done, spp);
        double start = hz_clock_seconds();
        if (passes > 0 && ((opt->cancel && *opt->cancel) ||
                           !progressive_pass_fits(start, deadline, last_seconds, last_samples,
                                                  end - done)))
            break;
        if (passes > 0)
            snapshot_copy(f, &snap, true);
        o.sample_begin = done;
        o.sample_end = end;
        o.deadline = passes > 0 ? deadline : 0.0; /* the first pass always ends */
        render_stats pass;
        st = renderer_run(rs, &o, &pass, err);
        if (st != HZ_OK)
            break;
        render_stats_add_work(&total, &pass);
        total.threads = pass.threads;
        total.tile_count = pass.tile_count;
        total.pixels_total = pass.pixels_total;
        if (pass.interrupted) {
            if (passes == 0) { /* the rendered tiles of one pass, as renderer_run */
                total.tiles_done = pass.tiles_done;
                total.pixels = pass.pixels;
                total.interrupted = true;
                total.spp = end;
                total.passes = 0;
            } else {
                snapshot_copy(f, &snap, false);
            }
            break;
        }
        last_seconds = hz_clock_seconds() - start;
        last_samples = end - done;
        done = end;
        ++passes;
        total.tiles_done = pass.tiles_done;
        total.pixels = pass.pixels;
        total.spp = done;
        total.passes = passes;
        if (opt->progress) {
            char el[32];
            progress_format_duration(hz_clock_seconds() - t0, el, sizeof el);
            fprintf(opt->progress, "pass %d: %d of %d spp, %s elapsed\n", passes, done, spp, el);
        }
    }
    snapshot_free(&snap);
    total.wall_seconds = hz_clock_seconds() - t0;
    if (stats)
        *stats = total;
    return st;
}
