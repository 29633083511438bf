/* What a progressive render (progressive.h) aims at, and the sizes of its
 * passes towards it: shared by the passes of one process (progressive.c),
 * the error estimate that sizes them (progressive_error.h) and the MPI
 * driver, so that none of them includes another's header for these. */
#ifndef HAZE_RENDER_PROGRESSIVE_GOAL_H
#define HAZE_RENDER_PROGRESSIVE_GOAL_H

#include <stdbool.h>

/* The end of the pass that starts at sample `begin` (< spp): 1 for the first,
 * then twice `begin`, at most spp. */
int progressive_pass_end(int begin, int spp);

/* Whether a pass of `work` (pixel samples), started at `now`, is expected to
 * end by `deadline`, given that the last pass took `last_seconds` for
 * `last_work` (time proportional to work). */
bool progressive_pass_fits(double now, double deadline, double last_seconds, double last_work,
                           double work);

/* When passes stop before the sampler's count. */
typedef struct {
    double deadline;     /* hz_clock_seconds() time; 0: none (--time-limit) */
    /* The image's relative error to reach, 0: none (--target-error): relMSE
     * as `haze diff` reports it against the converged image, estimated from
     * each pixel's variance (progressive_error). Needs a film that keeps
     * variance and sample counts. */
    double target_error;
    /* The estimated relMSE of the marching bias (step_pilot_choose), spent
     * before the noise: the image stops when its noise estimate reaches
     * progressive_noise_target. 0: none. */
    double bias;
} progressive_goal;

/* Samples before the first estimate of the image's error (a variance needs
 * two). */
enum { PROGRESSIVE_MIN_SPP = 2 };

/* The end of the first pass of a render towards `goal`: progressive_pass_end's
 * 1, or with a target error the PROGRESSIVE_MIN_SPP samples its first
 * estimate needs (at most spp). The first pass is never undone, so it needs
 * no copy of the film. */
int progressive_first_end(const progressive_goal *goal, int spp);

/* The noise's share of a target error: target_error less the bias, at least
 * half of target_error. */
double progressive_noise_target(const progressive_goal *goal);

#endif
