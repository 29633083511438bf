/* `haze info FILE`: a human-readable description of a file haze reads or
 * writes, chosen by the file's content (magic number), not its extension:
 *   OpenVDB (.vdb) / NanoVDB (.nvdb): every grid with its type, active voxels,
 *     index and world bounds, voxel size and value range;
 *   OpenEXR (.exr): size, windows, channels with pixel type, header attributes,
 *     per-channel min/max/mean and NaN/Inf counts;
 *   RGL measured BRDF (.bsdf, a "tensor_file"): its fields with type and
 *     shape, its description, and what the BRDF holds or why haze cannot
 *     render it;
 *   pbrt-v4 scene (text named *.pbrt, or whose first word after comments is
 *     shaped like a directive): camera, film resolution, sampler and entity
 *     counts.
 * Anything else is "not a .vdb, .nvdb, .exr, .bsdf or .pbrt file". */
#ifndef HAZE_CLI_INFO_H
#define HAZE_CLI_INFO_H

#include <stdio.h>

#include "core/error.h"

/* Prints the description of `path` to `out`. On failure (missing, unreadable,
 * unrecognised or malformed file) prints nothing and fills `err` with one line
 * that names the file and the problem. */
hz_status info_describe(const char *path, FILE *out, hz_error *err);

#endif
