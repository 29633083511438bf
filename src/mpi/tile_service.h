/* The dynamic tile hand-out of a render across MPI ranks (internal to
 * src/mpi, over the MPI module): rank 0 holds the tile counter; its
 * own worker threads take indices from it directly, a service thread answers
 * the other ranks' requests. docs/mpi.md explains the choice. */
#ifndef HAZE_MPI_TILE_SERVICE_H
#define HAZE_MPI_TILE_SERVICE_H

#include "core/error.h"
#include "mpi/mpi_module.h"

typedef struct tile_service tile_service;

/* Every rank calls this before rendering, with its rank and the world's
 * size; rank 0 starts its service thread. */
hz_status tile_service_create(const haze_mpi_api *mpi, int rank, int size, int tile_count,
                              tile_service **out, hz_error *err);
/* renderer_options.next_tile: the next tile index, -1 when none is left.
 * Thread-safe. On ranks other than 0 a thread keeps one request ahead, so it
 * must call this until it returns -1. */
int tile_service_next(void *service);
/* renderer_options.tiles_shown: tiles handed out so far (rank 0). */
int tile_service_shown(void *service);
/* After this rank's render: the other ranks tell rank 0 they are done; rank 0
 * waits until every rank has, then stops its service thread. Returns the
 * number of tiles this rank was handed but did not ask for (0 unless a worker
 * stopped early, i.e. the render failed). */
int tile_service_finish(tile_service *s);
/* What this rank's claims cost. */
typedef struct {
    long claims;         /* calls of tile_service_next (each thread's final -1 included) */
    long late;           /* other ranks: claims whose reply had not yet arrived */
    double wait_seconds; /* other ranks: total time workers spent in tile_service_next */
    double max_wait;     /* other ranks: the longest of those waits */
    double service_cpu_seconds; /* rank 0: CPU time of the service thread */
} tile_claim_stats;

tile_claim_stats tile_service_claims(const tile_service *s);
void tile_service_destroy(tile_service *s);

#endif
