/* core/hash: hash_block, the fingerprint of large input files. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "core/hash.h"

/* The same bytes give the same value; changing any one byte, in the words
 * of any lane or in the tail after the last 32-byte stripe, or the length,
 * or the starting value, changes it. */
static void test_block_sensitivity(void **state)
{
    (void)state;
    enum { N = 1000 }; /* 31 stripes and an 8-byte tail */
    unsigned char *b = malloc(N);
    assert_non_null(b);
    for (int i = 0; i < N; ++i)
        b[i] = (unsigned char)(i * 37 + 11);
    const uint64_t h = hash_block(HZ_FNV_OFFSET, b, N);
    assert_true(h == hash_block(HZ_FNV_OFFSET, b, N));
    assert_true(h != hash_block(HZ_FNV_OFFSET + 1, b, N));
    assert_true(h != hash_block(HZ_FNV_OFFSET, b, N - 1));
    const int at[] = {0, 7, 8, 15, 16, 24, 31, 32, 500, 991, 992, 999};
    for (size_t k = 0; k < sizeof at / sizeof at[0]; ++k) {
        for (int bit = 0; bit < 8; bit += 7) {
            b[at[k]] ^= (unsigned char)(1u << bit);
            if (hash_block(HZ_FNV_OFFSET, b, N) == h)
                fail_msg("flipping bit %d of byte %d left the hash unchanged", bit, at[k]);
            b[at[k]] ^= (unsigned char)(1u << bit);
        }
    }
    /* Two words swapped between lanes. */
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
        cmocka_unit_test(test_block_sensitivity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
