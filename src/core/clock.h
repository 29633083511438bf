/* A monotonic clock for timing: seconds as a double, and nanoseconds for the
 * per-thread time splits of `haze render --stats`. */
#ifndef HAZE_CORE_CLOCK_H
#define HAZE_CORE_CLOCK_H

#include <stdint.h>
#include <time.h>

static inline uint64_t hz_clock_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static inline double hz_clock_seconds(void) { return (double)hz_clock_ns() * 1e-9; }

#endif
