/* core/hash: hash_block, the fingerprint of large input files (XXH3). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "core/hash.h"

/* XXH3's published value for no bytes and seed 0 (xxHash's own sanity test):
 * hash_block is XXH3, so render ids do not move with the library's version. */
static void test_block_is_xxh3(void **state)
{
    (void)state;
    assert_true(hash_block(0, "", 0) == 0x2D06800538D394C2ull);
}

/* The same bytes give the same value; changing any one byte (at the start,
 * across XXH3's 64-byte stripes and 1 KiB blocks, in the last bytes), or the
 * length, or the seed, changes it. */
static void test_block_sensitivity(void **state)
{
    (void)state;
    enum { N = 3000 }; /* two 1 KiB blocks and a partial third */
    unsigned char *b = malloc(N);
    assert_non_null(b);
    for (int i = 0; i < N; ++i)
        b[i] = (unsigned char)(i * 37 + 11);
    const uint64_t h = hash_block(HZ_FNV_OFFSET, b, N);
    assert_true(h == hash_block(HZ_FNV_OFFSET, b, N));
    assert_true(h != hash_block(HZ_FNV_OFFSET + 1, b, N));
    assert_true(h != hash_block(HZ_FNV_OFFSET, b, N - 1));
    const int at[] = {0, 7, 8, 63, 64, 500, 1023, 1024, 2047, 2048, 2999};
    for (size_t k = 0; k < sizeof at / sizeof at[0]; ++k) {
        for (int bit = 0; bit < 8; bit += 7) {
            b[at[k]] ^= (unsigned char)(1u << bit);
            if (hash_block(HZ_FNV_OFFSET, b, N) == h)
                fail_msg("flipping bit %d of byte %d left the hash unchanged", bit, at[k]);
            b[at[k]] ^= (unsigned char)(1u << bit);
        }
    }
    /* Two words swapped. */
    unsigned char w[8];
    memcpy(w, b, 8);
    memcpy(b, b + 8, 8);
    memcpy(b + 8, w, 8);
    assert_true(hash_block(HZ_FNV_OFFSET, b, N) != h);
    /* Empty and short blocks are defined and differ by length. */
    assert_true(hash_block(HZ_FNV_OFFSET, b, 0) != hash_block(HZ_FNV_OFFSET, b, 1));
    free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_block_is_xxh3),
        cmocka_unit_test(test_block_sensitivity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
