/* Allocation for the scene subsystem. Running out of memory while reading a
 * scene is not recoverable in a useful way, so these end the program with one
 * line and exit status 1 (like any scene error) instead of threading a third
 * failure mode through every parser function. Never a crash or a core dump. */
#ifndef HAZE_SCENE_MEM_H
#define HAZE_SCENE_MEM_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static inline void *scene_xrealloc(void *p, size_t n)
{
    void *q = realloc(p, n ? n : 1);
    if (!q) {
        fprintf(stderr, "haze: out of memory reading the scene (%zu more bytes needed)\n", n);
        exit(EXIT_FAILURE);
    }
    return q;
}

static inline void *scene_xmalloc(size_t n) { return scene_xrealloc(NULL, n); }

/* count * size, refusing overflow (sizes come from untrusted files). */
static inline void *scene_xarray(size_t count, size_t size)
{
    if (size && count > (size_t)-1 / size) {
        fprintf(stderr, "haze: out of memory reading the scene (%zu x %zu bytes)\n", count, size);
        exit(EXIT_FAILURE);
    }
    return scene_xmalloc(count * size);
}

static inline char *scene_xstrdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = scene_xmalloc(n);
    memcpy(d, s, n);
    return d;
}

/* Returns `items` (of `size` bytes each) grown so that one more fits:
 * arr = scene_grow(arr, &cap, count, sizeof *arr). */
static inline void *scene_grow(void *items, size_t *capacity, size_t count, size_t size)
{
    if (count < *capacity)
        return items;
    size_t cap = *capacity ? *capacity * 2 : 8;
    *capacity = cap;
    return scene_xrealloc(items, cap * size);
}

/* Same for arrays whose capacity is not stored: it is implied by the count
 * (8, then powers of two), so growth stays amortised O(1). */
static inline void *scene_grow_implicit(void *items, size_t count, size_t size)
{
    if (count == 0)
        return scene_xrealloc(items, 8 * size);
    if (count >= 8 && (count & (count - 1)) == 0) {
        if (count > (size_t)-1 / 2 / size) {
            fprintf(stderr, "haze: out of memory reading the scene (%zu items)\n", count);
            exit(EXIT_FAILURE);
        }
        return scene_xrealloc(items, 2 * count * size);
    }
    return items;
}

#endif
