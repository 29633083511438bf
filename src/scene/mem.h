/* Allocation for the scene subsystem. Scene and PLY files are untrusted and
 * their sizes come from the file, so any of these can fail: they return NULL
 * (never print, never exit; a library must not end its caller's process) and
 * the caller reports "out of memory" at its place in the scene. The parser
 * then stops (parser_state.h, out_of_memory). Like realloc, a failed (re)allocation
 * leaves the old block as it was, still owned by the caller, who assigns the
 * result only on success (no T** to void** casts). */
#ifndef HAZE_SCENE_MEM_H
#define HAZE_SCENE_MEM_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#if defined(__GNUC__)
#define SCENE_MUST_CHECK __attribute__((warn_unused_result))
#else
#define SCENE_MUST_CHECK
#endif

SCENE_MUST_CHECK static inline void *scene_realloc(void *p, size_t n)
{
    return realloc(p, n ? n : 1);
}

SCENE_MUST_CHECK static inline void *scene_malloc(size_t n) { return scene_realloc(NULL, n); }

/* `count` items of `size` bytes; NULL when count * size overflows too. */
SCENE_MUST_CHECK static inline void *scene_realloc_array(void *p, size_t count, size_t size)
{
    if (size && count > SIZE_MAX / size)
        return NULL;
    return scene_realloc(p, count * size);
}

SCENE_MUST_CHECK static inline void *scene_array(size_t count, size_t size)
{
    return scene_realloc_array(NULL, count, size);
}

SCENE_MUST_CHECK static inline char *scene_strdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = scene_malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

/* `items` (of `size` bytes each) with room for one more after `count`: itself
 * when it has room, else a block twice as large. NULL when out of memory, and
 * then `items` and *capacity are unchanged (the owner can still free it):
 *     T *grown = scene_grow(arr, &cap, count, sizeof *arr);
 *     if (!grown) ...out of memory...
 *     arr = grown; */
SCENE_MUST_CHECK static inline void *scene_grow(void *items, size_t *capacity, size_t count,
                                                size_t size)
{
    if (count < *capacity)
        return items;
    if (*capacity > SIZE_MAX / 2)
        return NULL;
    size_t cap = *capacity ? *capacity * 2 : 8;
    void *grown = scene_realloc_array(items, cap, size);
    if (grown)
        *capacity = cap;
    return grown;
}

/* Same for arrays whose capacity is not stored: it is implied by the count
 * (8, then powers of two), so growth stays amortised O(1). The count is what
 * implies it, so a failed grow (count not incremented) changes nothing. */
SCENE_MUST_CHECK static inline void *scene_grow_implicit(void *items, size_t count, size_t size)
{
    if (count == 0)
        return scene_realloc_array(items, 8, size);
    if (count >= 8 && (count & (count - 1)) == 0) {
        if (count > SIZE_MAX / 2)
            return NULL;
        return scene_realloc_array(items, 2 * count, size);
    }
    return items;
}

#endif
