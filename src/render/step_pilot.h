/* --target-error's marching step (issue 20). With `raymarch` or `jittered`
 * estimators the image converges to the marched integral, not the true one:
 * their bias shrinks with the step, while the passes of --target-error only
 * measure noise. Before the passes, a pilot picks the step: the scene's
 * estimators run at the pixel centres of a sparse grid of pixels at step h
 * and h/2, with the same samples for every step (one for `raymarch`, which
 * is deterministic there; STEP_PILOT_SAMPLES for `jittered`, whose noise is
 * then subtracted: per pixel the squared mean difference less its variance);
 * twice their relMSE (haze diff's) estimates the bias of h
 * (midpoint marching: halving the step at least halves the error), on as
 * many of the grid's pixels as tell it from the goal (STEP_PILOT_Z). The
 * steps are the scene's times powers of two; from the coarsest within
 * STEP_PILOT_MAX_STEP the step halves until its bias is at most STEP_PILOT_SHARE
 * of the target below one that was not (cheapest first, and nothing finer
 * than half the step chosen is rendered); the shadow step keeps its ratio
 * to it. The
 * shadow cache's spacing (integrator/shadow_cache.h) does too; where the
 * scene has none but one applies (a static scene, a distant light, a grid
 * medium), the pilot uses one at the step's spacing, its bias measured with
 * the step's. */
#ifndef HAZE_RENDER_STEP_PILOT_H
#define HAZE_RENDER_STEP_PILOT_H

#include <signal.h>
#include <stdbool.h>

#include "core/error.h"
#include "render/render_scene.h"

/* The share of --target-error the step's estimated bias may take; the
 * passes' noise gets what the chosen step leaves (progressive_goal.bias).
 * Half: on the bench cloud and smoke it gave the fastest renders in four of
 * five cases against a quarter (bench/results/notes.md). */
#define STEP_PILOT_SHARE 0.5
/* About this many pixels in the pilot grid; steps between these (voxels). */
#define STEP_PILOT_PIXELS 2500
/* ... but at most 1/this of the image's pixels, and at least
 * STEP_PILOT_MIN_PIXELS (all of a smaller image's). */
#define STEP_PILOT_SHARE_OF_IMAGE 64
#define STEP_PILOT_MIN_PIXELS 256
/* A comparison of two steps starts on this many of the grid's pixels (an
 * even spread of them) and doubles them where its verdict could be wrong at
 * a cost (step_pilot.c, pilot_bias): while its bias estimate lies within
 * STEP_PILOT_Z standard errors (over pixels) of the goal, so that a clear
 * case costs a fraction of the grid and a close one up to all of it ... */
#define STEP_PILOT_START_PIXELS 64
#define STEP_PILOT_Z 3.0
/* ... and, for a pass that would choose its step, while fewer than this
 * many of its pixels tell the two steps apart
 * (pixels whose rays miss the media read the same at every step: on the
 * bench cloud, which covers a sixth of the image, 64 pixels held about ten
 * that do, and a clear verdict on those chose step 32 where step 8 was
 * already too coarse). */
#define STEP_PILOT_MIN_DIFFER 32
/* A failure more than this many times the goal stands on the pixels it has
 * (pilot_bias). */
#define STEP_PILOT_NEAR 4.0
/* Comparisons grow only while the pilot's cost stays within this share of
 * the render at the step the comparison would choose: at least its first
 * pass (two samples of every pixel; on a small image a pilot stays a small
 * part of a render that may end after that pass), and at least the samples
 * that bring the noise of the pilot's pixel centres down to E. Costs are
 * samples plus density lookups, counted in the pilot's renders (a count,
 * the same on any number of threads): the coarse renders at the top of the
 * walk take little of it.
 * Each comparison's first STEP_PILOT_START_PIXELS are taken whatever the
 * budget. */
#define STEP_PILOT_BUDGET 0.1
/* Samples per pilot pixel of a random (jittered) estimator. */
#define STEP_PILOT_SAMPLES 8
#define STEP_PILOT_MIN_STEP (1.0 / 64.0)
/* The coarsest step, voxels (under "auto": times its least scale). */
#define STEP_PILOT_MAX_STEP 64.0

typedef struct {
    bool applies;   /* a marching estimator in grid media: a step was chosen */
    double step, shadow_step; /* voxels, set on the scene */
    double shadow_cache;      /* voxels, set on the scene (0: none) */
    double bias;    /* the estimated relMSE of the chosen step */
    int pixels;     /* of the pilot grid, the most a comparison took */
    int renders;    /* pilot renders made */
    double finest;  /* voxels: the finest step they were at */
} step_choice;

/* Chooses the step for `target_error` (> 0) and sets it on `rs`, rendering
 * the pilot on `threads` threads (<= 0: every core); nothing to do (applies
 * false) when render_scene_marching is false. The same choice for any thread
 * count and on every rank. When `cancel` (NULL: never) becomes non-zero (a
 * signal) the pilot stops within a sample, leaves the scene's own
 * steps and applies is false. */
void step_pilot_choose(render_scene *rs, double target_error, int threads,
                       const volatile sig_atomic_t *cancel, step_choice *out);

#endif
