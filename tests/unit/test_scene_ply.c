#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include <zlib.h>

#include "scene/ply.h"

static void tmp_path(char *buf, size_t n, const char *name)
{
    snprintf(buf, n, "%s/%s", HAZE_TMP, name);
}

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

static void expect_error(const char *path, const char *want)
{
    shape_geometry g;
    hz_error err;
    assert_int_equal(ply_read(path, &g, &err), HZ_ERROR);
    if (!strstr(err.message, want))
        fail_msg("got \"%s\", want \"%s\"", err.message, want);
    assert_null(g.p);
}

static const char ascii_ply[] =
    "ply\nformat ascii 1.0\ncomment a quad and a triangle\n"
    "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n"
    "property float u\nproperty float v\nproperty list uchar float junk\n"
    "element face 2\nproperty list uchar int vertex_indices\nproperty int flags\n"
    "element extra 1\nproperty list int int stuff\n"
    "end_header\n"
    "0 0 0 0 0 1 0 0 2 9 9\n"
    "1 0 0 0 0 1 1 0 0\n"
    "1 1 0 0 0 1 1 1 1 7\n"
    "0 1 0 0 0 1 0 1 0\n"
    "2 2 2 0 0 1 .5 .5 0\n"
    "4 0 1 2 3 11\n"
    "3 1 4 2 12\n"
    "3 1 2 3\n";

static void test_ascii(void **state)
{
    (void)state;
    char path[512];
    tmp_path(path, sizeof path, "ascii.ply");
    write_bytes(path, ascii_ply, strlen(ascii_ply));
    shape_geometry g;
    hz_error err;
    if (ply_read(path, &g, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(g.kind, GEOMETRY_TRIANGLES);
    assert_int_equal(g.vertex_count, 5);
    assert_int_equal(g.triangle_count, 3);
    const uint32_t want[9] = {0, 1, 2, 0, 2, 3, 1, 4, 2};
    assert_memory_equal(g.indices, want, sizeof want);
    assert_true(g.p[3 * 2] == 1.0 && g.p[3 * 2 + 1] == 1.0);
    assert_true(g.p[3 * 4 + 2] == 2.0);
    assert_non_null(g.n);
    assert_true(g.n[3 * 3 + 2] == 1.0);
    assert_non_null(g.uv);
    assert_true(g.uv[2 * 4] == 0.5 && g.uv[2 * 2 + 1] == 1.0);
    shape_geometry_free(&g);
}

/* Builds a little-endian or big-endian binary PLY: 4 vertices (double xyz,
 * float s t), one quad with a uint count, plus an unknown element. */
static size_t build_binary(unsigned char *buf, int big_endian, int truncate)
{
    const char *header_fmt =
        "ply\r\nformat %s 1.0\r\nelement vertex 4\r\nproperty double x\r\nproperty double y\r\n"
        "property double z\r\nproperty float s\r\nproperty float t\r\n"
        "element face 1\r\nproperty list uint uint vertex_index\r\n"
        "element material 1\r\nproperty list uchar short name\r\nend_header\r\n";
    size_t n = (size_t)sprintf((char *)buf, header_fmt,
                               big_endian ? "binary_big_endian" : "binary_little_endian");
#define PUT(value, type)                                                                       \
    do {                                                                                        \
        type v_ = (value);                                                                      \
        unsigned char b_[sizeof v_];                                                            \
        memcpy(b_, &v_, sizeof v_);                                                             \
        for (size_t i_ = 0; i_ < sizeof v_; ++i_)                                               \
            buf[n++] = b_[big_endian ? sizeof v_ - 1 - i_ : i_];                                \
    } while (0)
    const double P[4][3] = {{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, -1}};
    for (int v = 0; v < 4; ++v) {
        for (int c = 0; c < 3; ++c)
            PUT(P[v][c], double);
        PUT((float)v * 0.25f, float);
        PUT(1.0f - (float)v * 0.25f, float);
    }
    PUT(4u, uint32_t);
    for (uint32_t i = 0; i < 4; ++i)
        PUT(i, uint32_t);
    buf[n++] = 2;
    PUT((int16_t)-5, int16_t);
    PUT((int16_t)7, int16_t);
#undef PUT
    return truncate ? n - 3 : n;
}

static void test_binary(void **state)
{
    (void)state;
    unsigned char buf[2048];
    char path[512];
    tmp_path(path, sizeof path, "binary.ply");
    for (int be = 0; be < 2; ++be) {
        write_bytes(path, buf, build_binary(buf, be, 0));
        shape_geometry g;
        hz_error err;
        if (ply_read(path, &g, &err) != HZ_OK)
            fail_msg("%s", err.message);
        assert_int_equal(g.vertex_count, 4);
        assert_int_equal(g.triangle_count, 2);
        const uint32_t want[6] = {0, 1, 2, 0, 2, 3};
        assert_memory_equal(g.indices, want, sizeof want);
        assert_true(g.p[3 * 2 + 1] == 3.0 && g.p[3 * 3 + 2] == -1.0);
        assert_null(g.n);
        assert_non_null(g.uv);
        assert_true(g.uv[2 * 1] == 0.25f && g.uv[2 * 1 + 1] == 0.75f);
        shape_geometry_free(&g);
    }
}

static void test_errors(void **state)
{
    (void)state;
    unsigned char buf[2048];
    char path[512];
    tmp_path(path, sizeof path, "bad.ply");
    size_t full = build_binary(buf, 0, 0);
    /* Every truncation of the binary file must fail cleanly. */
    size_t header = (size_t)(strstr((char *)buf, "end_header\r\n") - (char *)buf) + 12;
    for (size_t cut = 0; cut < full; ++cut) {
        write_bytes(path, buf, cut);
        shape_geometry g;
        hz_error err;
        assert_int_equal(ply_read(path, &g, &err), HZ_ERROR);
        if (cut > header && !strstr(err.message, "truncated"))
            fail_msg("cut %zu: %s", cut, err.message);
    }
    write_bytes(path, buf, build_binary(buf, 0, 1));
    expect_error(path, "bad.ply: file is truncated");

    /* Truncated ascii. */
    write_bytes(path, ascii_ply, strlen(ascii_ply) - 12);
    expect_error(path, "file is truncated");

    const char *cases[][2] = {
        {"PLY\n", "not a PLY file"},
        {"ply\nformat ascii 1.0\nelement vertex 3\n", "no end_header"},
        {"ply\nelement vertex 1\nproperty float x\nend_header\n", "no format line"},
        {"ply\nformat xml 1.0\nend_header\n", "unknown format \"xml\""},
        {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element"},
        {"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "bad element count"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "header line 4"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n",
         "vertex element lacks x, y or z"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0 1 0 0 0 1 0\n5 0 1 2 0 1\n",
         "face 0 has 5 vertices; only triangles and quads are supported"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0 1 0 0 0 1 0\n3 0 1 3\n",
         "vertex index 3 out of range (3 vertices)"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0 1 0 0 0 1 0\n3 0 1 x\n",
         "bad.ply:11: \"x\" is not a number"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nend_header\n0 0 0 1 0 0 0 1 0\n",
         "no faces"},
        {"ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\nproperty float x\n"
         "end_header\n",
         "truncated"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        write_bytes(path, cases[i][0], strlen(cases[i][0]));
        expect_error(path, cases[i][1]);
    }
    tmp_path(path, sizeof path, "does-not-exist.ply");
    expect_error(path, "does-not-exist.ply: cannot open");
}

/* pbrt-v4 reads .ply.gz; a device is refused instead of read forever. */
static void test_gzip_and_devices(void **state)
{
    (void)state;
    char plain[512], packed[512];
    tmp_path(plain, sizeof plain, "gz_quad.ply");
    tmp_path(packed, sizeof packed, "gz_quad.ply.gz");
    write_bytes(plain, ascii_ply, sizeof ascii_ply - 1);
    gzFile gz = gzopen(packed, "wb");
    assert_non_null(gz);
    assert_int_equal(gzwrite(gz, ascii_ply, sizeof ascii_ply - 1), (int)(sizeof ascii_ply - 1));
    gzclose(gz);
    shape_geometry a, b;
    hz_error err;
    if (ply_read(plain, &a, &err) != HZ_OK || ply_read(packed, &b, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(a.vertex_count, b.vertex_count);
    assert_int_equal(a.triangle_count, b.triangle_count);
    assert_memory_equal(a.p, b.p, 3 * a.vertex_count * sizeof *a.p);
    assert_memory_equal(a.indices, b.indices, 3 * a.triangle_count * sizeof *a.indices);
    shape_geometry_free(&a);
    shape_geometry_free(&b);
    expect_error("/dev/zero", "/dev/zero: cannot open: is a device; haze reads only regular files");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ascii),
        cmocka_unit_test(test_binary),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_gzip_and_devices),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
