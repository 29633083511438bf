/* Fan-out of one worker function over threads: the calling thread and up to
 * threads - 1 helpers run fn(ctx), each taking its own share of the work from
 * ctx (an atomic counter there), and all are joined before it returns. */
#ifndef HAZE_CORE_PARALLEL_H
#define HAZE_CORE_PARALLEL_H

#include <stdbool.h>

enum { HZ_PARALLEL_MAX_THREADS = 64 };

/* The online cores, at least 1 (the renderer's default thread count). */
int hz_core_count(void);

/* Runs fn(ctx) on `threads` threads (<= 0: every core; at most
 * HZ_PARALLEL_MAX_THREADS), the caller among them; fewer when a helper
 * cannot be started (the caller still runs, so the work is done by whoever
 * runs). True when every call returned NULL. */
bool hz_parallel_run(int threads, void *(*fn)(void *), void *ctx);

#endif
