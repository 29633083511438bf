/* Progressive rendering under a time limit (`haze render --time-limit`):
 * passes over the whole image, each adding the next samples of every pixel:
 * [0,1), [1,2), [2,4), [4,8), ... up to the sampler's count. Each pixel gets
 * its samples in the same order as in one render, so the image after passes
 * totalling S samples is byte-identical to a render with --spp S. Only
 * complete passes count: a pass the deadline (or a signal) cuts short is
 * undone from a copy of the film's accumulators taken at its start. */
#ifndef HAZE_RENDER_PROGRESSIVE_H
#define HAZE_RENDER_PROGRESSIVE_H

#include "core/error.h"
#include "render/progressive_goal.h"
#include "render/renderer.h"

/* renderer_run in passes until the sampler's count or the goal. The first
 * pass always runs to its end unless *opt->cancel is set; a later pass starts
 * only when progressive_pass_fits the deadline, and one cut short by the
 * deadline or *opt->cancel is undone. With a target error each pass renders
 * only the pixels that need more samples (progressive_error_select). opt->deadline,
 * sample_begin, sample_end and active are the driver's (ignored). stats: as
 * renderer_run's for the image left on the film (spp: the most samples a
 * pixel took, samples: all of them, passes: the passes), with the work of
 * every pass counted in the rays, lookups and times; interrupted only when
 * the first pass was; abandoned as renderer_run's for the last pass (the
 * pixel mask is then not freed: abandoned workers may read it). Progress:
 * one line per completed pass to opt->progress. */
hz_status renderer_run_progressive(render_scene *rs, const renderer_options *opt,
                                   const progressive_goal *goal, render_stats *stats,
                                   hz_error *err);

/* Adds the counters and thread times of `pass` to `total` (not its samples). */
void render_stats_add_work(render_stats *total, const render_stats *pass);

#endif
