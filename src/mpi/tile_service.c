/* Tile hand-out across MPI ranks.
 *
 * Why a service thread on rank 0 and not MPI_Fetch_and_op on a counter
 * window: passive-target one-sided operations progress only where the MPI
 * transport does atomics in hardware or shared memory (osc/sm on one node,
 * osc/ucx on RDMA networks). Over TCP, OpenMPI 4.1 falls back to osc/pt2pt,
 * whose target (rank 0) must itself enter MPI for a remote fetch to complete,
 * and rank 0's threads are busy rendering: a claim could wait for a whole
 * tile. Point-to-point messages work on every transport; the service thread
 * answers them as soon as it runs. It polls (MPI_Test and a 50 us nap)
 * instead of blocking in MPI_Recv, because OpenMPI's blocking receive spins a
 * core that rank 0's render threads need. Rank 0's own threads take tiles
 * from the same atomic counter without MPI.
 *
 * On the other ranks every worker thread keeps one request ahead: when it
 * receives tile t it at once asks for its next index, which travels while t
 * renders, so a claim costs a worker only the time to test a finished
 * request, however slowly rank 0's busy cores schedule the service thread
 * (measured: milliseconds on an oversubscribed machine). A thread thus holds
 * at most one tile in reserve; tiles are still handed out one at a time, in
 * order, to whoever asks. Each thread has its own reply tag; a mutex
 * serialises the rank's MPI calls, so MPI_THREAD_SERIALIZED suffices (rank 0
 * calls MPI only from the service thread while rendering, and from the main
 * thread after joining it). Measured costs: docs/mpi.md. */
#define _POSIX_C_SOURCE 200809L
#include "mpi/tile_service.h"

#include <pthread.h>
#include <stdbool.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

enum { TAG_CLAIM = 1, TAG_FINISH = 2, TAG_TILE_BASE = 16 };
/* Reply tags are TAG_TILE_BASE + slot; MPI guarantees tags up to 32767. */
enum { MAX_SLOTS = 32767 - TAG_TILE_BASE };

/* A worker thread of a rank other than 0 and its request in flight. Slots
 * are allocated one by one (the receive buffer `tile` must not move). */
typedef struct {
    pthread_t owner;
    int index;
    haze_mpi_request *req;
    int tile;     /* the reply lands here */
    bool pending; /* a request is out */
} claim_slot;

struct tile_service {
    const haze_mpi_api *mpi;
    int rank, size, tile_count;
    atomic_int next; /* rank 0: the next tile index to hand out */
    pthread_t thread; /* rank 0 with size > 1 */
    bool thread_started;
    bool finished; /* tile_service_finish ran */
    pthread_mutex_t lock; /* other ranks: serialises MPI calls and the slots */
    claim_slot **slots;
    int slot_count, slot_cap;
    tile_claim_stats stats; /* under lock (rank 0: claims from local_claims) */
    atomic_long local_claims; /* rank 0 */
};

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int take_local(tile_service *s)
{
    int t = atomic_fetch_add(&s->next, 1);
    return t < s->tile_count ? t : -1;
}

/* The service thread naps between tests of its posted receive: 50 us after
 * a request (others may follow), doubling while none comes, up to 1 ms. A
 * worker keeps a request ahead, so the nap hides behind the tile it renders;
 * the wake-ups stay few (measured CPU of this thread: the report line). */
enum { NAP_MIN_NS = 50 * 1000, NAP_MAX_NS = 1000 * 1000 };

static void *service_main(void *p)
{
    tile_service *s = p;
    int finished = 0;
    long nap_ns = NAP_MIN_NS;
    while (finished < s->size - 1) {
        int msg = 0, source = 0, tag = 0;
        haze_mpi_request *req = s->mpi->irecv(&msg, 1, HAZE_MPI_INT, HAZE_MPI_ANY, HAZE_MPI_ANY);
        if (!req) {
            fprintf(stderr, "haze: out of memory in the tile service\n");
            s->mpi->abort(1); /* the other ranks would wait for tiles forever */
        }
        while (!s->mpi->test(req, &source, &tag)) {
            struct timespec nap = {0, nap_ns};
            nanosleep(&nap, NULL);
            nap_ns = nap_ns * 2 < NAP_MAX_NS ? nap_ns * 2 : NAP_MAX_NS;
        }
        nap_ns = NAP_MIN_NS;
        if (tag == TAG_CLAIM) {
            int t = take_local(s);
            s->mpi->send(&t, 1, HAZE_MPI_INT, source, TAG_TILE_BASE + msg);
        } else if (tag == TAG_FINISH) {
            ++finished;
        }
    }
    struct timespec cpu;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu) == 0)
        s->stats.service_cpu_seconds = cpu.tv_sec + cpu.tv_nsec * 1e-9;
    return NULL;
}

hz_status tile_service_create(const haze_mpi_api *mpi, int rank, int size, int tile_count,
                              tile_service **out, hz_error *err)
{
    tile_service *s = calloc(1, sizeof *s);
    if (!s)
        return hz_fail(err, "out of memory for the tile service");
    s->mpi = mpi;
    s->rank = rank;
    s->size = size;
    s->tile_count = tile_count;
    atomic_init(&s->next, 0);
    atomic_init(&s->local_claims, 0);
    pthread_mutex_init(&s->lock, NULL);
    if (s->rank == 0 && s->size > 1) {
        if (pthread_create(&s->thread, NULL, service_main, s) != 0) {
            pthread_mutex_destroy(&s->lock);
            free(s);
            /* The other ranks would wait for tiles forever. */
            return hz_fail(err, "could not start the tile service thread");
        }
        s->thread_started = true;
    }
    *out = s;
    return HZ_OK;
}

/* The calling thread's slot, created on its first claim; NULL when out of
 * memory or slots. Under s->lock. */
static claim_slot *my_slot(tile_service *s)
{
    pthread_t self = pthread_self();
    for (int i = 0; i < s->slot_count; ++i)
        if (pthread_equal(s->slots[i]->owner, self))
            return s->slots[i];
    if (s->slot_count == s->slot_cap) {
        int cap = s->slot_cap ? 2 * s->slot_cap : 16;
        claim_slot **grown = cap <= MAX_SLOTS ? realloc(s->slots, (size_t)cap * sizeof *grown) : NULL;
        if (!grown)
            return NULL;
        s->slots = grown;
        s->slot_cap = cap;
    }
    claim_slot *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->owner = self;
    c->index = s->slot_count;
    c->req = NULL;
    s->slots[s->slot_count++] = c;
    return c;
}

/* Asks rank 0 for the slot's next tile index (the receive is posted first).
 * Under s->lock. */
static void post_claim(tile_service *s, claim_slot *c)
{
    c->req = s->mpi->irecv(&c->tile, 1, HAZE_MPI_INT, 0, TAG_TILE_BASE + c->index);
    if (!c->req) {
        fprintf(stderr, "haze: out of memory for a tile request\n");
        s->mpi->abort(1); /* a lost worker would leave tiles unrendered */
    }
    s->mpi->send(&c->index, 1, HAZE_MPI_INT, 0, TAG_CLAIM);
    c->pending = true;
}

int tile_service_next(void *service)
{
    tile_service *s = service;
    if (s->rank == 0) {
        atomic_fetch_add_explicit(&s->local_claims, 1, memory_order_relaxed);
        return take_local(s);
    }
    double t0 = now_seconds();
    pthread_mutex_lock(&s->lock);
    claim_slot *c = my_slot(s);
    if (!c) {
        pthread_mutex_unlock(&s->lock);
        fprintf(stderr, "haze: out of memory for a tile request\n");
        s->mpi->abort(1); /* a lost worker would leave tiles unrendered */
    }
    if (!c->pending)
        post_claim(s, c); /* the thread's first claim */
    pthread_mutex_unlock(&s->lock);
    bool late = false;
    for (int i = 0;; ++i) {
        pthread_mutex_lock(&s->lock);
        int done = s->mpi->test(c->req, NULL, NULL);
        if (done)
            c->req = NULL;
        pthread_mutex_unlock(&s->lock);
        if (done)
            break;
        late = true;
        if (i >= 64) {
            struct timespec nap = {0, 50 * 1000};
            nanosleep(&nap, NULL);
        }
    }
    int t = c->tile;
    pthread_mutex_lock(&s->lock);
    c->pending = false;
    if (t >= 0)
        post_claim(s, c); /* the next index travels while tile t renders */
    double waited = now_seconds() - t0;
    s->stats.claims++;
    s->stats.late += late;
    s->stats.wait_seconds += waited;
    if (waited > s->stats.max_wait)
        s->stats.max_wait = waited;
    pthread_mutex_unlock(&s->lock);
    return t;
}

int tile_service_shown(void *service)
{
    tile_service *s = service;
    int t = atomic_load(&s->next);
    return t < s->tile_count ? t : s->tile_count;
}

int tile_service_finish(tile_service *s)
{
    if (s->finished)
        return 0;
    s->finished = true;
    int lost = 0;
    /* A worker that stopped with a request out (only when a render failed):
     * collect the reply, counting a tile it will never render. */
    for (int i = 0; i < s->slot_count; ++i)
        if (s->slots[i]->pending) {
            s->mpi->wait(s->slots[i]->req);
            s->slots[i]->req = NULL;
            s->slots[i]->pending = false;
            lost += s->slots[i]->tile >= 0;
        }
    if (s->rank != 0) {
        int done = 0;
        s->mpi->send(&done, 1, HAZE_MPI_INT, 0, TAG_FINISH);
    } else if (s->thread_started) {
        pthread_join(s->thread, NULL);
        s->thread_started = false;
    }
    return lost;
}

tile_claim_stats tile_service_claims(const tile_service *s)
{
    tile_claim_stats c = s->stats;
    if (s->rank == 0) /* an atomic increment each: nothing to wait for */
        c.claims = atomic_load_explicit(&((tile_service *)s)->local_claims, memory_order_relaxed);
    return c;
}

void tile_service_destroy(tile_service *s)
{
    if (!s)
        return;
    tile_service_finish(s); /* joins a service thread still running (rank 0) */
    for (int i = 0; i < s->slot_count; ++i)
        free(s->slots[i]);
    free(s->slots);
    pthread_mutex_destroy(&s->lock);
    free(s);
}
