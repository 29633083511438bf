#include "materials/tensor_file.h"

#include <inttypes.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "core/text.h"

struct tensor_file {
    unsigned char *bytes;
    size_t len;
    tensor_field *fields;
    char **names;
    size_t count;
};

/* The fixed part of the header: magic, version, field count. */
enum { HEADER_BYTES = 12 + 2 + 4 };
/* The least a field's entry takes: name length, rank, type, offset. */
enum { FIELD_MIN_BYTES = 2 + 2 + 1 + 8 };

const char *tensor_dtype_name(tensor_dtype d)
{
    static const char *const names[] = {"invalid", "uint8",  "int8",    "uint16",
                                        "int16",   "uint32", "int32",   "uint64",
                                        "int64",   "float16", "float32", "float64"};
    return (unsigned)d < sizeof names / sizeof names[0] ? names[d] : "unknown";
}

static size_t dtype_size(tensor_dtype d)
{
    switch (d) {
    case TENSOR_U8:
    case TENSOR_I8:
        return 1;
    case TENSOR_U16:
    case TENSOR_I16:
    case TENSOR_F16:
        return 2;
    case TENSOR_U32:
    case TENSOR_I32:
    case TENSOR_F32:
        return 4;
    case TENSOR_U64:
    case TENSOR_I64:
    case TENSOR_F64:
        return 8;
    case TENSOR_INVALID:
        break;
    }
    return 0;
}

static uint64_t read_le(const unsigned char *p, int n)
{
    uint64_t v = 0;
    for (int i = n - 1; i >= 0; --i)
        v = (v << 8) | p[i];
    return v;
}

float tensor_field_f32(const tensor_field *f, size_t i)
{
    uint32_t bits = (uint32_t)read_le(f->data + 4 * i, 4);
    float v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

/* A cursor over the field table: every read checks what is left. */
typedef struct {
    const unsigned char *p;
    size_t left, at;
} cursor;

static bool take(cursor *c, size_t n, const unsigned char **out)
{
    if (c->left < n)
        return false;
    *out = c->p;
    c->p += n;
    c->left -= n;
    c->at += n;
    return true;
}

static bool take_uint(cursor *c, int n, uint64_t *v)
{
    const unsigned char *p;
    if (!take(c, (size_t)n, &p))
        return false;
    *v = read_le(p, n);
    return true;
}

/* The name as it may be printed: control bytes escaped, cut to fit. */
static void printable(const char *name, char *out, size_t n)
{
    text_escape(name, strlen(name), out, n);
}

/* Rank, type, offset and shape of field i (its name read already); the
 * data must lie inside the file. */
static hz_status read_layout(const tensor_file *t, cursor *c, tensor_field *f, hz_error *err)
{
    char shown[96];
    printable(f->name, shown, sizeof shown);
    uint64_t ndim, dtype, offset;
    if (!take_uint(c, 2, &ndim) || !take_uint(c, 1, &dtype) || !take_uint(c, 8, &offset))
        return hz_fail(err, "truncated: the entry of field \"%s\" ends past the file's end "
                            "(%zu bytes)", shown, t->len);
    if (dtype == TENSOR_INVALID || dtype > TENSOR_F64)
        return hz_fail(err, "field \"%s\" has unknown element type %" PRIu64, shown, dtype);
    if (ndim > TENSOR_MAX_DIMS)
        return hz_fail(err, "field \"%s\" has %" PRIu64 " dimensions (at most %d)", shown, ndim,
                       TENSOR_MAX_DIMS);
    f->dtype = (tensor_dtype)dtype;
    f->ndim = (int)ndim;
    size_t size = dtype_size(f->dtype), count = 1;
    bool too_big = false, empty = false;
    for (int j = 0; j < f->ndim; ++j) {
        if (!take_uint(c, 8, &f->shape[j]))
            return hz_fail(err, "truncated: the shape of field \"%s\" ends past the file's "
                                "end (%zu bytes)", shown, t->len);
        /* Checked against the file's size, so the product cannot overflow. */
        if (f->shape[j] != 0 && count > t->len / size / f->shape[j])
            too_big = true;
        else if (!too_big)
            count *= (size_t)f->shape[j];
        empty = empty || f->shape[j] == 0;
    }
    if (empty)
        count = 0;
    else if (too_big)
        return hz_fail(err, "field \"%s\": its shape holds more data than the whole file "
                            "(%zu bytes)", shown, t->len);
    if (offset > t->len || count * size > t->len - offset)
        return hz_fail(err, "truncated: field \"%s\" (%zu bytes at byte %" PRIu64
                            ") ends past the file's end (%zu bytes)",
                       shown, count * size, offset, t->len);
    f->count = count;
    f->data = t->bytes + offset;
    return HZ_OK;
}

static hz_status read_field(tensor_file *t, cursor *c, size_t i, hz_error *err)
{
    uint64_t name_len;
    const unsigned char *name;
    if (!take_uint(c, 2, &name_len) || !take(c, name_len, &name))
        return hz_fail(err, "truncated: the field table ends past the file's end (%zu bytes, "
                            "field %zu of %zu)", t->len, i + 1, t->count);
    if (name_len == 0 || memchr(name, '\0', name_len))
        return hz_fail(err, "field %zu has %s", i + 1,
                       name_len == 0 ? "an empty name" : "a NUL byte in its name");
    t->names[i] = malloc(name_len + 1);
    if (!t->names[i])
        return hz_fail(err, "out of memory");
    memcpy(t->names[i], name, name_len);
    t->names[i][name_len] = '\0';
    tensor_field *f = &t->fields[i];
    f->name = t->names[i];
    for (size_t j = 0; j < i; ++j)
        if (strcmp(t->names[j], f->name) == 0) {
            char shown[96];
            printable(f->name, shown, sizeof shown);
            return hz_fail(err, "field \"%s\" appears twice", shown);
        }
    return read_layout(t, c, f, err);
}

static hz_status parse_table(tensor_file *t, hz_error *err)
{
    if (t->len < HEADER_BYTES)
        return hz_fail(err, "not a tensor file: %zu bytes, less than its %d-byte header",
                       t->len, HEADER_BYTES);
    if (memcmp(t->bytes, "tensor_file", 12) != 0)
        return hz_fail(err, "not a tensor file (it does not start with \"tensor_file\")");
    if (t->bytes[12] != 1 || t->bytes[13] != 0)
        return hz_fail(err, "tensor file version %d.%d (haze reads 1.0)", t->bytes[12],
                       t->bytes[13]);
    uint64_t n = read_le(t->bytes + 14, 4);
    size_t most = (t->len - HEADER_BYTES) / FIELD_MIN_BYTES;
    if (n > most)
        return hz_fail(err, "truncated: %" PRIu64 " fields claimed, room for at most %zu in "
                            "%zu bytes", n, most, t->len);
    t->count = (size_t)n;
    t->fields = calloc(n ? n : 1, sizeof *t->fields);
    t->names = calloc(n ? n : 1, sizeof *t->names);
    if (!t->fields || !t->names)
        return hz_fail(err, "out of memory");
    cursor c = {t->bytes + HEADER_BYTES, t->len - HEADER_BYTES, HEADER_BYTES};
    for (size_t i = 0; i < t->count; ++i)
        if (read_field(t, &c, i, err) != HZ_OK)
            return HZ_ERROR;
    return HZ_OK;
}

hz_status tensor_file_parse(unsigned char *bytes, size_t len, tensor_file **out, hz_error *err)
{
    *out = NULL;
    tensor_file *t = calloc(1, sizeof *t);
    if (!t) {
        free(bytes);
        return hz_fail(err, "out of memory");
    }
    t->bytes = bytes;
    t->len = len;
    if (parse_table(t, err) != HZ_OK) {
        tensor_file_destroy(t);
        return HZ_ERROR;
    }
    *out = t;
    return HZ_OK;
}

hz_status tensor_file_read(const char *path, tensor_file **out, hz_error *err)
{
    *out = NULL;
    char *data = NULL;
    size_t len = 0;
    hz_error e;
    if (file_read_all(path, TENSOR_FILE_LIMIT, &data, &len, &e) != HZ_OK ||
        tensor_file_parse((unsigned char *)data, len, out, &e) != HZ_OK)
        return hz_fail(err, "%s: %s", path, e.message);
    return HZ_OK;
}

void tensor_file_destroy(tensor_file *t)
{
    if (!t)
        return;
    for (size_t i = 0; t->names && i < t->count; ++i)
        free(t->names[i]);
    free(t->names);
    free(t->fields);
    free(t->bytes);
    free(t);
}

size_t tensor_file_field_count(const tensor_file *t) { return t->count; }

const tensor_field *tensor_file_field_at(const tensor_file *t, size_t i)
{
    return i < t->count ? &t->fields[i] : NULL;
}

const tensor_field *tensor_file_field(const tensor_file *t, const char *name)
{
    for (size_t i = 0; i < t->count; ++i)
        if (strcmp(t->fields[i].name, name) == 0)
            return &t->fields[i];
    return NULL;
}
