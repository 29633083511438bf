#include "scene/shape_geometry.h"

#include <stdlib.h>
#include <string.h>

void shape_geometry_free(shape_geometry *g)
{
    free(g->p);
    free(g->n);
    free(g->uv);
    free(g->indices);
    free(g->cp);
    free(g->width);
    free(g->normals);
    memset(g, 0, sizeof *g);
}
