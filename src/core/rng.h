/* A small counter-based random stream (SplitMix64) for estimators that need an
 * unbounded number of random numbers per sample (ratio tracking, Russian
 * roulette). Seed it from the pixel sampler (sampler_stream_seed_at) so images stay
 * independent of the thread count. */
#ifndef HAZE_CORE_RNG_H
#define HAZE_CORE_RNG_H

#include <math.h>
#include <stdint.h>

typedef struct {
    uint64_t state;
} rng;

static inline rng rng_seeded(uint64_t seed) { return (rng){seed}; }

static inline uint64_t rng_bits(rng *r)
{
    uint64_t z = (r->state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1 - 2^-53]: 1.0 is never returned. */
static inline double rng_uniform(rng *r) { return (double)(rng_bits(r) >> 11) * 0x1p-53; }

/* An exponential deviate of rate 1, -log(1 - u): 1 - u is exact for u a
 * multiple of 2^-53 in [0, 1), so log is as accurate here as log1p(-u) and
 * 2.5x faster (5 ns against 13 in glibc): one per tentative collision. */
static inline double rng_exp1(rng *r) { return -log(1.0 - rng_uniform(r)); }

#endif
