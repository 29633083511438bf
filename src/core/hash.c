#include "core/hash.h"

#include <string.h>

static uint64_t rotl(uint64_t x, int r) { return x << r | x >> (64 - r); }

uint64_t hash_block(uint64_t h, const void *p, size_t n)
{
    static const uint64_t prime[4] = {0x9E3779B97F4A7C15ull, 0xC2B2AE3D27D4EB4Full,
                                      0x165667B19E3779F9ull, 0xD6E8FEB86659FD93ull};
    const unsigned char *b = p;
    uint64_t lane[4];
    for (int k = 0; k < 4; ++k)
        lane[k] = h ^ prime[k];
    size_t i = 0;
    for (; i + 32 <= n; i += 32) {
        uint64_t w[4];
        memcpy(w, b + i, sizeof w);
        for (int k = 0; k < 4; ++k)
            lane[k] = rotl((lane[k] ^ w[k]) * prime[k], 31);
    }
    h = fnv1a(h, lane, sizeof lane);
    h = fnv1a(h, b + i, n - i); /* the last 0..31 bytes */
    return fnv1a(h, &n, sizeof n);
}
