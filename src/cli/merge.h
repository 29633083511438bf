/* `haze merge PART.exr... -o FULL.exr`: assembles region renders (haze render
 * --pixelbounds / --cropwindow) into the full image.
 *
 * Every part is read whole (all channels, half or float as stored). The merge
 * is refused, naming the offending file(s) and region(s), unless: every part
 * is a regular file (a FIFO is refused, not waited on); no part is a partial
 * (interrupted) render (header attribute haze:partial); all parts
 * have the same display window, the same channel list with the same pixel
 * types, and the same header string attributes; every data window lies inside
 * the display window; no two data windows overlap; and together they cover
 * the display window (no gap). The output has data window = display window,
 * the parts' channels and attributes, and is written by the same EXR writer
 * as the film (exr_write: scanline, ZIP, increasing Y), atomically (temporary
 * file + rename): a refused or failed merge writes nothing. The output is
 * checked first as haze render's (cli/outputs.h): it must end in .exr and may
 * not be an existing non-regular file or one of the parts (device and inode).
 * Half values survive the read/write round trip exactly, so the merged file
 * is byte-identical to a full render of the same scene, seed and spp
 * (docs/regions.md). */
#ifndef HAZE_CLI_MERGE_H
#define HAZE_CLI_MERGE_H

#include <stdbool.h>
#include <stdio.h>

#include "core/error.h"

typedef struct {
    const char **parts; /* part_count EXR files (points into argv) */
    int part_count;
    const char *output; /* -o FULL.exr */
} merge_options;

/* Parses the arguments after "merge" (allocates opt->parts: free it with
 * merge_options_free). Sets *help when --help was given. */
hz_status merge_parse_args(int argc, char **argv, merge_options *opt, bool *help, hz_error *err);
void merge_options_free(merge_options *opt);

/* Checks the parts and writes the merged image; one line in `err` on failure. */
hz_status merge_run(const merge_options *opt, hz_error *err);

/* The whole subcommand: argv[0] is "merge". Returns the exit status: 0 merged,
 * 1 a part is unreadable, the parts do not tile the image, or the output
 * cannot be written, 2 usage errors. */
int merge_command(int argc, char **argv, FILE *out, FILE *errs);

#endif
