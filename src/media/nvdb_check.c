#include "media/nvdb_check.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>
#ifdef __SSE__
#include <xmmintrin.h>
#endif
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "core/parallel.h"

#define PNANOVDB_C
#include <nanovdb/PNanoVDB.h>

typedef struct {
    pnanovdb_buf_t buf;
    uint64_t size;
    pnanovdb_grid_type_t type;
    char *why;
    size_t why_size;
    /* Children met so far per level, against the counts the tree declares. */
    uint64_t uppers, lowers, leaves;
    uint64_t max_uppers, max_lowers, max_leaves;
} checker;

static int fail(checker *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->why, c->why_size, fmt, ap);
    va_end(ap);
    return -1;
}

/* [offset, offset + bytes) inside the buffer, 32-byte aligned as NanoVDB's
 * nodes are; offsets are signed 64-bit relative to `base` in the file. */
static bool node_fits(const checker *c, uint64_t base, int64_t rel, uint64_t bytes, uint64_t *at)
{
    if (rel < -(int64_t)base || rel > (int64_t)c->size)
        return false;
    uint64_t a = (uint64_t)((int64_t)base + rel);
    if (a % 32 != 0 || a > c->size || bytes > c->size - a)
        return false;
    *at = a;
    return true;
}

static pnanovdb_address_t addr(uint64_t a)
{
    pnanovdb_address_t r = {(pnanovdb_uint32_t)a};
    return r;
}

/* Word w (bits 32 w .. 32 w + 31) of the mask at byte `off` of a node: the
 * tables' masks read a word at a time, not a bit at a time (a lower node
 * has 4096 entries; a sparse grid's lower nodes are mostly empty). */
static uint32_t mask_word(pnanovdb_buf_t buf, pnanovdb_address_t node, uint32_t off, uint32_t w)
{
    return pnanovdb_read_uint32(buf, pnanovdb_address_offset(node, off + 4u * w));
}

static uint32_t lowest_bit(uint32_t m) { return (uint32_t)__builtin_ctz(m); }

static int check_lower(checker *c, uint64_t lower_at)
{
    pnanovdb_lower_handle_t lower = {addr(lower_at)};
    uint32_t leaf_size = PNANOVDB_GRID_TYPE_GET(c->type, leaf_size);
    for (uint32_t w = 0; w < PNANOVDB_LOWER_TABLE_COUNT / 32; ++w)
        for (uint32_t bits = mask_word(c->buf, lower.address, PNANOVDB_LOWER_OFF_CHILD_MASK, w);
             bits; bits &= bits - 1) {
            uint32_t n = 32 * w + lowest_bit(bits);
            if (++c->leaves > c->max_leaves)
                return fail(c, "more leaf children than the tree's %llu leaf nodes",
                            (unsigned long long)c->max_leaves);
            int64_t rel = pnanovdb_lower_get_table_child(c->type, c->buf, lower, n);
            uint64_t at;
            if (!node_fits(c, lower_at, rel, leaf_size, &at))
                return fail(c, "a lower node's child %u points outside the buffer", n);
        }
    return 0;
}

static int check_upper(checker *c, uint64_t upper_at)
{
    pnanovdb_upper_handle_t upper = {addr(upper_at)};
    uint32_t lower_size = PNANOVDB_GRID_TYPE_GET(c->type, lower_size);
    for (uint32_t n = 0; n < PNANOVDB_UPPER_TABLE_COUNT; ++n) {
        if (!pnanovdb_upper_get_child_mask(c->buf, upper, n))
            continue;
        if (++c->lowers > c->max_lowers)
            return fail(c, "more lower children than the tree's %llu lower nodes",
                        (unsigned long long)c->max_lowers);
        int64_t rel = pnanovdb_upper_get_table_child(c->type, c->buf, upper, n);
        uint64_t at;
        if (!node_fits(c, upper_at, rel, lower_size, &at))
            return fail(c, "an upper node's child %u points outside the buffer", n);
        if (check_lower(c, at) != 0)
            return -1;
    }
    return 0;
}

/* The tree's first node of a level and its count: a whole array of nodes. */
static int check_level(checker *c, uint64_t tree_at, uint64_t offset, uint64_t count,
                       uint64_t node_size, const char *level)
{
    if (count == 0)
        return 0;
    uint64_t at;
    if (offset > c->size || !node_fits(c, tree_at, (int64_t)offset, 0, &at) ||
        count > (c->size - at) / node_size)
        return fail(c, "the tree's %llu %s nodes at offset %llu do not fit in the buffer",
                    (unsigned long long)count, level, (unsigned long long)offset);
    return 0;
}

int nvdb_check_tree(const void *data, uint64_t size, char *why, size_t why_size)
{
    checker c = {pnanovdb_make_buf((pnanovdb_uint32_t *)data, size / 4), size, 0, why, why_size,
                 0, 0, 0, 0, 0, 0};
    if (size > UINT32_MAX)
        return fail(&c, "grid buffers over 4 GiB are not supported");
    if (size < PNANOVDB_GRID_SIZE + PNANOVDB_TREE_SIZE)
        return fail(&c, "buffer too small to hold a NanoVDB grid");
    pnanovdb_grid_handle_t grid = {addr(0)};
    if (pnanovdb_grid_get_magic(c.buf, grid) != PNANOVDB_MAGIC_NUMBER)
        return fail(&c, "not a NanoVDB grid (bad magic number)");
    if (pnanovdb_grid_get_grid_size(c.buf, grid) > size)
        return fail(&c, "grid larger than its buffer");
    c.type = pnanovdb_grid_get_grid_type(c.buf, grid);
    if (c.type != PNANOVDB_GRID_TYPE_FLOAT && c.type != PNANOVDB_GRID_TYPE_VEC3F)
        return fail(&c, "not a float or vec3f grid");
    uint32_t blind = pnanovdb_grid_get_blind_metadata_count(c.buf, grid);
    if (blind > 0) {
        uint64_t at;
        if (!node_fits(&c, 0, pnanovdb_grid_get_blind_metadata_offset(c.buf, grid), 0, &at) ||
            blind > (size - at) / PNANOVDB_GRIDBLINDMETADATA_SIZE)
            return fail(&c, "blind metadata outside the buffer");
    }

    pnanovdb_tree_handle_t tree = pnanovdb_grid_get_tree(c.buf, grid);
    uint64_t tree_at = tree.address.byte_offset;
    c.max_leaves = pnanovdb_tree_get_node_count_leaf(c.buf, tree);
    c.max_lowers = pnanovdb_tree_get_node_count_lower(c.buf, tree);
    c.max_uppers = pnanovdb_tree_get_node_count_upper(c.buf, tree);
    if (check_level(&c, tree_at, pnanovdb_tree_get_node_offset_leaf(c.buf, tree), c.max_leaves,
                    PNANOVDB_GRID_TYPE_GET(c.type, leaf_size), "leaf") != 0 ||
        check_level(&c, tree_at, pnanovdb_tree_get_node_offset_lower(c.buf, tree), c.max_lowers,
                    PNANOVDB_GRID_TYPE_GET(c.type, lower_size), "lower") != 0 ||
        check_level(&c, tree_at, pnanovdb_tree_get_node_offset_upper(c.buf, tree), c.max_uppers,
                    PNANOVDB_GRID_TYPE_GET(c.type, upper_size), "upper") != 0)
        return -1;

    uint64_t root_off = pnanovdb_tree_get_node_offset_root(c.buf, tree), root_at;
    uint64_t root_size = PNANOVDB_GRID_TYPE_GET(c.type, root_size);
    uint64_t tile_size = PNANOVDB_GRID_TYPE_GET(c.type, root_tile_size);
    if (root_off > size || !node_fits(&c, tree_at, (int64_t)root_off, root_size, &root_at))
        return fail(&c, "the root node lies outside the buffer");
    pnanovdb_root_handle_t root = {addr(root_at)};
    uint64_t tiles = pnanovdb_root_get_tile_count(c.buf, root);
    if (tiles > (size - root_at - root_size) / tile_size)
        return fail(&c, "the root's %llu tiles do not fit in the buffer",
                    (unsigned long long)tiles);
    uint32_t upper_size = PNANOVDB_GRID_TYPE_GET(c.type, upper_size);
    for (uint32_t t = 0; t < tiles; ++t) {
        pnanovdb_root_tile_handle_t tile = pnanovdb_root_get_tile(c.type, root, t);
        int64_t rel = pnanovdb_root_tile_get_child(c.buf, tile);
        if (rel == 0)
            continue; /* a value tile */
        if (++c.uppers > c.max_uppers)
            return fail(&c, "more root children than the tree's %llu upper nodes",
                        (unsigned long long)c.max_uppers);
        uint64_t at;
        if (!node_fits(&c, root_at, rel, upper_size, &at))
            return fail(&c, "root tile %u points outside the buffer", t);
        if (check_upper(&c, at) != 0)
            return -1;
    }
    return 0;
}

/* NanoVDB's checksum: the low 32 bits hold the header's CRC-32, all bits
 * set means no checksum. */
static int check_head_crc(checker *c, const void *data)
{
    pnanovdb_grid_handle_t grid = {addr(0)};
    uint64_t stored = pnanovdb_grid_get_checksum(c->buf, grid);
    if (stored == ~(uint64_t)0)
        return 0;
    pnanovdb_tree_handle_t tree = pnanovdb_grid_get_tree(c->buf, grid);
    pnanovdb_root_handle_t root = pnanovdb_tree_get_root(c->buf, tree);
    /* NanoVDB's range: the records laid end to end from the grid's start,
     * the root's tiles last. */
    uint64_t end = PNANOVDB_GRID_SIZE + PNANOVDB_TREE_SIZE +
                   PNANOVDB_GRID_TYPE_GET(c->type, root_size) +
                   (uint64_t)pnanovdb_root_get_tile_count(c->buf, root) *
                       PNANOVDB_GRID_TYPE_GET(c->type, root_tile_size);
    if (end > c->size)
        return fail(c, "the root's tiles run past the buffer");
    enum { SKIP = 16 }; /* the magic number and the checksum itself */
    uLong crc = crc32(0L, (const Bytef *)data + SKIP, (uInt)(end - SKIP));
    if ((uint32_t)crc != (uint32_t)stored)
        return fail(c, "the header's checksum is 0x%08x, the file says 0x%08x", (unsigned)crc,
                    (unsigned)(uint32_t)stored);
    return 0;
}

int nvdb_check_grid(const void *data, uint64_t size, char *why, size_t why_size)
{
    if (nvdb_check_tree(data, size, why, why_size) != 0)
        return -1;
    checker c = {pnanovdb_make_buf((pnanovdb_uint32_t *)data, size / 4), size, 0, why, why_size,
                 0, 0, 0, 0, 0, 0};
    c.type = pnanovdb_grid_get_grid_type(c.buf, (pnanovdb_grid_handle_t){addr(0)});
    return check_head_crc(&c, data);
}

static double vec3_length_at(pnanovdb_buf_t buf, pnanovdb_address_t at)
{
    double x = pnanovdb_read_float(buf, at), y = pnanovdb_read_float(buf, pnanovdb_address_offset(at, 4)),
           z = pnanovdb_read_float(buf, pnanovdb_address_offset(at, 8));
    return sqrt(x * x + y * y + z * z);
}

void nvdb_root_range(const void *data, uint64_t size, double *lo, double *hi)
{
    pnanovdb_buf_t buf = pnanovdb_make_buf((pnanovdb_uint32_t *)data, size / 4);
    pnanovdb_grid_handle_t grid = {addr(0)};
    pnanovdb_grid_type_t type = pnanovdb_grid_get_grid_type(buf, grid);
    pnanovdb_root_handle_t root = pnanovdb_tree_get_root(buf, pnanovdb_grid_get_tree(buf, grid));
    pnanovdb_address_t min_at = pnanovdb_root_get_min_address(type, buf, root);
    pnanovdb_address_t max_at = pnanovdb_root_get_max_address(type, buf, root);
    if (type == PNANOVDB_GRID_TYPE_VEC3F) {
        *lo = vec3_length_at(buf, min_at);
        *hi = vec3_length_at(buf, max_at);
    } else {
        *lo = pnanovdb_read_float(buf, min_at);
        *hi = pnanovdb_read_float(buf, max_at);
    }
}

/* ---- values of a density grid ---- */

typedef struct {
    checker c;
    bool any;          /* an active value met */
    float lo, hi;      /* of the active values met */
    bool signed_ok;    /* negative values allowed (not a density) */
    uint8_t *data;     /* the buffer, written where inactive values fold */
    float bg;          /* the background */
    uint64_t folded;   /* voxels whose inactive value became the background */
    const struct leaf_pass *pass; /* the leaves checked beforehand (NULL: none) */
} values;

/* An inactive value (a voxel, or a tile of `voxels` voxels) holds the
 * background: lookups read stored values whatever their state, while the
 * majorants, supports and empty-space boxes take inactive voxels to be the
 * background (OpenVDB's meaning of inactive in a fog volume). Writing the
 * background over any other value makes every estimator and the statistics
 * agree on one field. */
static void fold_inactive(values *v, pnanovdb_address_t at, uint64_t voxels)
{
    float x = pnanovdb_read_float(v->c.buf, at);
    if (x == v->bg)
        return;
    memcpy(v->data + at.byte_offset, &v->bg, sizeof v->bg);
    v->folded += voxels;
}

static int bad_value(values *v, float x, const pnanovdb_coord_t *at, const char *where)
{
    if (isnan(x))
        return fail(&v->c, "%s (%d, %d, %d) is NaN", where, at->x, at->y, at->z);
    if (isinf(x))
        return fail(&v->c, "%s (%d, %d, %d) is infinite", where, at->x, at->y, at->z);
    return fail(&v->c, "%s (%d, %d, %d) is negative (%g); densities must be >= 0", where, at->x,
                at->y, at->z, (double)x);
}

/* One active value: finite (and >= 0 for a density), and it widens the
 * running range. */
static int take(values *v, float x, const pnanovdb_coord_t *at, const char *where, float *lo,
                float *hi, bool *any)
{
    if (!isfinite(x) || (!v->signed_ok && !(x >= 0.0f)))
        return bad_value(v, x, at, where);
    *lo = *any ? fminf(*lo, x) : x;
    *hi = *any ? fmaxf(*hi, x) : x;
    *any = true;
    return 0;
}

/* The stored statistics of a node must bound what lies under it: the
 * majorant grid is built from them. */
static int stats_bound(values *v, pnanovdb_address_t min_at, pnanovdb_address_t max_at, bool any,
                       float lo, float hi, const pnanovdb_coord_t *at, const char *level)
{
    if (!any)
        return 0;
    float smin = pnanovdb_read_float(v->c.buf, min_at), smax = pnanovdb_read_float(v->c.buf, max_at);
    if (!(smin <= lo && smax >= hi))
        return fail(&v->c,
                    "the %s node at (%d, %d, %d) stores the range [%g, %g] but holds values in "
                    "[%g, %g]",
                    level, at->x, at->y, at->z, (double)smin, (double)smax, (double)lo,
                    (double)hi);
    return 0;
}

/* The first bad active value of a leaf (one that leaf_scan found), named. */
static int leaf_bad_value(values *v, pnanovdb_leaf_handle_t leaf, const uint32_t *mask,
                          const float *x)
{
    pnanovdb_coord_t origin = pnanovdb_leaf_get_bbox_min(v->c.buf, leaf);
    float l = 0, h = 0;
    bool a = false;
    for (uint32_t n = 0; n < PNANOVDB_LEAF_TABLE_COUNT; ++n) {
        if (!(mask[n >> 5] >> (n & 31) & 1))
            continue;
        pnanovdb_coord_t at = {origin.x + (int32_t)(n >> 6), origin.y + (int32_t)((n >> 3) & 7),
                               origin.z + (int32_t)(n & 7)};
        if (take(v, x[n], &at, "voxel", &l, &h, &a) != 0)
            return -1;
    }
    return fail(&v->c, "a voxel of the leaf at (%d, %d, %d) is out of range", origin.x, origin.y,
                origin.z);
}

/* The first zero of x[0 .. n) (which of +0 and -0 a running minimum or
 * maximum met first keeps). */
static float first_zero(const float *x, uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i)
        if (x[i] == 0.0f)
            return x[i];
    return 0.0f;
}

enum { LANES = 8 };

/* A fully active leaf's values: in range (*bad when not) and their range,
 * in LANES running minima and maxima that the compiler keeps in vector
 * registers; the same bits as one running minimum and maximum (a zero
 * result is the first zero met, as that keeps it). A NaN or an infinity
 * makes its lane's sum of v * 0 NaN. */
static bool full_leaf_range(const float *x, float floor_value, float *lo, float *hi)
{
    float l[LANES], h[LANES], z[LANES];
#ifdef __SSE__
    /* minps(v, l) is v < l ? v : l, lane by lane (maxps likewise) */
    __m128 l0 = _mm_set1_ps(INFINITY), l1 = l0, h0 = _mm_set1_ps(-INFINITY), h1 = h0;
    __m128 z0 = _mm_setzero_ps(), z1 = z0;
    const __m128 zero = _mm_setzero_ps();
    for (uint32_t n = 0; n < PNANOVDB_LEAF_TABLE_COUNT; n += LANES) {
        __m128 v0 = _mm_loadu_ps(x + n), v1 = _mm_loadu_ps(x + n + 4);
        l0 = _mm_min_ps(v0, l0);
        l1 = _mm_min_ps(v1, l1);
        h0 = _mm_max_ps(v0, h0);
        h1 = _mm_max_ps(v1, h1);
        z0 = _mm_add_ps(z0, _mm_mul_ps(v0, zero));
        z1 = _mm_add_ps(z1, _mm_mul_ps(v1, zero));
    }
    _mm_storeu_ps(l, l0);
    _mm_storeu_ps(l + 4, l1);
    _mm_storeu_ps(h, h0);
    _mm_storeu_ps(h + 4, h1);
    _mm_storeu_ps(z, z0);
    _mm_storeu_ps(z + 4, z1);
#else
    for (int k = 0; k < LANES; ++k) {
        l[k] = INFINITY;
        h[k] = -INFINITY;
        z[k] = 0.0f;
    }
    for (uint32_t n = 0; n < PNANOVDB_LEAF_TABLE_COUNT; n += LANES)
        for (int k = 0; k < LANES; ++k) {
            float v = x[n + (uint32_t)k];
            l[k] = v < l[k] ? v : l[k];
            h[k] = v > h[k] ? v : h[k];
            z[k] += v * 0.0f;
        }
#endif
    bool bad = false;
    for (int k = 0; k < LANES; ++k) {
        bad = bad || z[k] != 0.0f;
        *lo = k == 0 || l[k] < *lo ? l[k] : *lo;
        *hi = k == 0 || h[k] > *hi ? h[k] : *hi;
    }
    if (*lo == 0.0f)
        *lo = first_zero(x, PNANOVDB_LEAF_TABLE_COUNT);
    if (*hi == 0.0f)
        *hi = first_zero(x, PNANOVDB_LEAF_TABLE_COUNT);
    return bad || !(*lo >= floor_value);
}

/* The first active zero of a leaf's values (first_zero over its active
 * voxels). */
static float first_active_zero(const float *x, const uint32_t *mask)
{
    for (uint32_t n = 0; n < PNANOVDB_LEAF_TABLE_COUNT; ++n)
        if ((mask[n >> 5] >> (n & 31) & 1) && x[n] == 0.0f)
            return x[n];
    return 0.0f;
}

/* A partly active leaf: its active values' range and whether one of them is
 * out of range, as full_leaf_range gives a full leaf's (*lo = INFINITY,
 * *hi = -INFINITY when none is active); *stray: whether an inactive voxel
 * holds anything but bg (NaN included). Four voxels at a time, their mask
 * bits spread over the lanes, without a branch per voxel. */
static bool part_leaf_range(const float *x, const uint32_t *mask, float floor_value, float bg,
                            float *lo, float *hi, bool *stray)
{
    float l = INFINITY, h = -INFINITY;
    bool bad = false, off = false;
#ifdef __SSE2__
    const __m128i bit = _mm_set_epi32(8, 4, 2, 1);
    const __m128 inf = _mm_set1_ps(INFINITY), ninf = _mm_set1_ps(-INFINITY),
                 bgv = _mm_set1_ps(bg), zero = _mm_setzero_ps();
    __m128 l0 = inf, h0 = ninf, z0 = zero, s0 = zero;
    /* A word of the mask whose 32 voxels are all active or all inactive (most
     * of a sparse grid's partial leaves) takes the unmasked steps. */
    for (uint32_t n = 0; n < PNANOVDB_LEAF_TABLE_COUNT; n += 32) {
        uint32_t word = mask[n >> 5];
        if (word == 0xFFFFFFFFu) {
            for (uint32_t k = n; k < n + 32; k += 4) {
                __m128 v = _mm_loadu_ps(x + k);
                l0 = _mm_min_ps(v, l0);
                h0 = _mm_max_ps(v, h0);
                z0 = _mm_add_ps(z0, _mm_mul_ps(v, zero));
            }
        } else if (word == 0) {
            for (uint32_t k = n; k < n + 32; k += 4)
                s0 = _mm_or_ps(s0, _mm_cmpneq_ps(_mm_loadu_ps(x + k), bgv));
        } else {
            for (uint32_t k = n; k < n + 32; k += 4) {
                __m128i m = _mm_set1_epi32((int)(word >> (k & 31)));
                __m128 on = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(m, bit), bit));
                __m128 v = _mm_loadu_ps(x + k), va = _mm_and_ps(on, v);
                l0 = _mm_min_ps(_mm_or_ps(va, _mm_andnot_ps(on, inf)), l0);
                h0 = _mm_max_ps(_mm_or_ps(va, _mm_andnot_ps(on, ninf)), h0);
                z0 = _mm_add_ps(z0, _mm_mul_ps(va, zero));
                s0 = _mm_or_ps(s0, _mm_andnot_ps(on, _mm_cmpneq_ps(v, bgv)));
            }
        }
    }
    float lv[4], hv[4], zv[4];
    _mm_storeu_ps(lv, l0);
    _mm_storeu_ps(hv, h0);
    _mm_storeu_ps(zv, z0);
    for (int k = 0; k < 4; ++k) {
        bad = bad || zv[k] != 0.0f;
        l = lv[k] < l ? lv[k] : l;
        h = hv[k] > h ? hv[k] : h;
    }
    off = _mm_movemask_ps(s0) != 0;
    if (l == 0.0f)
        l = first_active_zero(x, mask);
    if (h == 0.0f)
        h = first_active_zero(x, mask);
#else
    for (uint32_t n = 0; n < PNANOVDB_LEAF_TABLE_COUNT; ++n) {
        if (!(mask[n >> 5] >> (n & 31) & 1)) {
            off = off || x[n] != bg;
            continue;
        }
        bad |= !(x[n] >= floor_value && x[n] <= FLT_MAX);
        l = x[n] < l ? x[n] : l;
        h = x[n] > h ? x[n] : h;
    }
#endif
    *lo = l;
    *hi = h;
    *stray = off;
    return bad || (l != INFINITY && !(l >= floor_value));
}

/* One leaf: its mask and value table copied out in two moves (the per-voxel
 * accessors cost 5 ns a voxel), inactive values folded, active ones checked
 * without a branch per voxel. */
static int leaf_values(values *v, pnanovdb_leaf_handle_t leaf, float *lo, float *hi, bool *any)
{
    uint32_t mask[PNANOVDB_LEAF_TABLE_COUNT / 32];
    float x[PNANOVDB_LEAF_TABLE_COUNT];
    uint64_t table = pnanovdb_leaf_get_table_address(v->c.type, v->c.buf, leaf, 0).byte_offset;
    memcpy(mask, v->data + leaf.address.byte_offset + PNANOVDB_LEAF_OFF_VALUE_MASK, sizeof mask);
    memcpy(x, v->data + table, sizeof x);
    const float floor_value = v->signed_ok ? -FLT_MAX : 0.0f;
    float l = INFINITY, h = -INFINITY;
    bool bad = false, a = false;
    uint32_t full = 0xFFFFFFFFu;
    for (uint32_t w = 0; w < PNANOVDB_LEAF_TABLE_COUNT / 32; ++w)
        full &= mask[w];
    if (full == 0xFFFFFFFFu) { /* most leaves of a dense grid: no voxel to fold */
        bad = full_leaf_range(x, floor_value, &l, &h);
        a = true;
    } else {
        bool stray = false;
        bad = part_leaf_range(x, mask, floor_value, v->bg, &l, &h, &stray);
        for (uint32_t w = 0; w < PNANOVDB_LEAF_TABLE_COUNT / 32; ++w)
            a = a || mask[w] != 0;
        for (uint32_t n = 0; stray && n < PNANOVDB_LEAF_TABLE_COUNT; ++n)
            if (!(mask[n >> 5] >> (n & 31) & 1) && x[n] != v->bg) {
                memcpy(v->data + table + 4 * (uint64_t)n, &v->bg, sizeof v->bg);
                v->folded++;
            }
    }
    if (bad)
        return leaf_bad_value(v, leaf, mask, x);
    pnanovdb_coord_t origin = pnanovdb_leaf_get_bbox_min(v->c.buf, leaf);
    if (stats_bound(v, pnanovdb_leaf_get_min_address(v->c.type, v->c.buf, leaf),
                    pnanovdb_leaf_get_max_address(v->c.type, v->c.buf, leaf), a, l, h, &origin,
                    "leaf") != 0)
        return -1;
    if (a) {
        *lo = *any ? fminf(*lo, l) : l;
        *hi = *any ? fmaxf(*hi, h) : h;
        *any = true;
    }
    return 0;
}

/* The leaves of the tree's leaf array, checked on every core before the
 * walk from the root: per leaf whether it failed, holds active values, and
 * their range. The walk takes these for the leaves it meets in the array
 * (a leaf elsewhere, which only a hostile file has, it checks itself), and
 * checks a failed leaf again for the message: the walk's order names the
 * first bad value, as a walk alone would. */
enum { LEAF_EMPTY, LEAF_ACTIVE, LEAF_BAD };
typedef struct {
    float lo, hi;
    uint8_t state;
} leaf_result;

typedef struct leaf_pass {
    values proto;
    uint64_t first, count, size; /* the leaf array: byte offset, leaves, bytes per leaf */
    leaf_result *out;
    nvdb_leaf_stats *stats; /* NULL: not asked for */
    nvdb_leaf_mask *masks;  /* with stats */
    atomic_uint_fast64_t next;
    atomic_uint_fast64_t folded;
} leaf_pass;

enum { LEAF_CHUNK = 256, LEAF_AHEAD = 2 };

/* A leaf's stored statistics and how much of it is active (its header,
 * which leaf_values has just read); a partly active leaf's mask into *mask. */
static nvdb_leaf_stats leaf_stats(const values *v, pnanovdb_leaf_handle_t leaf,
                                  nvdb_leaf_mask *mask)
{
    uint64_t slice[8], all = ~0ull, some = 0; /* bit 8 y + z of slice x: voxel (x, y, z) */
    memcpy(slice, v->data + leaf.address.byte_offset + PNANOVDB_LEAF_OFF_VALUE_MASK, sizeof slice);
    uint8_t xs = 0, ys = 0, zs = 0;
    for (int x = 0; x < 8; ++x) {
        all &= slice[x];
        some |= slice[x];
        xs |= (uint8_t)((slice[x] != 0) << x);
    }
    for (int y = 0; y < 8; ++y) {
        uint8_t row = (uint8_t)(some >> (8 * y));
        ys |= (uint8_t)((row != 0) << y);
        zs |= row;
    }
    if (some && all != ~0ull)
        memcpy(mask->slice, slice, sizeof slice);
    return (nvdb_leaf_stats){
        pnanovdb_read_float(v->c.buf, pnanovdb_leaf_get_min_address(v->c.type, v->c.buf, leaf)),
        pnanovdb_read_float(v->c.buf, pnanovdb_leaf_get_max_address(v->c.type, v->c.buf, leaf)),
        all == ~0ull ? NVDB_LEAF_ALL_ACTIVE
        : some       ? NVDB_LEAF_SOME_ACTIVE
                     : NVDB_LEAF_NONE_ACTIVE,
        xs, ys, zs};
}

static void *leaf_pass_worker(void *ctx)
{
    leaf_pass *p = ctx;
    values v = p->proto;
    char why[256];
    v.c.why = why;
    v.c.why_size = sizeof why;
    v.folded = 0;
    for (;;) {
        uint64_t i = atomic_fetch_add(&p->next, LEAF_CHUNK);
        if (i >= p->count)
            break;
        uint64_t end = i + LEAF_CHUNK < p->count ? i + LEAF_CHUNK : p->count;
        for (; i < end; ++i) {
            pnanovdb_leaf_handle_t leaf = {addr(p->first + i * p->size)};
            /* the leaf after next on its way from memory: leaves are 2 KiB,
             * and the hardware's prefetcher stops at each 4 KiB page */
            if (i + LEAF_AHEAD < p->count) {
                const uint8_t *next = v.data + p->first + (i + LEAF_AHEAD) * p->size;
                for (uint64_t o = 0; o < p->size; o += 64)
                    __builtin_prefetch(next + o);
            }
            float l = 0, h = 0;
            bool a = false;
            int st = leaf_values(&v, leaf, &l, &h, &a);
            p->out[i] = (leaf_result){l, h, st != 0 ? LEAF_BAD : a ? LEAF_ACTIVE : LEAF_EMPTY};
            if (p->stats)
                p->stats[i] = leaf_stats(&v, leaf, &p->masks[i]);
        }
    }
    atomic_fetch_add(&p->folded, v.folded);
    return NULL;
}

/* Runs the pass over the tree's leaf array, gathering each leaf's
 * statistics too when `stats`; false (and nothing done) when its results
 * cannot be held. */
static bool leaf_pass_run(leaf_pass *p, const values *v, bool stats)
{
    pnanovdb_tree_handle_t tree = pnanovdb_grid_get_tree(v->c.buf, (pnanovdb_grid_handle_t){addr(0)});
    p->proto = *v;
    p->count = pnanovdb_tree_get_node_count_leaf(v->c.buf, tree);
    p->size = PNANOVDB_GRID_TYPE_GET(v->c.type, leaf_size);
    p->first = tree.address.byte_offset + pnanovdb_tree_get_node_offset_leaf(v->c.buf, tree);
    atomic_init(&p->next, 0);
    atomic_init(&p->folded, 0);
    p->out = p->count ? malloc(p->count * sizeof *p->out) : NULL;
    p->stats = p->out && stats ? malloc(p->count * sizeof *p->stats) : NULL;
    p->masks = p->stats ? calloc(p->count, sizeof *p->masks) : NULL;
    if (!p->masks) {
        free(p->stats);
        p->stats = NULL;
    }
    if (!p->out)
        return false;
    /* A few thousand leaves take less than starting a thread. */
    hz_parallel_run(p->count < 16 * LEAF_CHUNK ? 1 : 0, leaf_pass_worker, p);
    return true;
}

/* A lower node's child leaf: from the pass when it lies in the leaf array. */
static int child_leaf_values(values *v, pnanovdb_leaf_handle_t leaf, float *lo, float *hi,
                             bool *any)
{
    const leaf_pass *p = v->pass;
    uint64_t at = leaf.address.byte_offset;
    if (!p || at < p->first || (at - p->first) % p->size != 0 || (at - p->first) / p->size >= p->count)
        return leaf_values(v, leaf, lo, hi, any);
    leaf_result r = p->out[(at - p->first) / p->size];
    if (r.state == LEAF_BAD)
        return leaf_values(v, leaf, lo, hi, any);
    if (r.state == LEAF_ACTIVE) {
        *lo = *any ? fminf(*lo, r.lo) : r.lo;
        *hi = *any ? fmaxf(*hi, r.hi) : r.hi;
        *any = true;
    }
    return 0;
}

static int lower_values(values *v, pnanovdb_lower_handle_t lower, float *lo, float *hi, bool *any)
{
    pnanovdb_coord_t origin = pnanovdb_lower_get_bbox_min(v->c.buf, lower);
    float l = 0, h = 0;
    bool a = false;
    uint32_t child = 0, value = 0;
    for (uint32_t n = 0; n < PNANOVDB_LOWER_TABLE_COUNT; ++n) {
        if (n % 32 == 0) {
            child = mask_word(v->c.buf, lower.address, PNANOVDB_LOWER_OFF_CHILD_MASK, n / 32);
            value = mask_word(v->c.buf, lower.address, PNANOVDB_LOWER_OFF_VALUE_MASK, n / 32);
        }
        if (child >> (n % 32) & 1u) {
            if (child_leaf_values(v, pnanovdb_lower_get_child(v->c.type, v->c.buf, lower, n), &l,
                                  &h, &a) != 0)
                return -1;
        } else if (value >> (n % 32) & 1u) {
            float x = pnanovdb_read_float(
                v->c.buf, pnanovdb_lower_get_table_address(v->c.type, v->c.buf, lower, n));
            if (take(v, x, &origin, "a tile value of the lower node at", &l, &h, &a) != 0)
                return -1;
        } else {
            fold_inactive(v, pnanovdb_lower_get_table_address(v->c.type, v->c.buf, lower, n),
                          8 * 8 * 8);
        }
    }
    if (stats_bound(v, pnanovdb_lower_get_min_address(v->c.type, v->c.buf, lower),
                    pnanovdb_lower_get_max_address(v->c.type, v->c.buf, lower), a, l, h, &origin,
                    "lower") != 0)
        return -1;
    if (a) {
        *lo = *any ? fminf(*lo, l) : l;
        *hi = *any ? fmaxf(*hi, h) : h;
        *any = true;
    }
    return 0;
}

static int upper_values(values *v, pnanovdb_upper_handle_t upper, float *lo, float *hi, bool *any)
{
    pnanovdb_coord_t origin = pnanovdb_upper_get_bbox_min(v->c.buf, upper);
    float l = 0, h = 0;
    bool a = false;
    for (uint32_t n = 0; n < PNANOVDB_UPPER_TABLE_COUNT; ++n) {
        if (pnanovdb_upper_get_child_mask(v->c.buf, upper, n)) {
            if (lower_values(v, pnanovdb_upper_get_child(v->c.type, v->c.buf, upper, n), &l, &h,
                             &a) != 0)
                return -1;
        } else if (pnanovdb_upper_get_value_mask(v->c.buf, upper, n)) {
            float x = pnanovdb_read_float(
                v->c.buf, pnanovdb_upper_get_table_address(v->c.type, v->c.buf, upper, n));
            if (take(v, x, &origin, "a tile value of the upper node at", &l, &h, &a) != 0)
                return -1;
        } else {
            fold_inactive(v, pnanovdb_upper_get_table_address(v->c.type, v->c.buf, upper, n),
                          128 * 128 * 128);
        }
    }
    if (stats_bound(v, pnanovdb_upper_get_min_address(v->c.type, v->c.buf, upper),
                    pnanovdb_upper_get_max_address(v->c.type, v->c.buf, upper), a, l, h, &origin,
                    "upper") != 0)
        return -1;
    if (a) {
        *lo = *any ? fminf(*lo, l) : l;
        *hi = *any ? fmaxf(*hi, h) : h;
        *any = true;
    }
    return 0;
}

/* The root's tiles and children, depth first. */
static int root_values(values *v, float *l, float *h, bool *a)
{
    pnanovdb_root_handle_t root =
        pnanovdb_tree_get_root(v->c.buf, pnanovdb_grid_get_tree(v->c.buf, (pnanovdb_grid_handle_t){addr(0)}));
    pnanovdb_coord_t nowhere = {0, 0, 0};
    uint32_t tiles = pnanovdb_root_get_tile_count(v->c.buf, root);
    for (uint32_t t = 0; t < tiles; ++t) {
        pnanovdb_root_tile_handle_t tile = pnanovdb_root_get_tile(v->c.type, root, t);
        if (pnanovdb_root_tile_get_child(v->c.buf, tile) != 0) {
            if (upper_values(v, pnanovdb_root_get_child(v->c.type, v->c.buf, root, tile), l, h,
                             a) != 0)
                return -1;
        } else if (pnanovdb_root_tile_get_state(v->c.buf, tile)) {
            float x = pnanovdb_read_float(v->c.buf,
                                          pnanovdb_root_tile_get_value_address(v->c.type, v->c.buf, tile));
            if (take(v, x, &nowhere, "a root tile value, given at", l, h, a) != 0)
                return -1;
        } else {
            fold_inactive(v, pnanovdb_root_tile_get_value_address(v->c.type, v->c.buf, tile),
                          (uint64_t)4096 * 4096 * 4096);
        }
    }
    return stats_bound(v, pnanovdb_root_get_min_address(v->c.type, v->c.buf, root),
                       pnanovdb_root_get_max_address(v->c.type, v->c.buf, root), *a, *l, *h,
                       &nowhere, "root");
}

int nvdb_check_float_values(void *data, uint64_t size, int nonnegative, float *vmin,
                            float *vmax, uint64_t *folded, nvdb_leaf_table *leaves, char *why,
                            size_t why_size)
{
    if (leaves)
        *leaves = (nvdb_leaf_table){NULL, NULL, 0, 0, 0};
    values v = {{pnanovdb_make_buf((pnanovdb_uint32_t *)data, size / 4), size,
                 PNANOVDB_GRID_TYPE_FLOAT, why, why_size, 0, 0, 0, 0, 0, 0},
                false, 0.0f, 0.0f, !nonnegative, data, 0.0f, 0, NULL};
    pnanovdb_grid_handle_t grid = {addr(0)};
    if (pnanovdb_grid_get_grid_type(v.c.buf, grid) != PNANOVDB_GRID_TYPE_FLOAT)
        return fail(&v.c, "not a float grid");
    pnanovdb_root_handle_t root = pnanovdb_tree_get_root(v.c.buf, pnanovdb_grid_get_tree(v.c.buf, grid));
    float bg = pnanovdb_read_float(
        v.c.buf, pnanovdb_address_offset(root.address,
                                         PNANOVDB_GRID_TYPE_GET(v.c.type, root_off_background)));
    pnanovdb_coord_t nowhere = {0, 0, 0};
    if (!isfinite(bg) || (nonnegative && !(bg >= 0.0f)))
        return bad_value(&v, bg, &nowhere, "the background, given at");
    v.bg = bg;
    leaf_pass pass;
    if (leaf_pass_run(&pass, &v, leaves != NULL))
        v.pass = &pass;
    float l = 0, h = 0;
    bool a = false;
    int st = root_values(&v, &l, &h, &a);
    if (v.pass) {
        v.folded += atomic_load(&pass.folded);
        free(pass.out);
        if (st == 0 && leaves && pass.stats) {
            *leaves = (nvdb_leaf_table){pass.stats, pass.masks, pass.first, pass.count, pass.size};
        } else {
            free(pass.stats);
            free(pass.masks);
        }
    }
    if (st != 0)
        return -1;
    *vmin = a ? l : 0.0f;
    *vmax = a ? h : 0.0f;
    *folded = v.folded;
    return 0;
}
