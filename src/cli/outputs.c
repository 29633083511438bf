#define _XOPEN_SOURCE 700
#include "cli/outputs.h"

#include "core/file.h"
#include "core/hash.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* A file name with this extension (not the bare extension, nor a directory's). */
static bool has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n > m && file_has_suffix(s, suffix) && s[n - m - 1] != '/';
}

/* Creates (and removes) a probe file where the temporary file will go, which
 * also catches read-only file systems that access() does not see for root. */
static hz_status check_dir(const char *path, hz_error *err)
{
    char dir[PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    char probe[PATH_MAX + 32];
    snprintf(probe, sizeof probe, "%s/.haze-probe-XXXXXX", dir);
    int fd = mkstemp(probe);
    if (fd >= 0) {
        close(fd);
        unlink(probe);
        return HZ_OK;
    }
    int e = errno;
    struct stat st;
    if (stat(dir, &st) != 0)
        return hz_fail(err, "cannot write '%s': directory '%s' does not exist", path, dir);
    if (!S_ISDIR(st.st_mode))
        return hz_fail(err, "cannot write '%s': '%s' is not a directory", path, dir);
    return hz_fail(err, "cannot write '%s': directory '%s' is not writable (%s)", path, dir,
                   strerror(e));
}

hz_status outputs_check_path(const char *path, const char *ext, const char *what, char *out,
                             size_t n, hz_error *err)
{
    if (!has_suffix(path, ext))
        return hz_fail(err, "%s '%s' must end in %s%s", what, path, ext,
                       strcmp(ext, ".exr") == 0
                           ? " (-o writes OpenEXR; give -o NAME.exr, and --preview NAME.png for a PNG)"
                           : "");
    struct stat st;
    if (lstat(path, &st) != 0) {
        if (errno != ENOENT)
            return hz_fail(err, "cannot write '%s': %s", path, strerror(errno));
        snprintf(out, n, "%s", path);
        return check_dir(out, err);
    }
    if (S_ISLNK(st.st_mode)) {
        char *target = realpath(path, NULL);
        if (!target)
            return hz_fail(err, "%s '%s' is a symlink to a missing file (%s); name the file itself",
                           what, path, strerror(errno));
        snprintf(out, n, "%s", target);
        free(target);
        if (stat(out, &st) != 0)
            return hz_fail(err, "cannot write '%s': %s", out, strerror(errno));
    } else {
        snprintf(out, n, "%s", path);
    }
    if (!S_ISREG(st.st_mode))
        return hz_fail(err, "%s '%s' is %s; haze replaces only regular files", what, out,
                       file_kind_name(st.st_mode));
    return check_dir(out, err);
}

static bool same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    return strcmp(a, b) == 0;
}

hz_status outputs_refuse_inputs(const char *what, const char *path, const char *resolved,
                                const char *const *inputs, size_t count, const char *reader,
                                hz_error *err)
{
    struct stat so, si;
    if (stat(resolved, &so) != 0) /* only an existing output can be an input */
        return HZ_OK;
    for (size_t i = 0; i < count; ++i)
        if (stat(inputs[i], &si) == 0 && so.st_dev == si.st_dev && so.st_ino == si.st_ino)
            return hz_fail(err, "%s '%s' is '%s', which %s reads; refusing to replace it", what,
                           path, inputs[i], reader);
    return HZ_OK;
}

hz_status outputs_resolve(const scene_desc *sd, const char *image, bool film_named,
                          const char *png, render_outputs *out, hz_error *err)
{
    out->png[0] = '\0';
    /* -o writes EXR only: it is what haze merge and haze diff read back. */
    out->image_png = film_named && has_suffix(image, ".png");
    if (outputs_check_path(image, out->image_png ? ".png" : ".exr", "output", out->image,
                           sizeof out->image, err) != HZ_OK)
        return HZ_ERROR;
    if (png && outputs_check_path(png, ".png", "preview", out->png, sizeof out->png, err) != HZ_OK)
        return HZ_ERROR;
    if (png && same_file(out->image, out->png))
        return hz_fail(err, "output '%s' and preview '%s' are the same file", image, png);
    char **inputs;
    size_t count;
    if (scene_input_files(sd, &inputs, &count, err) != HZ_OK)
        return HZ_ERROR;
    const char *const *names = (const char *const *)inputs;
    hz_status st = outputs_refuse_inputs("output", image, out->image, names, count, "the render", err);
    if (st == HZ_OK && png)
        st = outputs_refuse_inputs("preview", png, out->png, names, count, "the render", err);
    scene_input_files_free(inputs, count);
    return st;
}

uint64_t outputs_render_id(uint64_t inputs_hash, const render_scene *rs, int spp,
                           bool disable_pixel_jitter)
{
    uint64_t h = fnv1a(inputs_hash, HAZE_VERSION, sizeof HAZE_VERSION);
    sampler s = *render_scene_sampler(rs);
    s.spp = spp;
    h = sampler_fingerprint(h, &s);
    HASH_FIELD(h, disable_pixel_jitter);
    return h;
}

void outputs_partial_path(const char *path, char *out, size_t n)
{
    struct stat st;
    if (lstat(path, &st) != 0 && errno == ENOENT) {
        snprintf(out, n, "%s", path);
        return;
    }
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash) || dot == path || (slash && dot == slash + 1))
        snprintf(out, n, "%s.partial", path);
    else
        snprintf(out, n, "%.*s.partial%s", (int)(dot - path), path, dot);
}
