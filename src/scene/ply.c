/* PLY reader. The whole file is read into memory and every read is bounds
 * checked, so truncated or hostile files give an error, never a crash; element
 * counts are checked against the bytes left before anything is allocated. */
#include "scene/ply.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "scene/mem.h"

#define MAX_ELEMENTS 32
#define MAX_PROPS 64

typedef enum { T_INT8, T_UINT8, T_INT16, T_UINT16, T_INT32, T_UINT32, T_FLOAT32, T_FLOAT64 } ply_type;

typedef struct {
    char name[64];
    ply_type type, count_type;
    int is_list;
} ply_prop;

typedef struct {
    char name[64];
    size_t count;
    ply_prop props[MAX_PROPS];
    int prop_count;
} ply_element;

typedef enum { FMT_ASCII, FMT_LE, FMT_BE } ply_format;

typedef struct {
    const char *path;
    const unsigned char *data;
    size_t len, pos;
    ply_format format;
    size_t line; /* ascii body only, for messages */
} ply_reader;

static const struct {
    const char *name;
    ply_type type;
    size_t size;
} type_table[] = {
    {"char", T_INT8, 1},     {"int8", T_INT8, 1},       {"uchar", T_UINT8, 1},
    {"uint8", T_UINT8, 1},   {"short", T_INT16, 2},     {"int16", T_INT16, 2},
    {"ushort", T_UINT16, 2}, {"uint16", T_UINT16, 2},   {"int", T_INT32, 4},
    {"int32", T_INT32, 4},   {"uint", T_UINT32, 4},     {"uint32", T_UINT32, 4},
    {"float", T_FLOAT32, 4}, {"float32", T_FLOAT32, 4}, {"double", T_FLOAT64, 8},
    {"float64", T_FLOAT64, 8},
};

static int parse_type(const char *s, ply_type *t)
{
    for (size_t i = 0; i < sizeof type_table / sizeof type_table[0]; ++i)
        if (strcmp(type_table[i].name, s) == 0) {
            *t = type_table[i].type;
            return 1;
        }
    return 0;
}

static size_t type_size(ply_type t)
{
    for (size_t i = 0; i < sizeof type_table / sizeof type_table[0]; ++i)
        if (type_table[i].type == t)
            return type_table[i].size;
    return 1;
}

static hz_status truncated(const ply_reader *r, hz_error *err)
{
    return hz_fail(err, "%s: file is truncated (ended while reading data)", r->path);
}

static hz_status read_binary(ply_reader *r, ply_type t, double *out, hz_error *err)
{
    size_t n = type_size(t);
    if (r->len - r->pos < n)
        return truncated(r, err);
    unsigned char b[8];
    for (size_t i = 0; i < n; ++i)
        b[i] = r->data[r->pos + (r->format == FMT_BE ? n - 1 - i : i)];
    r->pos += n;
    uint64_t u = 0;
    for (size_t i = 0; i < n; ++i)
        u |= (uint64_t)b[i] << (8 * i);
    switch (t) {
    case T_INT8: *out = (double)(int8_t)(uint8_t)u; break;
    case T_UINT8: *out = (double)(uint8_t)u; break;
    case T_INT16: *out = (double)(int16_t)(uint16_t)u; break;
    case T_UINT16: *out = (double)(uint16_t)u; break;
    case T_INT32: *out = (double)(int32_t)(uint32_t)u; break;
    case T_UINT32: *out = (double)(uint32_t)u; break;
    case T_FLOAT32: {
        uint32_t u32 = (uint32_t)u;
        float f;
        memcpy(&f, &u32, sizeof f);
        *out = f;
        break;
    }
    case T_FLOAT64: memcpy(out, &u, sizeof *out); break;
    }
    return HZ_OK;
}

static hz_status read_ascii(ply_reader *r, double *out, hz_error *err)
{
    while (r->pos < r->len && strchr(" \t\r\n", r->data[r->pos]) && r->data[r->pos]) {
        if (r->data[r->pos] == '\n')
            ++r->line;
        ++r->pos;
    }
    if (r->pos >= r->len)
        return truncated(r, err);
    char buf[64];
    size_t n = 0;
    while (r->pos < r->len && !strchr(" \t\r\n", r->data[r->pos]) && r->data[r->pos]) {
        if (n + 1 < sizeof buf)
            buf[n++] = (char)r->data[r->pos];
        ++r->pos;
    }
    buf[n] = '\0';
    char *end;
    *out = strtod(buf, &end);
    if (n == 0 || *end != '\0')
        return hz_fail(err, "%s:%zu: \"%s\" is not a number", r->path, r->line, buf);
    return HZ_OK;
}

static hz_status read_value(ply_reader *r, ply_type t, double *out, hz_error *err)
{
    hz_status st = r->format == FMT_ASCII ? read_ascii(r, out, err) : read_binary(r, t, out, err);
    if (st == HZ_OK && !isfinite(*out))
        return hz_fail(err, "%s: value is not finite", r->path);
    return st;
}

/* ---- header ------------------------------------------------------------ */

/* Copies the header line at r->pos into `line` (cut to its size, without
 * the "\r" of a CRLF file) and moves past it. */
static void header_line(ply_reader *r, char *line, size_t size)
{
    const unsigned char *nl = memchr(r->data + r->pos, '\n', r->len - r->pos);
    size_t end = nl ? (size_t)(nl - r->data) : r->len;
    size_t n = end - r->pos;
    if (n >= size)
        n = size - 1;
    memcpy(line, r->data + r->pos, n);
    line[n] = '\0';
    line[strcspn(line, "\r")] = '\0';
    r->pos = nl ? end + 1 : r->len;
}

/* "element NAME COUNT" (its words in w). */
static hz_status header_element(const ply_reader *r, char (*w)[64], int line_no,
                                ply_element *els, int *nel, hz_error *err)
{
    char *e;
    errno = 0;
    unsigned long long c = strtoull(w[2], &e, 10);
    if (*e || errno || w[2][0] == '-')
        return hz_fail(err, "%s: bad PLY header line %d: bad element count \"%s\"", r->path,
                       line_no, w[2]);
    if (*nel == MAX_ELEMENTS)
        return hz_fail(err, "%s: bad PLY header: more than %d elements", r->path, MAX_ELEMENTS);
    ply_element *el = &els[(*nel)++];
    memset(el, 0, sizeof *el);
    snprintf(el->name, sizeof el->name, "%s", w[1]);
    el->count = (size_t)c;
    if ((unsigned long long)el->count != c)
        return hz_fail(err, "%s: element count too large", r->path);
    return HZ_OK;
}

/* "property TYPE NAME" or "property list COUNT_TYPE TYPE NAME" (its k words
 * in w) of the last element. */
static hz_status header_property(const ply_reader *r, char (*w)[64], int k, int line_no,
                                 const char *line, ply_element *els, int nel, hz_error *err)
{
    if (nel == 0)
        return hz_fail(err, "%s: bad PLY header line %d: property before any element", r->path,
                       line_no);
    ply_element *el = &els[nel - 1];
    if (el->prop_count == MAX_PROPS)
        return hz_fail(err, "%s: bad PLY header: too many properties", r->path);
    ply_prop *p = &el->props[el->prop_count++];
    memset(p, 0, sizeof *p);
    int ok;
    if (k == 5 && strcmp(w[1], "list") == 0) {
        p->is_list = 1;
        ok = parse_type(w[2], &p->count_type) && parse_type(w[3], &p->type);
        snprintf(p->name, sizeof p->name, "%s", w[4]);
    } else {
        ok = k == 3 && parse_type(w[1], &p->type);
        snprintf(p->name, sizeof p->name, "%s", w[2]);
    }
    if (!ok)
        return hz_fail(err, "%s: bad PLY header line %d: \"%.80s\"", r->path, line_no, line);
    return HZ_OK;
}

static hz_status parse_header(ply_reader *r, ply_element *els, int *nel, hz_error *err)
{
    *nel = 0;
    int line_no = 0, saw_format = 0;
    for (;;) {
        if (r->pos >= r->len)
            return hz_fail(err, "%s: bad PLY header: no end_header", r->path);
        char line[256];
        header_line(r, line, sizeof line);
        ++line_no;
        char w[5][64];
        int k = sscanf(line, "%63s %63s %63s %63s %63s", w[0], w[1], w[2], w[3], w[4]);
        if (line_no == 1) {
            if (k != 1 || strcmp(w[0], "ply") != 0)
                return hz_fail(err, "%s: not a PLY file (first line is not \"ply\")", r->path);
            continue;
        }
        if (k <= 0 || strcmp(w[0], "comment") == 0 || strcmp(w[0], "obj_info") == 0)
            continue;
        if (strcmp(w[0], "end_header") == 0)
            break;
        if (strcmp(w[0], "format") == 0 && k == 3) {
            if (strcmp(w[1], "ascii") == 0)
                r->format = FMT_ASCII;
            else if (strcmp(w[1], "binary_little_endian") == 0)
                r->format = FMT_LE;
            else if (strcmp(w[1], "binary_big_endian") == 0)
                r->format = FMT_BE;
            else
                return hz_fail(err, "%s: bad PLY header line %d: unknown format \"%s\"", r->path,
                               line_no, w[1]);
            saw_format = 1;
        } else if (strcmp(w[0], "element") == 0 && k == 3) {
            if (header_element(r, w, line_no, els, nel, err) != HZ_OK)
                return HZ_ERROR;
        } else if (strcmp(w[0], "property") == 0 && (k == 3 || k == 5)) {
            if (header_property(r, w, k, line_no, line, els, *nel, err) != HZ_OK)
                return HZ_ERROR;
        } else {
            return hz_fail(err, "%s: bad PLY header line %d: \"%.80s\"", r->path, line_no, line);
        }
    }
    if (!saw_format)
        return hz_fail(err, "%s: bad PLY header: no format line", r->path);
    r->line = (size_t)line_no + 1;
    return HZ_OK;
}

/* ---- body -------------------------------------------------------------- */

static int prop_index(const ply_element *el, const char *const *names)
{
    for (; *names; ++names)
        for (int i = 0; i < el->prop_count; ++i)
            if (!el->props[i].is_list && strcmp(el->props[i].name, *names) == 0)
                return i;
    return -1;
}

/* Reads one property; scalars land in *v, lists are read and dropped unless
 * `list` is given (then up to 4 entries are stored and *list_n set). */
static hz_status read_prop(ply_reader *r, const ply_prop *p, double *v, double *list,
                           size_t *list_n, hz_error *err)
{
    if (!p->is_list)
        return read_value(r, p->type, v, err);
    double c;
    if (read_value(r, p->count_type, &c, err) != HZ_OK)
        return HZ_ERROR;
    if (c < 0 || c != (double)(size_t)c || c > (double)(r->len - r->pos + 1) * 2 + 2)
        return hz_fail(err, "%s: bad list length %g", r->path, c);
    size_t n = (size_t)c;
    if (list_n)
        *list_n = n;
    for (size_t i = 0; i < n; ++i) {
        double x;
        if (read_value(r, p->type, &x, err) != HZ_OK)
            return HZ_ERROR;
        if (list && i < 4)
            list[i] = x;
    }
    return HZ_OK;
}

static hz_status read_vertices(ply_reader *r, const ply_element *el, shape_geometry *g,
                               hz_error *err)
{
    static const char *const xs[] = {"x", NULL}, *const ys[] = {"y", NULL}, *const zs[] = {"z", NULL};
    static const char *const nxs[] = {"nx", NULL}, *const nys[] = {"ny", NULL},
                             *const nzs[] = {"nz", NULL};
    static const char *const us[] = {"u", "s", "texture_u", "texture_s", NULL};
    static const char *const vs[] = {"v", "t", "texture_v", "texture_t", NULL};
    int ix[8] = {prop_index(el, xs),  prop_index(el, ys),  prop_index(el, zs), prop_index(el, nxs),
                 prop_index(el, nys), prop_index(el, nzs), prop_index(el, us), prop_index(el, vs)};
    if (ix[0] < 0 || ix[1] < 0 || ix[2] < 0)
        return hz_fail(err, "%s: vertex element lacks x, y or z", r->path);
    int has_n = ix[3] >= 0 && ix[4] >= 0 && ix[5] >= 0;
    int has_uv = ix[6] >= 0 && ix[7] >= 0;
    g->vertex_count = el->count;
    g->p = scene_array(el->count, 3 * sizeof *g->p);
    g->n = has_n ? scene_array(el->count, 3 * sizeof *g->n) : NULL;
    g->uv = has_uv ? scene_array(el->count, 2 * sizeof *g->uv) : NULL;
    if (!g->p || (has_n && !g->n) || (has_uv && !g->uv)) /* freed by ply_read */
        return hz_fail(err, "%s: out of memory for %zu vertices", r->path, el->count);
    double vals[MAX_PROPS];
    for (size_t i = 0; i < el->count; ++i) {
        for (int k = 0; k < el->prop_count; ++k)
            if (read_prop(r, &el->props[k], &vals[k], NULL, NULL, err) != HZ_OK)
                return HZ_ERROR;
        for (int c = 0; c < 3; ++c) {
            g->p[3 * i + (size_t)c] = vals[ix[c]];
            if (has_n)
                g->n[3 * i + (size_t)c] = vals[ix[3 + c]];
        }
        if (has_uv) {
            g->uv[2 * i] = vals[ix[6]];
            g->uv[2 * i + 1] = vals[ix[7]];
        }
    }
    return HZ_OK;
}

static hz_status read_faces(ply_reader *r, const ply_element *el, shape_geometry *g, size_t *cap,
                            hz_error *err)
{
    int fi = -1;
    for (int k = 0; k < el->prop_count; ++k)
        if (el->props[k].is_list && (strcmp(el->props[k].name, "vertex_indices") == 0 ||
                                     strcmp(el->props[k].name, "vertex_index") == 0))
            fi = k;
    if (fi < 0)
        return hz_fail(err, "%s: face element has no vertex_indices list", r->path);
    for (size_t f = 0; f < el->count; ++f) {
        double idx[4] = {0, 0, 0, 0}, dummy;
        size_t n = 0;
        for (int k = 0; k < el->prop_count; ++k) {
            if (read_prop(r, &el->props[k], &dummy, k == fi ? idx : NULL, k == fi ? &n : NULL,
                          err) != HZ_OK)
                return HZ_ERROR;
        }
        if (n != 3 && n != 4)
            return hz_fail(err, "%s: face %zu has %zu vertices; only triangles and quads are "
                                "supported", r->path, f, n);
        for (size_t i = 0; i < n; ++i)
            if (idx[i] < 0 || idx[i] > 4294967295.0 || idx[i] != (double)(uint32_t)idx[i])
                return hz_fail(err, "%s: face %zu has a bad vertex index %g", r->path, f, idx[i]);
        static const int split[2][3] = {{0, 1, 2}, {0, 2, 3}};
        for (size_t t = 0; t < n - 2; ++t) {
            if (g->triangle_count == *cap) {
                size_t want = *cap ? *cap * 2 : 64;
                uint32_t *grown = scene_realloc_array(g->indices, want, 3 * sizeof *g->indices);
                if (!grown) /* g->indices is still g's: freed by ply_read */
                    return hz_fail(err, "%s: out of memory for %zu triangles", r->path, want);
                g->indices = grown;
                *cap = want;
            }
            for (int c = 0; c < 3; ++c)
                g->indices[3 * g->triangle_count + (size_t)c] = (uint32_t)idx[split[t][c]];
            g->triangle_count++;
        }
    }
    return HZ_OK;
}

static hz_status read_body(ply_reader *r, const ply_element *els, int nel, shape_geometry *g,
                           hz_error *err)
{
    size_t cap = 0;
    int saw_vertex = 0;
    for (int e = 0; e < nel; ++e) {
        const ply_element *el = &els[e];
        if (el->prop_count == 0)
            continue; /* nothing stored for it */
        /* Every element takes at least one byte: bounds the work and memory. */
        if (el->count > r->len - r->pos)
            return truncated(r, err);
        if (strcmp(el->name, "vertex") == 0 && !saw_vertex) {
            saw_vertex = 1;
            if (read_vertices(r, el, g, err) != HZ_OK)
                return HZ_ERROR;
        } else if (strcmp(el->name, "face") == 0) {
            if (read_faces(r, el, g, &cap, err) != HZ_OK)
                return HZ_ERROR;
        } else {
            double dummy;
            for (size_t i = 0; i < el->count; ++i)
                for (int k = 0; k < el->prop_count; ++k)
                    if (read_prop(r, &el->props[k], &dummy, NULL, NULL, err) != HZ_OK)
                        return HZ_ERROR;
        }
    }
    if (!saw_vertex)
        return hz_fail(err, "%s: no vertex element", r->path);
    if (g->triangle_count == 0)
        return hz_fail(err, "%s: no faces", r->path);
    for (size_t i = 0; i < 3 * g->triangle_count; ++i)
        if (g->indices[i] >= g->vertex_count)
            return hz_fail(err, "%s: vertex index %u out of range (%zu vertices)", r->path,
                           (unsigned)g->indices[i], g->vertex_count);
    return HZ_OK;
}

hz_status ply_read(const char *path, shape_geometry *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    out->kind = GEOMETRY_TRIANGLES;
    char *text;
    size_t len;
    hz_error ferr;
    if (file_read_all(path, FILE_LIMIT_MESH, &text, &len, &ferr) != HZ_OK)
        return hz_fail(err, "%s: cannot open: %s", path, ferr.message);
    unsigned char *data = (unsigned char *)text;
    ply_reader r = {path, data, len, 0, FMT_ASCII, 0};
    ply_element *els = scene_array(MAX_ELEMENTS, sizeof *els);
    int nel = 0;
    hz_status st = els ? parse_header(&r, els, &nel, err) : hz_fail(err, "%s: out of memory", path);
    if (st == HZ_OK)
        st = read_body(&r, els, nel, out, err);
    free(els);
    free(data);
    if (st != HZ_OK)
        shape_geometry_free(out);
    return st;
}
