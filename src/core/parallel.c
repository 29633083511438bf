#define _POSIX_C_SOURCE 200809L
#include "core/parallel.h"

#include <limits.h>
#include <pthread.h>
#include <unistd.h>

int hz_core_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > INT_MAX ? INT_MAX : (int)n;
}

bool hz_parallel_run(int threads, void *(*fn)(void *), void *ctx)
{
    if (threads < 1)
        threads = hz_core_count();
    if (threads > HZ_PARALLEL_MAX_THREADS)
        threads = HZ_PARALLEL_MAX_THREADS;
    pthread_t tid[HZ_PARALLEL_MAX_THREADS];
    int started = 0;
    while (started < threads - 1 && pthread_create(&tid[started], NULL, fn, ctx) == 0)
        started++;
    bool ok = fn(ctx) == NULL;
    for (int t = 0; t < started; ++t) {
        void *rv = NULL;
        pthread_join(tid[t], &rv);
        ok &= rv == NULL;
    }
    return ok;
}
