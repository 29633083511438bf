/* The kinds of media, one file each: the rows of medium_kinds.c's table.
 * Private to src/media; the kinds' files do not include it, so the table
 * depends on them and not the other way round. */
#ifndef HAZE_MEDIA_MEDIUM_KINDS_H
#define HAZE_MEDIA_MEDIUM_KINDS_H

#include "media/medium.h"

extern const medium_ops medium_homogeneous_ops;  /* homogeneous.c */
extern const medium_ops medium_nanovdb_ops;      /* nanovdb_medium.c */
extern const medium_ops medium_uniformgrid_ops;  /* uniformgrid_medium.c */
extern const medium_ops medium_rgbgrid_ops;      /* rgbgrid.c */
extern const medium_ops medium_cloud_ops;        /* cloud_medium.c */

#endif
