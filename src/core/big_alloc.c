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

void *hz_big_calloc(size_t count, size_t size)
{
    void *p = calloc(count, size); /* NULL when count * size overflows */
    if (p)
        advise_huge(p, count * size);
    return p;
}

void *hz_big_malloc(size_t bytes)
{
    void *p = malloc(bytes);
    advise_huge(p, bytes);
    return p;
}
