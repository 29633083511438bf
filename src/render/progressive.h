/* Progressive rendering under a time limit (`haze render --time-limit`):
 * passes over the whole image, each adding the next samples of every pixel:
 * [0,1), [1,2), [2,4), [4,8), ... up to the sampler's count. Each pixel gets
 * its samples in the same order as in one render, so the image after passes
 * totalling S samples is byte-identical to a render with --spp S. Only
 * complete passes count: a pass the deadline (or a signal) cuts short is
 * undone from a copy of the film's accumulators taken at its start. */
#ifndef HAZE_RENDER_PROGRESSIVE_H
#define HAZE_RENDER_PROGRESSIVE_H

#include <stdbool.h>

#include "core/error.h"
#include "render/renderer.h"

/* The end of the pass that starts at sample `begin` (< spp): 1 for the first,
 * then twice `begin`, at most spp. */
int progressive_pass_end(int begin, int spp);

/* Whether a pass of `samples` samples per pixel, started at `now`, is
 * expected to end by `deadline`, given that the last pass took
 * `last_seconds` for `last_samples` (time proportional to samples). */
bool progressive_pass_fits(double now, double deadline, double last_seconds, int last_samples,
                           int samples);

/* renderer_run in passes until the sampler's count or `deadline`
 * (hz_clock_seconds()). The first pass always runs to its end unless
 * *opt->cancel is set; a later pass starts only when progressive_pass_fits,
 * and one cut short by the deadline or *opt->cancel is undone. opt->deadline,
 * sample_begin and sample_end are the driver's (ignored). stats: as
 * renderer_run's for the image left on the film (spp: its samples per pixel,
 * passes: its passes), with the work of every pass counted in the rays,
 * lookups and times; interrupted only when the first pass was. Progress: one
 * line per completed pass to opt->progress. */
hz_status renderer_run_progressive(render_scene *rs, const renderer_options *opt, double deadline,
                                   render_stats *stats, hz_error *err);

/* Adds the counters and thread times of `pass` to `total`. */
void render_stats_add_work(render_stats *total, const render_stats *pass);

#endif
