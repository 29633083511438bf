/* Large zeroed buffers (films, their copies) that the render threads fill
 * page by page: calloc, with the kernel asked for transparent huge pages over
 * the buffer's aligned interior (where the system allows them: Linux's
 * MADV_HUGEPAGE), so that filling 10 MB of film takes a few page faults
 * instead of thousands, each of which may interrupt every other core to flush
 * its TLB. hz_big_calloc also maps every page writable at once (Linux's
 * MADV_POPULATE_WRITE, 5.14 and later): the buffer is committed when it is
 * made, not when a thread first touches it. Freed with free(). */
#ifndef HAZE_CORE_BIG_ALLOC_H
#define HAZE_CORE_BIG_ALLOC_H

#include <stddef.h>

void *hz_big_calloc(size_t count, size_t size);
void *hz_big_malloc(size_t bytes);

#endif
