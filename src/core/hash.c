#include "core/hash.h"

#include <xxhash.h>

uint64_t hash_block(uint64_t seed, const void *p, size_t n)
{
    return (uint64_t)XXH3_64bits_withSeed(p, n, (XXH64_hash_t)seed);
}
