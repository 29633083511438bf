/* One image across MPI ranks (docs/mpi.md): starting MPI only when mpirun
 * launched this process, the agreement of all ranks on their scene before
 * rendering, the dynamic tile hand-out of rank 0, and the gather of the films
 * and statistics onto rank 0, which alone writes the image. In a build without
 * MPI (HAZE_HAVE_MPI undefined), or when not launched by mpirun, the context
 * is a single rank and every function takes the single-process path. */
#ifndef HAZE_MPI_DISTRIBUTED_H
#define HAZE_MPI_DISTRIBUTED_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "core/error.h"
#include "render/render_scene.h"
#include "render/progressive.h"
#include "render/renderer.h"

typedef struct distributed distributed;

/* True when the environment says mpirun (OpenMPI or a PMIx launcher) started
 * this process: OMPI_COMM_WORLD_SIZE or PMIX_RANK is set. */
bool distributed_launched(void);

/* Initialises MPI (MPI_THREAD_SERIALIZED) when distributed_launched() and the
 * build has MPI; otherwise a one-rank context that never touches MPI, so a
 * plain `haze render` does not pay MPI_Init. */
hz_status distributed_create(distributed **out, hz_error *err);
/* MPI_Finalize when MPI was initialised. NULL is ignored. */
void distributed_destroy(distributed *d);

int distributed_rank(const distributed *d);
int distributed_size(const distributed *d);

/* A hash of what must be equal on every rank for their tiles to form one
 * image: `inputs_hash` (scene_inputs_hash: the bytes of the scene, its
 * includes, meshes and volumes), the film parameters but the file name, and
 * the sampler (kind, spp, strata, jitter, seed). */
uint64_t distributed_fingerprint(uint64_t inputs_hash, const render_scene *rs);

/* Called by every rank once its scene is built, with its own status and
 * message (`local_err`, used when `local` is HZ_ERROR) and fingerprint.
 * Returns HZ_OK on every rank only when every rank succeeded and all
 * fingerprints equal rank 0's; otherwise HZ_ERROR on every rank, and rank 0
 * has written one line per failing rank to `report`:
 * "haze: rank R on host H: MESSAGE". A single process writes its own failure
 * as "haze: MESSAGE". */
hz_status distributed_agree(distributed *d, hz_status local, const hz_error *local_err,
                            uint64_t fingerprint, FILE *report);

/* renderer_run across all ranks: tiles come from rank 0 (its own threads take
 * them from a counter, the other ranks' threads ask its service thread), then
 * the films and the statistics are summed onto rank 0, whose film and `stats`
 * are then exactly those of a single-process render (wall time: the whole
 * distributed render; threads: all ranks' threads). opt->cancel must be NULL
 * with more than one rank. A failure on any rank is HZ_ERROR on every rank,
 * rank 0's `err` naming the rank and host. One rank: renderer_run. With a
 * `goal` (NULL: one render): progressive passes as renderer_run_progressive;
 * across ranks each pass after the first renders on every rank the tiles that
 * rank rendered in the first (a pixel's samples stay on one film, in order),
 * and a pass starts only when every rank expects to finish it by the deadline
 * and some rank has pixels above the target error (no pass is cut short). */
hz_status distributed_render(distributed *d, render_scene *rs, const renderer_options *opt,
                             const progressive_goal *goal, render_stats *stats, hz_error *err);

/* Rank 0 after distributed_render with more than one rank: one line with the
 * tiles each rank rendered, the mean time a worker waited for a tile index
 * from rank 0, the time rank 0 waited for the slowest rank and the time the
 * gather took. Writes nothing otherwise. */
void distributed_print_report(const distributed *d, FILE *out);

#endif
