/* Every file a render of a scene reads, and their fingerprint. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdlib.h>
#include <sys/mman.h>
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

/* Files up to this size are hashed byte by byte (FNV-1a); larger ones (a
 * production volume of a GB took 1.3 s that way) in blocks of
 * SCENE_INPUTS_BLOCK with hash_block, from a mapping of the file or, when it
 * cannot be mapped, read into a buffer: the same value either way. */
#define SCENE_INPUTS_BYTEWISE ((off_t)16 << 20)
#define SCENE_INPUTS_BLOCK ((size_t)1 << 20)

/* Reads up to n bytes, fewer only at the end of the file. */
static ssize_t read_full(int fd, unsigned char *buf, size_t n)
{
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, buf + got, n - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return -1;
        if (r == 0)
            break;
        got += (size_t)r;
    }
    return (ssize_t)got;
}

/* A window of the file mapped at a time: mapped whole, a volume the render
 * has mapped too would count twice in the process's resident memory. */
#define SCENE_INPUTS_WINDOW ((size_t)4 << 20)

static bool hash_large(int fd, off_t size, unsigned char *buf, uint64_t *h)
{
    uint64_t start = *h;
    bool mapped = true;
    for (size_t w = 0; mapped && w < (size_t)size; w += SCENE_INPUTS_WINDOW) {
        size_t len = (size_t)size - w < SCENE_INPUTS_WINDOW ? (size_t)size - w : SCENE_INPUTS_WINDOW;
        void *m = mmap(NULL, len, PROT_READ, MAP_PRIVATE, fd, (off_t)w);
        if (m == MAP_FAILED) {
            mapped = false;
            break;
        }
        for (size_t at = 0; at < len; at += SCENE_INPUTS_BLOCK) {
            size_t n = len - at < SCENE_INPUTS_BLOCK ? len - at : SCENE_INPUTS_BLOCK;
            *h = hash_block(*h, (const unsigned char *)m + at, n);
        }
        munmap(m, len);
    }
    if (mapped)
        return true;
    *h = start; /* read it instead, from the start */
    if (lseek(fd, 0, SEEK_SET) != 0)
        return false;
    ssize_t n;
    while ((n = read_full(fd, buf, SCENE_INPUTS_BLOCK)) > 0)
        *h = hash_block(*h, buf, (size_t)n);
    return n == 0;
}

static bool hash_small(int fd, unsigned char *buf, uint64_t *h)
{
    ssize_t n;
    while ((n = read_full(fd, buf, SCENE_INPUTS_BLOCK)) > 0)
        *h = fnv1a(*h, buf, (size_t)n);
    return n == 0;
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
    unsigned char *buf = malloc(SCENE_INPUTS_BLOCK);
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
        bool ok = size > SCENE_INPUTS_BYTEWISE ? hash_large(fd, size, buf, &h) : hash_small(fd, buf, &h);
        if (!ok)
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
