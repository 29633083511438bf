/* `haze diff A.exr B.exr`: compares two EXR images channel by channel.
 *
 * For the channels both images have (or those named with --channels) it
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
 * ".png" (pixels without any finite pair are NaN in the EXR, red in the PNG). */
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
} diff_options;

/* Parses the arguments after "diff". Sets *help when --help was given. */
hz_status diff_parse_args(int argc, char **argv, diff_options *opt, bool *help, hz_error *err);

/* Compares, prints the report to `out` and writes the heatmap. *passed is
 * false only when a --metric check failed. Fails (one line in `err`) on
 * unreadable files, mismatched windows, missing or no shared channels, and
 * heatmap write errors. */
hz_status diff_run(const diff_options *opt, FILE *out, bool *passed, hz_error *err);

/* The whole subcommand: argv[0] is "diff". Returns the exit status: 0 equal
 * enough / report only, 1 a --metric check failed, 2 usage or file errors. */
int diff_command(int argc, char **argv, FILE *out, FILE *errs);

#endif
