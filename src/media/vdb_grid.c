#define _POSIX_C_SOURCE 200809L
#include "media/vdb_grid.h"

#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

void vdb_buffer_free(vdb_buffer *b)
{
    if (!b)
        return;
    if (b->mapping)
        munmap(b->mapping, b->mapping_size);
    else
        free(b->data);
    *b = (vdb_buffer){NULL, 0, NULL, 0};
}

int vdb_error_is_missing_grid(const char *message)
{
    /* Both readers say this, and only this, for a file that holds no grid of
     * the name asked for. */
    return strstr(message, ": no grid named \"") != NULL;
}
