/* Every file a render of a scene reads, and their fingerprint. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>
#include <string.h>

#include "core/digest_cache.h"
#include "core/file.h"
#include "core/hash.h"
#include "core/parallel.h"
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

/* Files up to this size are read and hashed a block of SCENE_INPUTS_BLOCK
 * at a time on one core, each block's hash_block folded in (byte by byte,
 * FNV-1a took 4 ms of a 0.014 s one-pixel render of a 2.7 MB volume);
 * larger ones (a production volume of a GB took 1.3 s that way) by windows of
 * SCENE_INPUTS_WINDOW bytes: each window's hash_block (XXH3, seeded with the
 * window's number) on every core, then the windows' values folded in file
 * order with FNV-1a into the file's digest. A window is mapped or, when it
 * cannot be, read: the same value either way. A changed byte changes its
 * window's value, and each fold step is a bijection of the running value, so
 * it changes the result. The digest cache keeps a large file's digest
 * between runs (a warm 1.1 GB volume: 0.07 s of its 0.28 s load). */
#define SCENE_INPUTS_BYTEWISE ((off_t)16 << 20)
#define SCENE_INPUTS_BLOCK ((size_t)1 << 20)
/* The digest cache's kind of these digests. */
#define SCENE_INPUTS_DIGEST "inputs-xxh3-4m"

/* Mapped a window at a time: mapped whole, a volume the render has mapped
 * too would count twice in the process's resident memory. */
#define SCENE_INPUTS_WINDOW ((size_t)4 << 20)

/* Reads up to n bytes from `at`, fewer only at the end of the file. */
static ssize_t read_full(int fd, unsigned char *buf, size_t n, off_t at)
{
    size_t got = 0;
    while (got < n) {
        ssize_t r = pread(fd, buf + got, n - got, at + (off_t)got);
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

typedef struct {
    int fd;
    size_t size, windows;
    uint64_t *value; /* per window */
    atomic_size_t next;
    atomic_int error; /* the first errno (EIO for a short read), 0: none */
} window_job;

static void window_fail(window_job *j, int e)
{
    int none = 0;
    atomic_compare_exchange_strong(&j->error, &none, e ? e : EIO);
}

static void *hash_windows(void *ctx)
{
    window_job *j = ctx;
    unsigned char *buf = NULL; /* only when a window cannot be mapped */
    for (size_t w; (w = atomic_fetch_add(&j->next, 1)) < j->windows && !atomic_load(&j->error);) {
        size_t at = w * SCENE_INPUTS_WINDOW;
        size_t len = j->size - at < SCENE_INPUTS_WINDOW ? j->size - at : SCENE_INPUTS_WINDOW;
        void *m = mmap(NULL, len, PROT_READ, MAP_PRIVATE, j->fd, (off_t)at);
        if (m != MAP_FAILED) {
            j->value[w] = hash_block(w, m, len);
            munmap(m, len);
            continue;
        }
        if (!buf && !(buf = malloc(SCENE_INPUTS_WINDOW))) {
            window_fail(j, ENOMEM);
            break;
        }
        ssize_t n = read_full(j->fd, buf, len, (off_t)at);
        if (n != (ssize_t)len) {
            window_fail(j, n < 0 ? errno : EIO);
            break;
        }
        j->value[w] = hash_block(w, buf, len);
    }
    free(buf);
    return NULL;
}

/* The windows' values folded in file order: the file's digest. */
static bool digest_large(int fd, off_t size, uint64_t *digest)
{
    window_job j = {.fd = fd, .size = (size_t)size};
    j.windows = (j.size + SCENE_INPUTS_WINDOW - 1) / SCENE_INPUTS_WINDOW;
    j.value = malloc(j.windows * sizeof *j.value);
    if (!j.value) {
        errno = ENOMEM;
        return false;
    }
    atomic_init(&j.next, 0);
    atomic_init(&j.error, 0);
    hz_parallel_run(0, hash_windows, &j);
    int e = atomic_load(&j.error);
    uint64_t d = HZ_FNV_OFFSET;
    for (size_t w = 0; !e && w < j.windows; ++w)
        HASH_FIELD(d, j.value[w]);
    free(j.value);
    *digest = d;
    errno = e;
    return e == 0;
}

/* A large file's digest, from the digest cache when it has the file as it
 * is (core/digest_cache.h), folded into h. */
static bool hash_large(int fd, off_t size, uint64_t *h)
{
    file_identity id;
    bool known = file_identity_of(fd, &id);
    file_digest d = {{0, 0}};
    if (!(known && digest_cache_get(SCENE_INPUTS_DIGEST, &id, &d))) {
        if (!digest_large(fd, size, &d.v[0]))
            return false;
        if (known)
            digest_cache_put(SCENE_INPUTS_DIGEST, &id, &d);
    }
    HASH_FIELD(*h, d.v[0]);
    return true;
}

/* A small file (read a block at a time, not cached): each block's
 * hash_block (seeded with its number), folded in order with its length. */
static bool hash_small(int fd, unsigned char *buf, uint64_t *h)
{
    ssize_t n;
    uint64_t k = 0;
    for (off_t at = 0; (n = read_full(fd, buf, SCENE_INPUTS_BLOCK, at)) > 0; at += n, ++k) {
        uint64_t v = hash_block(k, buf, (size_t)n);
        HASH_FIELD(*h, v);
        HASH_FIELD(*h, n);
    }
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
        bool ok = size > SCENE_INPUTS_BYTEWISE ? hash_large(fd, size, &h) : hash_small(fd, buf, &h);
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
