/* `haze diff A.exr B.exr`: compares two EXR images channel by channel.
 *
 * For the channels both images have (except the statistics layers
 * Variance.* and SampleCount.*, which only --channels selects), or those
 * named with --channels, it
 * prints, per channel and over all chosen channels' values together: MSE,
 * RMSE, relative MSE (pbrt-v4 imgtool's: mean of (a-b)^2 / (b+0.01)^2 with b
 * from the second image), mean and max absolute error (with the max's pixel,
 * in data-window coordinates, and channel), PSNR with peak 1 (inf when the
 * MSE is 0), the means of A and B and their relative difference, and each
 * image's count of NaN/Inf values. A value pair with a non-finite value on
 * either side is counted and left out of every metric.
 *
 * --metric NAME --threshold X makes the command a check: exit 1 when the
 * overall metric exceeds X (for psnr: falls below X). --heatmap OUT writes the
 * per-pixel mean over the chosen channels of |a-b|: a one-channel ("Y") float
 * EXR, or a grey PNG scaled so the largest error is white when OUT ends in
 * ".png" (pixels without any finite pair are NaN in the EXR, red in the PNG).
 *
 * --ztest [--alpha A] [--accept F] is the statistical check for noisy renders
 * (docs/regression.md): for each of R, G, B among the compared channels that B
 * has "Variance.<c>" for, a two-sided z-test of A against B's mean, with var =
 * var_A + var_B; var_B is B's Variance.<c>, var_A is B's Variance.<c> *
 * SampleCount.Y(B) / SampleCount.Y(A) when both images have a sample count,
 * else A's own Variance.<c> (else an error). z = (a - b) / sqrt(var + (1e-5 *
 * max(|a|, |b|))^2), 0 when a == b; a non-finite a (or an A pixel without
 * samples where B has some) fails. Tests at three scales: every pixel, every
 * 8x8 block of the data window (partial edge blocks included; z = sum(a - b) /
 * sqrt(sum var)), and the whole image, per channel. Sidak correction over all N
 * tests: a test fails when erfc(|z|/sqrt 2) < 1 - (1 - alpha)^(1/N). Passes when
 * at most floor((1 - accept) * tests) pixel tests and as many block tests fail,
 * and no image test does. Defaults alpha 0.01, accept 0.999. Combined with
 * --metric both checks must pass. With --ztest, --heatmap writes the per-pixel
 * |z| (largest over the channels; +inf where A is not finite). */
#ifndef HAZE_CLI_DIFF_H
#define HAZE_CLI_DIFF_H

#include <stdbool.h>
#include <stdio.h>

#include "core/error.h"

typedef enum {
    DIFF_METRIC_NONE,
    DIFF_METRIC_MSE,
    DIFF_METRIC_RMSE,
    DIFF_METRIC_RELMSE,
    DIFF_METRIC_MAE,
    DIFF_METRIC_MAX,
    DIFF_METRIC_PSNR
} diff_metric;

typedef struct {
    const char *a, *b;        /* the two EXR files; b is the reference */
    const char *channels;     /* comma-separated list, or NULL for the shared ones */
    diff_metric metric;       /* DIFF_METRIC_NONE: report only */
    double threshold;
    const char *heatmap;      /* output path or NULL */
    bool ztest;               /* --ztest */
    double alpha;             /* family-wise significance level, in (0, 1); default 0.01 */
    double accept;            /* fraction of pixel / block tests that must pass, in [0, 1]; 0.999 */
} diff_options;

/* Parses the arguments after "diff". Sets *help when --help was given. */
hz_status diff_parse_args(int argc, char **argv, diff_options *opt, bool *help, hz_error *err);

/* Compares, prints the report to `out` and writes the heatmap. *passed is
 * false only when a --metric check or the --ztest failed. Fails (one line in
 * `err`) on unreadable files, files that are not regular files (a FIFO is
 * refused, not waited on), mismatched windows, missing or no shared
 * channels, missing or invalid statistics for --ztest, and heatmap write
 * errors. */
hz_status diff_run(const diff_options *opt, FILE *out, bool *passed, hz_error *err);

/* The whole subcommand: argv[0] is "diff". Returns the exit status: 0 equal
 * enough / report only, 1 a --metric check or the --ztest failed, 2 usage or
 * file errors. */
int diff_command(int argc, char **argv, FILE *out, FILE *errs);

#endif
