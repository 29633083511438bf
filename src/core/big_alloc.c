#define _DEFAULT_SOURCE
#include "core/big_alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>

enum { HUGE_PAGE = 2 * 1024 * 1024 };

/* Advice only: without THP, or where the call fails, the buffer is the same. */
static void advise_huge(void *p, size_t bytes)
{
#ifdef MADV_HUGEPAGE
    if (!p || bytes < 2 * (size_t)HUGE_PAGE)
        return;
    uintptr_t a = ((uintptr_t)p + HUGE_PAGE - 1) & ~(uintptr_t)(HUGE_PAGE - 1);
    uintptr_t e = ((uintptr_t)p + bytes) & ~(uintptr_t)(HUGE_PAGE - 1);
    if (e > a)
        (void)madvise((void *)a, e - a, MADV_HUGEPAGE);
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
    const uintptr_t page = 4096;
    uintptr_t a = ((uintptr_t)p + page - 1) & ~(page - 1);
    uintptr_t e = ((uintptr_t)p + bytes) & ~(page - 1);
    if (e > a)
        (void)madvise((void *)a, e - a, MADV_POPULATE_WRITE);
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
