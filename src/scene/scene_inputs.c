/* Every file a render of a scene reads. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdlib.h>
#include <unistd.h>
#include <string.h>

#include "core/file.h"
#include "core/hash.h"
#include "core/path.h"
#include "scene/scene_desc.h"

static bool push(char ***list, size_t *n, size_t *cap, char *path)
{
    if (!path)
        return false;
    if (*n == *cap) {
        size_t c = *cap ? 2 * *cap : 16;
        char **grown = realloc(*list, c * sizeof *grown);
        if (!grown) {
            free(path);
            return false;
        }
        *list = grown;
        *cap = c;
    }
    (*list)[(*n)++] = path;
    return true;
}

static bool push_named(char ***list, size_t *n, size_t *cap, const scene_entity *e,
                       const char *type, const char *param_name)
{
    if (!e->type || strcmp(e->type, type) != 0)
        return true;
    const char *name = params_peek_string(&e->params, param_name, NULL);
    return !name || push(list, n, cap, path_of_scene_file(e->loc, name));
}

hz_status scene_input_files(const scene_desc *sd, char ***out, size_t *count, hz_error *err)
{
    char **list = NULL;
    size_t n = 0, cap = 0;
    bool ok = true;
    for (size_t i = 0; ok && i < sd->file_count; ++i) {
        size_t len = strlen(sd->files[i]) + 1;
        char *copy = malloc(len);
        if (copy)
            memcpy(copy, sd->files[i], len);
        ok = push(&list, &n, &cap, copy);
    }
    for (size_t i = 0; ok && i < sd->shape_count; ++i)
        ok = push_named(&list, &n, &cap, &sd->shapes[i].entity, "plymesh", "filename");
    for (size_t i = 0; ok && i < sd->object_shape_count; ++i)
        ok = push_named(&list, &n, &cap, &sd->object_shapes[i].entity, "plymesh", "filename");
    for (size_t i = 0; ok && i < sd->medium_count; ++i)
        ok = push_named(&list, &n, &cap, &sd->media[i].entity, "nanovdb", "filename");
    static const char *const image_lights[] = {"infinite", "goniometric", "projection"};
    for (size_t i = 0; ok && i < sd->light_count; ++i)
        for (int k = 0; ok && k < 3; ++k)
            ok = push_named(&list, &n, &cap, &sd->lights[i].entity, image_lights[k], "filename");
    for (size_t i = 0; ok && i < sd->texture_count; ++i)
        ok = push_named(&list, &n, &cap, &sd->textures[i].entity, "imagemap", "filename");
    if (!ok) {
        scene_input_files_free(list, n);
        return hz_fail(err, "out of memory listing the scene's files");
    }
    *out = list;
    *count = n;
    return HZ_OK;
}

hz_status scene_inputs_hash(const scene_desc *sd, uint64_t *out, hz_error *err)
{
    char **files;
    size_t count;
    if (scene_input_files(sd, &files, &count, err) != HZ_OK)
        return HZ_ERROR;
    uint64_t h = HZ_FNV_OFFSET;
    HASH_FIELD(h, count);
    hz_status st = HZ_OK;
    unsigned char *buf = malloc(1 << 16);
    if (!buf)
        st = hz_fail(err, "out of memory hashing the scene's files");
    for (size_t i = 0; st == HZ_OK && i < count; ++i) {
        int fd;
        off_t size;
        hz_error ferr;
        if (file_open_regular(files[i], &fd, &size, &ferr) != HZ_OK) {
            st = hz_fail(err, "%s: cannot read: %s", files[i], ferr.message);
            break;
        }
        HASH_FIELD(h, size);
        ssize_t n;
        while ((n = read(fd, buf, 1 << 16)) > 0)
            h = fnv1a(h, buf, (size_t)n);
        if (n < 0)
            st = hz_fail(err, "%s: cannot read: %s", files[i], strerror(errno));
        close(fd);
    }
    free(buf);
    scene_input_files_free(files, count);
    *out = h;
    return st;
}

void scene_input_files_free(char **files, size_t count)
{
    for (size_t i = 0; i < count; ++i)
        free(files[i]);
    free(files);
}
