#include "media/vdb_grid.h"

#include <stdlib.h>
#include <string.h>

void vdb_buffer_free(vdb_buffer *b)
{
    if (!b)
        return;
    free(b->data);
    b->data = NULL;
    b->size = 0;
}

int vdb_error_is_missing_grid(const char *message)
{
    /* Both readers say this, and only this, for a file that holds no grid of
     * the name asked for. */
    return strstr(message, ": no grid named \"") != NULL;
}
