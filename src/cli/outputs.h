/* Where `haze render` and `haze merge` may write their images, checked
 * before any work. */
#ifndef HAZE_CLI_OUTPUTS_H
#define HAZE_CLI_OUTPUTS_H

#include <limits.h>
#include <stdbool.h>

#include "core/error.h"
#include "render/render_scene.h"
#include "scene/scene_desc.h"

typedef struct {
    char image[PATH_MAX]; /* the file the image replaces (a symlink's target) */
    bool image_png;       /* the image is a PNG (the Film's filename), not an EXR */
    char png[PATH_MAX];   /* the same for the --preview PNG; "" without one */
    char render_id[17];   /* outputs_render_id in hex: the EXR's "haze:render" */
} render_outputs;

/* What identifies a render, written to every EXR as "haze:render" so that
 * `haze merge` refuses parts of different renders: the bytes of every input
 * file (scene_inputs_hash), the haze version, the sampler (kind, strata,
 * jitter, seed; `spp` the samples per pixel taken) and pixel jitter. Not the region, the thread count or the
 * output name: the parts of one render share it. */
uint64_t outputs_render_id(uint64_t inputs_hash, const render_scene *rs, int spp,
                           bool disable_pixel_jitter);

/* Resolves and checks the image `image` and the optional preview PNG `png`
 * (NULL: none) of a render of `sd`. The image is an EXR, or a PNG when
 * `film_named` (the Film's filename, not -o's) and it ends in ".png". Refused,
 * each with one line naming the file: an image name not ending in ".exr" (or
 * ".png" as above; a preview not in ".png"); an existing file
 * that is not a regular file (device, FIFO, socket, directory: never
 * replaced); a dangling symlink; a file the render reads (the scene, an
 * include, a mesh, a volume: compared by device and inode); the EXR and the
 * PNG being one file; a directory that does not exist or cannot be written.
 * A symlink is written through: its target is replaced atomically. */
hz_status outputs_resolve(const scene_desc *sd, const char *image, bool film_named,
                          const char *png, render_outputs *out, hz_error *err);

/* Resolves and checks one output, `path` (named `what` in messages: "output",
 * "preview"), as outputs_resolve does: refused when its name does not end in
 * `ext`, when it exists and is not a regular file, when it is a dangling
 * symlink, or when its directory does not exist or cannot be written. `out`
 * gets the file that will be replaced: `path`, or a symlink's target. */
hz_status outputs_check_path(const char *path, const char *ext, const char *what, char *out,
                             size_t n, hz_error *err);

/* Refuses to replace `resolved` (from outputs_check_path of `path`) when it
 * is one of the `count` files `inputs`, compared by device and inode, so that
 * another name or a link for an input is caught too. `reader` says who reads
 * them in the message ("the render", "the merge"). */
hz_status outputs_refuse_inputs(const char *what, const char *path, const char *resolved,
                                const char *const *inputs, size_t count, const char *reader,
                                hz_error *err);

/* Where an interrupted render's image goes: `path` when nothing is there yet,
 * else NAME.partial.EXT next to it. */
void outputs_partial_path(const char *path, char *out, size_t n);

#endif
