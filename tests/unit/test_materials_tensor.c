/* materials/tensor_file and measured_data's checks: RGL's tensor container
 * read back exactly, and every truncated, corrupted or malformed file
 * refused with one line saying what (never a crash, a hang or a NaN): each
 * prefix of a valid file, each byte of it flipped, and one file per rule of
 * the container and of the BRDF's fields. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "materials/measured.h"
#include "materials/tensor_file.h"

/* A field to write: dtype 1 (uint8) or 10 (float32). */
typedef struct {
    const char *name;
    uint8_t dtype;
    int ndim;
    uint64_t shape[5];
    const void *data;
} tfield;

static uint64_t elements(const tfield *f)
{
    uint64_t n = 1;
    for (int i = 0; i < f->ndim; ++i)
        n *= f->shape[i];
    return n;
}

static void put(unsigned char **p, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; ++i)
        *(*p)++ = (unsigned char)(v >> (8 * i));
}

/* The tensor file of fields f (malloc'ed, *len bytes). */
static unsigned char *tensor_bytes(const tfield *f, int n, size_t *len)
{
    size_t table = 18, data = 0;
    for (int i = 0; i < n; ++i) {
        table += 2 + strlen(f[i].name) + 2 + 1 + 8 + 8 * (size_t)f[i].ndim;
        data += elements(&f[i]) * (f[i].dtype == 1 ? 1 : 4);
    }
    unsigned char *buf = malloc(table + data + 1), *p = buf;
    assert_non_null(buf);
    memcpy(p, "tensor_file", 12);
    p += 12;
    put(&p, 1, 1);
    put(&p, 0, 1);
    put(&p, (uint64_t)n, 4);
    uint64_t offset = table;
    for (int i = 0; i < n; ++i) {
        put(&p, strlen(f[i].name), 2);
        memcpy(p, f[i].name, strlen(f[i].name));
        p += strlen(f[i].name);
        put(&p, (uint64_t)f[i].ndim, 2);
        put(&p, f[i].dtype, 1);
        put(&p, offset, 8);
        for (int j = 0; j < f[i].ndim; ++j)
            put(&p, f[i].shape[j], 8);
        offset += elements(&f[i]) * (f[i].dtype == 1 ? 1 : 4);
    }
    for (int i = 0; i < n; ++i)
        for (uint64_t k = 0; k < elements(&f[i]); ++k) {
            if (f[i].dtype == 1) {
                put(&p, ((const uint8_t *)f[i].data)[k], 1);
            } else {
                uint32_t bits;
                memcpy(&bits, &((const float *)f[i].data)[k], 4);
                put(&p, bits, 4);
            }
        }
    *len = (size_t)(p - buf);
    return buf;
}

/* src into dst[n], cut to fit. */
static void set_msg(char *dst, size_t n, const char *src)
{
    size_t len = strlen(src);
    len = len < n ? len : n - 1;
    memcpy(dst, src, len);
    dst[len] = '\0';
}

/* Parses a copy of bytes; returns the tensor or NULL with the message. */
static tensor_file *parse(const unsigned char *bytes, size_t len, char *msg, size_t n)
{
    unsigned char *copy = malloc(len ? len : 1);
    assert_non_null(copy);
    memcpy(copy, bytes, len);
    tensor_file *t = NULL;
    hz_error err;
    msg[0] = '\0';
    if (tensor_file_parse(copy, len, &t, &err) != HZ_OK)
        set_msg(msg, n, err.message);
    return t;
}

static void expect_parse_error(const unsigned char *bytes, size_t len, const char *want)
{
    char msg[512];
    tensor_file *t = parse(bytes, len, msg, sizeof msg);
    if (t || !strstr(msg, want) || strchr(msg, '\n'))
        fail_msg("want \"%s\", got \"%s\"", want, t ? "(parsed)" : msg);
}

static void tensor_round_trip(void **state)
{
    (void)state;
    const float v[6] = {1.5f, -2.0f, 0.0f, 1e-30f, 3.25f, 7.0f};
    const uint8_t b[3] = {7, 8, 9};
    tfield f[] = {{"floats", 10, 2, {2, 3}, v}, {"bytes", 1, 1, {3}, b}};
    size_t len;
    unsigned char *bytes = tensor_bytes(f, 2, &len);
    char msg[256];
    tensor_file *t = parse(bytes, len, msg, sizeof msg);
    assert_non_null(t);
    assert_int_equal(tensor_file_field_count(t), 2);
    const tensor_field *ff = tensor_file_field(t, "floats");
    assert_non_null(ff);
    assert_true(ff->dtype == TENSOR_F32 && ff->ndim == 2 && ff->shape[0] == 2 &&
                ff->shape[1] == 3 && ff->count == 6);
    for (int i = 0; i < 6; ++i)
        assert_true(tensor_field_f32(ff, (size_t)i) == v[i]);
    const tensor_field *fb = tensor_file_field(t, "bytes");
    assert_true(fb && fb->dtype == TENSOR_U8 && fb->count == 3 && fb->data[2] == 9);
    assert_null(tensor_file_field(t, "missing"));
    tensor_file_destroy(t);
    free(bytes);
}

/* One malformed container per rule. */
static void tensor_errors(void **state)
{
    (void)state;
    const float v[4] = {1, 2, 3, 4};
    tfield f[] = {{"a", 10, 1, {4}, v}};
    size_t len;
    unsigned char *good = tensor_bytes(f, 1, &len);
    unsigned char *bad = malloc(len + 64);
    assert_non_null(bad);
    expect_parse_error(good, 5, "not a tensor file: 5 bytes");
#define MUTATE(stmt, want)                                                                   \
    do {                                                                                     \
        memcpy(bad, good, len);                                                              \
        stmt;                                                                                \
        expect_parse_error(bad, len, want);                                                  \
    } while (0)
    MUTATE(bad[10] = 'X', "does not start with \"tensor_file\"");
    MUTATE(bad[12] = 2, "tensor file version 2.0");
    MUTATE(bad[14] = 0xff; bad[15] = 0xff, "65535 fields claimed");
    MUTATE(bad[18] = 60, "field table ends past the file's end");
    MUTATE(bad[18] = 0, "field 1 has an empty name");
    MUTATE(bad[20] = '\0', "NUL byte in its name");
    MUTATE(bad[23] = 12, "unknown element type 12");
    MUTATE(bad[21] = 17, "17 dimensions (at most 16)");
    /* The field's entry: name length at 18, name at 20, rank at 21, type at
     * 23, offset at 24, shape at 32; its data at 40. */
    MUTATE(bad[32] = 5, "(20 bytes at byte 40) ends past the file's end (56 bytes)");
    MUTATE(bad[32] = 0xff, "its shape holds more data than the whole file (56 bytes)");
    MUTATE(bad[39] = 0x40, "its shape holds more data than the whole file");
    MUTATE(bad[24] = 41, "(16 bytes at byte 41) ends past the file's end");
#undef MUTATE
    /* Two fields of one name. */
    tfield twice[] = {{"a", 10, 1, {2}, v}, {"a", 10, 1, {2}, v}};
    free(good);
    good = tensor_bytes(twice, 2, &len);
    expect_parse_error(good, len, "field \"a\" appears twice");
    /* A control byte in a name is escaped in the message. */
    tfield esc[] = {{"a\x1b[31m", 10, 1, {4}, v}};
    free(good);
    good = tensor_bytes(esc, 1, &len);
    expect_parse_error(good, len - 1, "field \"a\\x1b[31m\"");
    free(good);
    free(bad);
}

static const float k_theta[2] = {0.0f, 1.2f}, k_phi[1] = {0.0f}, k_lambda[2] = {400, 700};
static const float k_ones[64] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
                                 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
                                 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
static const uint8_t k_desc[3] = {'a', 'b', 'c'}, k_jac[1] = {1};

/* A valid measured BRDF at the least resolution (10 fields). */
static void tiny_fields(tfield *f)
{
    const tfield t[10] = {
        {"theta_i", 10, 1, {2}, k_theta},          {"phi_i", 10, 1, {1}, k_phi},
        {"ndf", 10, 2, {2, 2}, k_ones},            {"sigma", 10, 2, {2, 2}, k_ones},
        {"vndf", 10, 4, {1, 2, 2, 2}, k_ones},     {"luminance", 10, 4, {1, 2, 2, 2}, k_ones},
        {"spectra", 10, 5, {1, 2, 2, 2, 2}, k_ones}, {"wavelengths", 10, 1, {2}, k_lambda},
        {"description", 1, 1, {3}, k_desc},        {"jacobian", 1, 1, {1}, k_jac},
    };
    memcpy(f, t, sizeof t);
}

/* The BRDF of fields f, or NULL with its message. */
static measured_brdf *brdf_of(const tfield *f, int n, char *msg, size_t msg_n)
{
    size_t len;
    unsigned char *bytes = tensor_bytes(f, n, &len);
    tensor_file *t = parse(bytes, len, msg, msg_n);
    free(bytes);
    assert_non_null(t);
    measured_brdf *m = NULL;
    hz_error err;
    if (measured_brdf_from_tensor(t, &m, &err) != HZ_OK)
        set_msg(msg, msg_n, err.message);
    tensor_file_destroy(t);
    return m;
}

static void expect_brdf_error(const tfield *f, int n, const char *want)
{
    char msg[512];
    measured_brdf *m = brdf_of(f, n, msg, sizeof msg);
    if (m || !strstr(msg, want))
        fail_msg("want \"%s\", got \"%s\"", want, m ? "(built)" : msg);
    print_message("refused: %s\n", msg);
}

static void brdf_structure_errors(void **state)
{
    (void)state;
    tfield f[10];
    char msg[512];
    tiny_fields(f);
    measured_brdf *m = brdf_of(f, 10, msg, sizeof msg);
    if (!m)
        fail_msg("%s", msg);
    measured_brdf_destroy(m);
    expect_brdf_error(f, 9, "no field \"jacobian\"");
    const float dec[2] = {1.0f, 0.5f}, neg[8] = {1, 1, 1, -1, 1, 1, 1, 1};
    const float nan_spectra[16] = {1, 1, 1, 1, 1, 1, NAN, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    const float zero[8] = {1, 1, 1, 1, 0, 0, 0, 0}, half_circle[3] = {0.0f, 1.5f, 3.1416f};
    const float bad_lambda[2] = {0.0f, 700.0f};
#define WITH(i, member, value, want)                                                         \
    do {                                                                                     \
        tiny_fields(f);                                                                      \
        f[i].member = value;                                                                 \
        expect_brdf_error(f, 10, want);                                                      \
    } while (0)
    WITH(4, dtype, 1, "field \"vndf\" is uint8 of rank 4; a measured BRDF's is float32");
    WITH(6, shape[2], 3, "field \"spectra\" has shape [1, 2, 3, 2, 2]; it must be [1 (phi_i)");
    WITH(2, shape[0], 1, "field \"ndf\" has shape [1, 2]; it must be at least [2, 2]");
    WITH(0, data, dec, "field \"theta_i\" must increase: value 1 is 0.5 after 1");
    WITH(7, data, bad_lambda, "field \"wavelengths\": value 0 is 0");
    WITH(4, data, neg, "field \"vndf\": value 3 is negative (-1)");
    WITH(6, data, nan_spectra, "field \"spectra\": value 6 is not finite");
    WITH(5, data, zero, "field \"luminance\": slice 2 of 2 integrates to 0");
#undef WITH
    tiny_fields(f);
    f[9].shape[0] = 2;
    f[9].data = k_desc;
    expect_brdf_error(f, 10, "field \"jacobian\" has shape [2]; it must be [1]");
    /* An anisotropic table over half the circle of azimuths. */
    tiny_fields(f);
    f[1].shape[0] = 3;
    f[1].data = half_circle;
    f[4].shape[0] = f[5].shape[0] = f[6].shape[0] = 3;
    expect_brdf_error(f, 10, "files reduced by symmetry are not supported");
}

static unsigned char *read_tiny(size_t *len)
{
    char *data;
    hz_error err;
    if (file_read_all(HAZE_TEST_BSDF "/tiny.bsdf", 1 << 20, &data, len, &err) != HZ_OK)
        fail_msg("%s", err.message);
    return (unsigned char *)data;
}

/* Evaluating and sampling a BRDF that was accepted gives finite values. */
static void expect_finite(const measured_brdf *m)
{
    const vec3 dirs[4] = {{0, 0, 1}, {0.6, 0, 0.8}, {-0.3, 0.5, 0.81240384}, {0, 0.99, 0.14}};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            rgb f = bxdf_measured_f(m, dirs[i], dirs[j]);
            double pdf = bxdf_measured_pdf(m, dirs[i], dirs[j]);
            assert_true(isfinite(f.r + f.g + f.b + pdf) && f.r >= 0 && f.g >= 0 && pdf >= 0);
            bsdf_sample s;
            if (bxdf_measured_sample(m, dirs[i], v2(0.1 + 0.2 * j, 0.7), &s))
                assert_true(isfinite(s.f.r + s.f.g + s.f.b + s.pdf) && s.pdf > 0 &&
                            v3_is_finite(s.wi));
        }
}

/* Every prefix of a valid file is refused (its last field's data is cut),
 * with one line; the whole file loads. Through a file: the message starts
 * with its path. */
static void truncated_files(void **state)
{
    (void)state;
    size_t len;
    unsigned char *bytes = read_tiny(&len);
    char msg[512];
    for (size_t n = 0; n < len; ++n) {
        tensor_file *t = parse(bytes, n, msg, sizeof msg);
        if (t || !(strstr(msg, "truncated") || strstr(msg, "not a tensor file")))
            fail_msg("prefix of %zu bytes: %s", n, t ? "parsed" : msg);
    }
    const char *path = HAZE_TMP "/truncated.bsdf";
    FILE *out = fopen(path, "wb");
    assert_non_null(out);
    fwrite(bytes, 1, len - 3, out);
    fclose(out);
    measured_brdf *m = NULL;
    hz_error err;
    assert_int_equal(measured_brdf_read(path, &m, &err), HZ_ERROR);
    print_message("%s\n", err.message);
    assert_true(strncmp(err.message, path, strlen(path)) == 0 && !strchr(err.message, '\n'));
    assert_non_null(strstr(err.message, "truncated: field \"spectra\""));
    assert_int_equal(measured_brdf_read(HAZE_TEST_BSDF "/tiny.bsdf", &m, &err), HZ_OK);
    expect_finite(m);
    measured_brdf_destroy(m);
    remove(path);
    free(bytes);
}

/* Each byte of a valid file replaced by three others: every result either
 * loads and evaluates to finite values or is refused with one line. */
static void corrupted_files(void **state)
{
    (void)state;
    size_t len;
    unsigned char *bytes = read_tiny(&len);
    const unsigned char flips[3] = {0xff, 0x01, 0x80};
    int loaded = 0, refused = 0;
    char msg[512];
    for (size_t i = 0; i < len; ++i)
        for (int k = 0; k < 3; ++k) {
            bytes[i] ^= flips[k];
            tensor_file *t = parse(bytes, len, msg, sizeof msg);
            measured_brdf *m = NULL;
            hz_error err;
            if (t && measured_brdf_from_tensor(t, &m, &err) != HZ_OK)
                set_msg(msg, sizeof msg, err.message);
            if (m) {
                expect_finite(m);
                ++loaded;
            } else {
                assert_true(msg[0] != '\0' && !strchr(msg, '\n'));
                ++refused;
            }
            measured_brdf_destroy(m);
            tensor_file_destroy(t);
            bytes[i] ^= flips[k];
        }
    print_message("%zu bytes x 3 corruptions: %d loaded, %d refused\n", len, loaded, refused);
    assert_true(loaded > 0 && refused > 0);
    free(bytes);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(tensor_round_trip),     cmocka_unit_test(tensor_errors),
        cmocka_unit_test(brdf_structure_errors), cmocka_unit_test(truncated_files),
        cmocka_unit_test(corrupted_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
