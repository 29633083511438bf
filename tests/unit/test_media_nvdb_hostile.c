/* Hostile .nvdb files: a real grid (volumes/box.nvdb) with its checksum
 * marked absent, so nothing but the structure stands between a changed offset
 * and a wild read, then offsets pointed outside the buffer and random bytes
 * of the tree changed. Every load must end in the grid (whose lookups and
 * majorant are then safe to use) or in one error naming the grid, never in a
 * crash (this test runs under ASan + UBSan too). */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "media/grid.h"
#include "media/majorant.h"
#include "media/vdb_load.h"

#define VOLUMES HAZE_SCENES "/../volumes/"
#define GRID_SIZE 672 /* NanoVDB 32.x GridData */

static unsigned char *file_bytes(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *n = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(*n);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, *n, f), *n);
    fclose(f);
    return b;
}

/* Where the grid starts in the file: the second "NanoVDB0" (the first is the
 * file header's). */
static size_t grid_offset(const unsigned char *b, size_t n)
{
    for (size_t i = 8; i + 8 <= n; ++i)
        if (memcmp(b + i, "NanoVDB0", 8) == 0)
            return i;
    fail_msg("no grid in the file");
    return 0;
}

static void put64(unsigned char *p, uint64_t v) { memcpy(p, &v, 8); }
static void put32(unsigned char *p, uint32_t v) { memcpy(p, &v, 4); }

static void write_bytes(const char *path, const unsigned char *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, n, f), n);
    fclose(f);
}

/* Loads `bytes`, builds its majorant (every brick, also those a build leaves
 * to their first use) and looks up a few points when it loads; returns
 * whether it loaded. */
static bool try_load(const unsigned char *bytes, size_t n, char *message, size_t msize)
{
    const char *path = HAZE_TMP "/hostile.nvdb";
    write_bytes(path, bytes, n);
    grid *g = NULL;
    hz_error err = {0};
    if (grid_load(path, "density", &g, &err) != HZ_OK) {
        assert_non_null(strstr(err.message, "hostile.nvdb"));
        assert_null(strchr(err.message, '\n'));
        snprintf(message, msize, "%s", err.message);
        return false;
    }
    vec3 lo, hi;
    if (grid_support_bounds(g, &lo, &hi)) {
        majorant_grid mg;
        int32_t pad[3] = {0, 0, 0};
        if (majorant_grid_build(g, NULL, lo, hi, pad, &mg, &err) == HZ_OK) {
            size_t bricks, cells;
            majorant_grid_count(&mg, &bricks, &cells);
            majorant_grid_free(&mg);
        }
    }
    grid_accessor acc;
    grid_accessor_init(g, &acc);
    for (int i = -8; i < 48; i += 3)
        (void)grid_density_index(g, &acc, v3(i, i * 0.5, 31 - i));
    grid_destroy(g);
    message[0] = '\0';
    return true;
}

static void test_offsets_outside(void **state)
{
    (void)state;
    size_t n;
    unsigned char *orig = file_bytes(VOLUMES "box.nvdb", &n);
    size_t g = grid_offset(orig, n);
    unsigned char *b = malloc(n);
    char msg[sizeof(hz_error){0}.message];
    memcpy(b, orig, n);
    assert_true(try_load(b, n, msg, sizeof msg)); /* untouched: loads */

    const uint64_t bad[] = {0x7fff0000u, 0xfffffff0u, (uint64_t)-64, (uint64_t)1 << 40, 8};
    for (int level = 0; level < 4; ++level) /* leaf, lower, upper, root offsets */
        for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
            memcpy(b, orig, n);
            put64(b + g + 8, ~(uint64_t)0); /* checksum: absent */
            put64(b + g + GRID_SIZE + 8 * (size_t)level, bad[k]);
            assert_false(try_load(b, n, msg, sizeof msg));
            assert_non_null(strstr(msg, "is corrupt"));
        }
    /* Node counts far beyond the buffer. */
    for (int level = 0; level < 3; ++level) {
        memcpy(b, orig, n);
        put64(b + g + 8, ~(uint64_t)0);
        put32(b + g + GRID_SIZE + 32 + 4 * (size_t)level, 0x7fffffffu);
        assert_false(try_load(b, n, msg, sizeof msg));
    }
    free(b);
    free(orig);
}

/* Random changes of the tree's first kilobytes and of the node tables, with
 * the checksum absent: never a crash. */
static void test_random_tree_bytes(void **state)
{
    (void)state;
    size_t n;
    unsigned char *orig = file_bytes(VOLUMES "box.nvdb", &n);
    size_t g = grid_offset(orig, n);
    unsigned char *b = malloc(n);
    char msg[sizeof(hz_error){0}.message];
    uint64_t s = 0x9e3779b97f4a7c15u;
    int loaded = 0, refused = 0;
    for (int iter = 0; iter < 150; ++iter) {
        memcpy(b, orig, n);
        put64(b + g + 8, ~(uint64_t)0);
        for (int e = 0; e < 1 + iter % 6; ++e) {
            s = s * 6364136223846793005u + 1442695040888963407u;
            size_t span = n - g - GRID_SIZE < 40000 ? n - g - GRID_SIZE : 40000;
            size_t at = g + GRID_SIZE + (size_t)(s >> 33) % span;
            b[at] = (unsigned char)(s >> 20);
        }
        if (try_load(b, n, msg, sizeof msg))
            ++loaded;
        else
            ++refused;
    }
    /* Both outcomes occur (105 and 45 with this seed): the check neither
     * accepts every mutated tree nor refuses every change of a byte. The
     * crash-freedom itself is what ASan checks. */
    assert_true(loaded > 0 && refused > 0);
    free(b);
    free(orig);
}

/* The values themselves, not the stored statistics: a NaN, a negative and a
 * value above its leaf's stored maximum (statistics left alone, checksum
 * absent) are each refused, naming the voxel. */
static void test_bad_values(void **state)
{
    (void)state;
    size_t n;
    unsigned char *orig = file_bytes(VOLUMES "box.nvdb", &n);
    size_t g = grid_offset(orig, n);
    uint64_t leaf_offset;
    memcpy(&leaf_offset, orig + g + GRID_SIZE, 8); /* tree: first leaf, relative to the tree */
    size_t first_value = g + GRID_SIZE + (size_t)leaf_offset + 96; /* float leaf table */
    unsigned char *b = malloc(n);
    const struct {
        float value;
        const char *message;
    } cases[] = {{NAN, "voxel (0, 0, 3) is NaN"},
                 {-0.5f, "voxel (0, 0, 3) is negative (-0.5)"},
                 {INFINITY, "voxel (0, 0, 3) is infinite"},
                 {5.0f, "stores the range [1, 1] but holds values in [1, 5]"}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        memcpy(b, orig, n);
        put64(b + g + 8, ~(uint64_t)0);
        memcpy(b + first_value + 3 * 4, &cases[k].value, 4);
        const char *path = HAZE_TMP "/badvalue.nvdb";
        write_bytes(path, b, n);
        grid *gr = NULL;
        hz_error err = {0};
        assert_int_equal(grid_load(path, "density", &gr, &err), HZ_OK);
        assert_int_equal(grid_check_density(gr, &err), HZ_ERROR);
        if (!strstr(err.message, cases[k].message))
            fail_msg("got \"%s\", want \"%s\"", err.message, cases[k].message);
        grid_destroy(gr);
    }
    /* The untouched grid passes, with its true range. */
    grid *gr = NULL;
    hz_error err = {0};
    assert_int_equal(grid_load(VOLUMES "box.nvdb", "density", &gr, &err), HZ_OK);
    assert_int_equal(grid_check_density(gr, &err), HZ_OK);
    assert_true(grid_min_value(gr) == 1.0f && grid_max_value(gr) == 1.0f);
    grid_destroy(gr);
    free(b);
    free(orig);
}

/* NanoVDB's header checksum (the CRC-32 of the grid, tree and root records):
 * a changed byte of the grid's own name, which nothing else reads, is
 * refused while the file has its checksum and loads once it is marked
 * absent. */
static void test_header_checksum(void **state)
{
    (void)state;
    size_t n;
    unsigned char *b = file_bytes(VOLUMES "box.nvdb", &n);
    size_t g = grid_offset(b, n);
    uint64_t stored;
    memcpy(&stored, b + g + 8, 8);
    assert_true(stored != ~(uint64_t)0); /* box.nvdb has one */
    char msg[sizeof(hz_error){0}.message];
    assert_true(try_load(b, n, msg, sizeof msg));
    b[g + 40 + 3] ^= 0x20; /* mGridName: "density" -> "denSity" */
    assert_false(try_load(b, n, msg, sizeof msg));
    assert_non_null(strstr(msg, "is corrupt (the header's checksum is 0x"));
    put64(b + g + 8, ~(uint64_t)0);
    assert_true(try_load(b, n, msg, sizeof msg));
    free(b);
}

/* A grid of 4913 leaves (17^3: enough for the value check's pass over the
 * leaf array to run on every core) with a NaN in two leaves: the message
 * names the one a walk from the root meets first, the one in the lower
 * node's earlier child (child index 256 x + 16 y + z of each 8^3 leaf),
 * whichever thread met which. Without them the range is the values'. */
static void test_many_leaves(void **state)
{
    (void)state;
    enum { N = 136 };
    float *values = malloc(sizeof(float) * N * N * N);
    assert_non_null(values);
    for (size_t i = 0; i < (size_t)N * N * N; ++i)
        values[i] = 0.25f + (float)(i % 7) * 0.125f;
    const double scale[3] = {1, 1, 1}, origin[3] = {0, 0, 0};
    for (int bad = 0; bad < 2; ++bad) {
        if (bad) {
            values[((size_t)5 * N + 100) * N + 5] = NAN;  /* voxel (5, 100, 5): leaf (0, 12, 0) */
            values[((size_t)5 * N + 5) * N + 100] = NAN;  /* voxel (100, 5, 5): leaf (12, 0, 0) */
        }
        vdb_buffer buf;
        char why[256];
        assert_int_equal(vdb_grid_from_dense(values, N, N, N, scale, origin, "density", &buf, why,
                                             sizeof why),
                         HZ_OK);
        grid *gr = NULL;
        hz_error err = {0};
        assert_int_equal(grid_create_from_buffer(&buf, "density", &gr, &err), HZ_OK);
        if (!bad) {
            assert_int_equal(grid_check_density(gr, &err), HZ_OK);
            assert_true(grid_min_value(gr) == 0.25f && grid_max_value(gr) == 1.0f);
        } else {
            assert_int_equal(grid_check_density(gr, &err), HZ_ERROR);
            if (!strstr(err.message, "voxel (5, 100, 5) is NaN"))
                fail_msg("got \"%s\"", err.message);
        }
        grid_destroy(gr);
    }
    free(values);
}

/* Partly active leaves (every third voxel 0, so inactive): the range is
 * that of the active values alone, whichever lanes of the vector pass met
 * them, and a bad active value among inactive neighbours is refused by
 * name. */
static void test_partial_leaves(void **state)
{
    (void)state;
    enum { N = 40 };
    float *values = malloc(sizeof(float) * N * N * N);
    assert_non_null(values);
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < (size_t)N * N * N; ++i) {
        values[i] = i % 3 == 0 ? 0.0f : 0.3f + (float)(i % 11) * 0.0625f + (float)(i % 5) * 1e-3f;
        if (values[i] != 0.0f) {
            lo = values[i] < lo ? values[i] : lo;
            hi = values[i] > hi ? values[i] : hi;
        }
    }
    const double scale[3] = {1, 1, 1}, origin[3] = {0, 0, 0};
    const struct {
        float value;
        const char *message;
    } cases[] = {{0.0f, NULL},
                 {NAN, "voxel (13, 9, 21) is NaN"},
                 {-0.5f, "voxel (13, 9, 21) is negative (-0.5)"}};
    const size_t at = ((size_t)21 * N + 9) * N + 13; /* voxel (13, 9, 21), active */
    assert_true(at % 3 != 0);
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        float keep = values[at];
        if (cases[k].message)
            values[at] = cases[k].value;
        vdb_buffer buf;
        char why[256];
        assert_int_equal(vdb_grid_from_dense(values, N, N, N, scale, origin, "density", &buf, why,
                                             sizeof why),
                         HZ_OK);
        values[at] = keep;
        grid *gr = NULL;
        hz_error err = {0};
        assert_int_equal(grid_create_from_buffer(&buf, "density", &gr, &err), HZ_OK);
        if (!cases[k].message) {
            assert_int_equal(grid_check_density(gr, &err), HZ_OK);
            assert_true(grid_min_value(gr) == lo && grid_max_value(gr) == hi);
            assert_int_equal(grid_inactive_folded(gr), 0);
        } else {
            assert_int_equal(grid_check_density(gr, &err), HZ_ERROR);
            if (!strstr(err.message, cases[k].message))
                fail_msg("got \"%s\", want \"%s\"", err.message, cases[k].message);
        }
        grid_destroy(gr);
    }
    free(values);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_offsets_outside),
        cmocka_unit_test(test_partial_leaves),
        cmocka_unit_test(test_random_tree_bytes),
        cmocka_unit_test(test_bad_values),
        cmocka_unit_test(test_header_checksum),
        cmocka_unit_test(test_many_leaves),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
