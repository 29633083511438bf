/* The MPI module: haze's calls of MPI live in a shared module, libhaze_mpi.so,
 * that haze dlopens only when mpirun launched it (distributed_launched), so a
 * plain render never maps OpenMPI and the libraries it drags in (its runtime,
 * hwloc, libevent: some 2 ms of every process start).
 *
 * This header holds the C ABI between the two: the entry table the module
 * exports (a const data symbol, HAZE_MPI_ENTRY, checked for HAZE_MPI_ABI).
 * Every call is on MPI_COMM_WORLD; counts are MPI's ints. The module is found
 * as core/module.h says, with $HAZE_MPI_MODULE. */
#ifndef HAZE_MPI_MPI_MODULE_H
#define HAZE_MPI_MPI_MODULE_H

#include <stdint.h>

/* Bump when haze_mpi_api changes in any way. */
#define HAZE_MPI_ABI 1
#define HAZE_MPI_ENTRY "haze_mpi_entry"

/* Any source or tag, in irecv. */
enum { HAZE_MPI_ANY = -1 };

typedef enum { HAZE_MPI_BYTE, HAZE_MPI_INT, HAZE_MPI_DOUBLE, HAZE_MPI_UINT32, HAZE_MPI_UINT64 } haze_mpi_type;
typedef enum { HAZE_MPI_SUM, HAZE_MPI_MIN } haze_mpi_op;

/* A receive in flight (the module's MPI_Request). */
typedef struct haze_mpi_request haze_mpi_request;

typedef struct {
    uint32_t abi_version; /* HAZE_MPI_ABI of the module's build */
    uint32_t struct_size; /* sizeof(haze_mpi_api) of the module's build */
    /* MPI_Init_thread asking for MPI_THREAD_SERIALIZED: 0 on success, with
     * this rank, the world's size, the processor's name ("" when MPI has
     * none) and the thread level MPI provides, in *provided, and whether it
     * is at least MPI_THREAD_SERIALIZED, in *serialized. */
    int (*init)(int *rank, int *size, char *host, int host_size, int *provided, int *serialized);
    void (*finalize)(void);
    void (*abort)(int code);
    /* MPI_Gather of `count` elements from each rank into recv on `root`. */
    void (*gather)(const void *send, int count, haze_mpi_type type, void *recv, int root);
    void (*bcast)(void *buf, int count, haze_mpi_type type, int root);
    /* MPI_Reduce in place on `root` (buf the send buffer elsewhere). */
    void (*reduce)(void *buf, int count, haze_mpi_type type, haze_mpi_op op, int root);
    /* MPI_Allreduce in place. */
    void (*allreduce)(void *buf, int count, haze_mpi_type type, haze_mpi_op op);
    /* MPI_Irecv; NULL when out of memory. */
    haze_mpi_request *(*irecv)(void *buf, int count, haze_mpi_type type, int source, int tag);
    /* MPI_Test: 1 (the request freed; its source and tag, either pointer may
     * be NULL) when the receive completed, else 0. */
    int (*test)(haze_mpi_request *req, int *source, int *tag);
    /* MPI_Wait; frees the request. */
    void (*wait)(haze_mpi_request *req);
    void (*send)(const void *buf, int count, haze_mpi_type type, int dest, int tag);
} haze_mpi_api;

#endif
