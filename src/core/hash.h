/* 64-bit FNV-1a, for fingerprints of what a render depends on (not for
 * anything adversarial). */
#ifndef HAZE_CORE_HASH_H
#define HAZE_CORE_HASH_H

#include <stddef.h>
#include <stdint.h>

#define HZ_FNV_OFFSET 14695981039346656037ull

static inline uint64_t fnv1a(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; ++i) {
        h ^= b[i];
        h *= 1099511628211ull;
    }
    return h;
}

#define HASH_FIELD(h, x) ((h) = fnv1a((h), &(x), sizeof(x)))

/* The fingerprint of a large block at memory speed (FNV-1a takes a byte per
 * multiply, a second per GB): XXH3's 64-bit hash of the bytes with `seed`
 * (Debian's libxxhash; its values are fixed across versions since 0.8.0).
 * A different function of the bytes than fnv1a. */
uint64_t hash_block(uint64_t seed, const void *p, size_t n);

#endif
