/* The "tensor_file" container that holds RGL's measured BSDFs (Dupuy and
 * Jakob 2018; Mitsuba's TensorFile, read by pbrt-v4's MeasuredBxDF): a
 * 12-byte header "tensor_file\0", a version (1, 0), a field count, then per
 * field its name, rank, element type, data offset and shape. Every number is
 * little-endian; the data of a field is its elements in row-major order.
 *
 * The reader trusts nothing: a short header, an unknown type, a shape whose
 * size overflows, data past the end of the file, a repeated name or a field
 * table longer than the file are refused with one line saying what. */
#ifndef HAZE_MATERIALS_TENSOR_FILE_H
#define HAZE_MATERIALS_TENSOR_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

typedef enum {
    TENSOR_INVALID = 0,
    TENSOR_U8,
    TENSOR_I8,
    TENSOR_U16,
    TENSOR_I16,
    TENSOR_U32,
    TENSOR_I32,
    TENSOR_U64,
    TENSOR_I64,
    TENSOR_F16,
    TENSOR_F32,
    TENSOR_F64,
} tensor_dtype;

/* Ranks above this are refused (RGL's files have at most 5). */
enum { TENSOR_MAX_DIMS = 16 };

/* More than this is not read: a device or a huge file cannot fill memory. */
#define TENSOR_FILE_LIMIT ((size_t)1 << 30)

typedef struct {
    const char *name; /* NUL-terminated, owned by the tensor_file */
    tensor_dtype dtype;
    int ndim;
    uint64_t shape[TENSOR_MAX_DIMS];
    size_t count;              /* elements: the product of the shape */
    const unsigned char *data; /* count elements, little-endian, inside the file's bytes */
} tensor_field;

typedef struct tensor_file tensor_file;

/* Parses `len` bytes, which the result takes over (freed by
 * tensor_file_destroy, or here on failure). The message is the reason
 * only. */
hz_status tensor_file_parse(unsigned char *bytes, size_t len, tensor_file **out, hz_error *err);
/* Reads and parses the file at `path` (regular files only, at most
 * TENSOR_FILE_LIMIT bytes); the message starts with the path. */
hz_status tensor_file_read(const char *path, tensor_file **out, hz_error *err);
void tensor_file_destroy(tensor_file *t);

size_t tensor_file_field_count(const tensor_file *t);
const tensor_field *tensor_file_field_at(const tensor_file *t, size_t i);
/* The field of that name, or NULL. */
const tensor_field *tensor_file_field(const tensor_file *t, const char *name);

/* "uint8", "float32", ...: the name of a type for messages. */
const char *tensor_dtype_name(tensor_dtype d);
/* Element i of a float32 field. */
float tensor_field_f32(const tensor_field *f, size_t i);

#endif
