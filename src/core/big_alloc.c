#define _DEFAULT_SOURCE
#include "core/big_alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>

enum { HUGE_PAGE = 2 * 1024 * 1024 };

#if defined(MADV_HUGEPAGE) || defined(MADV_POPULATE_WRITE)
/* madvise over the whole `align`-aligned stretches inside [p, p + bytes).
 * Advice only: where the call fails, the buffer is the same. */
static void advise_inside(void *p, size_t bytes, uintptr_t align, int advice)
{
    uintptr_t a = ((uintptr_t)p + align - 1) & ~(align - 1);
    uintptr_t e = ((uintptr_t)p + bytes) & ~(align - 1);
    if (e > a)
        (void)madvise((void *)a, e - a, advice);
}
#endif

/* Transparent huge pages over the aligned interior (without THP, nothing). */
static void advise_huge(void *p, size_t bytes)
{
#ifdef MADV_HUGEPAGE
    if (p && bytes >= 2 * (size_t)HUGE_PAGE)
        advise_inside(p, bytes, HUGE_PAGE, MADV_HUGEPAGE);
#else
    (void)p;
    (void)bytes;
#endif
}

/* Maps every page of the buffer writable now, before the render threads
 * touch it: their first access is a read (sums are read, then written),
 * which maps the shared zero page, and the write that follows faults again
 * and interrupts the other cores to flush the zero page from their TLBs. */
static void populate_write(void *p, size_t bytes)
{
#ifdef MADV_POPULATE_WRITE
    advise_inside(p, bytes, 4096, MADV_POPULATE_WRITE);
#else
    (void)p;
    (void)bytes;
#endif
}

void *hz_big_calloc(size_t count, size_t size)
{
    void *p = calloc(count, size); /* NULL when count * size overflows */
    if (p) {
        advise_huge(p, count * size);
        populate_write(p, count * size);
    }
    return p;
}

void *hz_big_malloc(size_t bytes)
{
    void *p = malloc(bytes);
    advise_huge(p, bytes);
    return p;
}
