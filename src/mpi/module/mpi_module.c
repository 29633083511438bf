/* The MPI module (mpi/mpi_module.h): haze's MPI calls, in libhaze_mpi.so. */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

#include "mpi/mpi_module.h"

struct haze_mpi_request {
    MPI_Request req;
};

static MPI_Datatype type_of(haze_mpi_type t)
{
    switch (t) {
    case HAZE_MPI_BYTE:
        return MPI_BYTE;
    case HAZE_MPI_INT:
        return MPI_INT;
    case HAZE_MPI_DOUBLE:
        return MPI_DOUBLE;
    case HAZE_MPI_UINT32:
        return MPI_UINT32_T;
    case HAZE_MPI_UINT64:
        return MPI_UINT64_T;
    }
    return MPI_BYTE;
}

static MPI_Op op_of(haze_mpi_op op)
{
    switch (op) {
    case HAZE_MPI_SUM:
        return MPI_SUM;
    case HAZE_MPI_MIN:
        return MPI_MIN;
    }
    return MPI_SUM;
}

static int init(int *rank, int *size, char *host, int host_size, int *provided, int *serialized)
{
    if (MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, provided) != MPI_SUCCESS)
        return 1;
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    char name[MPI_MAX_PROCESSOR_NAME];
    int len = 0;
    host[0] = '\0';
    if (host_size > 0 && MPI_Get_processor_name(name, &len) == MPI_SUCCESS && len > 0)
        snprintf(host, (size_t)host_size, "%.*s", len, name);
    *serialized = *provided >= MPI_THREAD_SERIALIZED;
    return 0;
}

static void finalize(void) { MPI_Finalize(); }

static void abort_all(int code) { MPI_Abort(MPI_COMM_WORLD, code); }

static void gather(const void *send, int count, haze_mpi_type type, void *recv, int root)
{
    MPI_Gather(send, count, type_of(type), recv, count, type_of(type), root, MPI_COMM_WORLD);
}

static void bcast(void *buf, int count, haze_mpi_type type, int root)
{
    MPI_Bcast(buf, count, type_of(type), root, MPI_COMM_WORLD);
}

static void reduce(void *buf, int count, haze_mpi_type type, haze_mpi_op op, int root)
{
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Reduce(rank == root ? MPI_IN_PLACE : buf, buf, count, type_of(type), op_of(op), root,
               MPI_COMM_WORLD);
}

static void allreduce(void *buf, int count, haze_mpi_type type, haze_mpi_op op)
{
    MPI_Allreduce(MPI_IN_PLACE, buf, count, type_of(type), op_of(op), MPI_COMM_WORLD);
}

static haze_mpi_request *irecv(void *buf, int count, haze_mpi_type type, int source, int tag)
{
    haze_mpi_request *r = malloc(sizeof *r);
    if (!r)
        return NULL;
    MPI_Irecv(buf, count, type_of(type), source == HAZE_MPI_ANY ? MPI_ANY_SOURCE : source,
              tag == HAZE_MPI_ANY ? MPI_ANY_TAG : tag, MPI_COMM_WORLD, &r->req);
    return r;
}

static int test(haze_mpi_request *r, int *source, int *tag)
{
    int done = 0;
    MPI_Status st;
    MPI_Test(&r->req, &done, &st);
    if (!done)
        return 0;
    if (source)
        *source = st.MPI_SOURCE;
    if (tag)
        *tag = st.MPI_TAG;
    free(r);
    return 1;
}

static void wait_for(haze_mpi_request *r)
{
    MPI_Wait(&r->req, MPI_STATUS_IGNORE);
    free(r);
}

static void send(const void *buf, int count, haze_mpi_type type, int dest, int tag)
{
    MPI_Send(buf, count, type_of(type), dest, tag, MPI_COMM_WORLD);
}

/* The module's one export (everything else is hidden). */
extern __attribute__((visibility("default"))) const haze_mpi_api haze_mpi_entry;
const haze_mpi_api haze_mpi_entry = {HAZE_MPI_ABI, sizeof(haze_mpi_api), init,   finalize,
                                     abort_all,    gather,               bcast,  reduce,
                                     allreduce,    irecv,                test,   wait_for,
                                     send};
