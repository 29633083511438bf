#include "media/grid.h"

#include "media/nvdb_check.h"

#include <assert.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FLOAT_GRID PNANOVDB_GRID_TYPE_FLOAT
#define VEC3_GRID PNANOVDB_GRID_TYPE_VEC3F

struct grid {
    vdb_buffer owned;
    pnanovdb_buf_t buf;
    pnanovdb_grid_handle_t handle;
    pnanovdb_root_handle_t root;
    uint32_t type;                        /* FLOAT_GRID or VEC3_GRID */
    /* Float grids: values; vec3 grids: lengths (background_vec is the vector). */
    float background, min_value, max_value;
    vec3 background_vec;
    bool empty;
    uint64_t inactive_folded; /* grid_inactive_folded */
    bool checked;             /* the value check ran: every inactive value is the background */
    nvdb_leaf_table leaves;   /* from the value check: what grid_blocks reads of each leaf */
    grid_ibox bounds;
    /* Trilinear lookups outside [min - 1, max + 1] are background: skip the tree. */
    vec3 support_lo, support_hi;
    transform world_from_index, index_from_world;
    char name[256];
};

static const char *nanovdb_type_name(uint32_t type)
{
    static const char *names[] = {"unknown", "float", "double", "int16",  "int32", "int64", "vec3f",
                                  "vec3d",   "mask",  "half",   "uint32", "bool",  "rgba8", "fp4",
                                  "fp8",     "fp16",  "fpn",    "vec4f",  "vec4d", "index"};
    return type < sizeof names / sizeof names[0] ? names[type] : "unknown";
}

static pnanovdb_coord_t coord(int32_t i, int32_t j, int32_t k)
{
    pnanovdb_coord_t c;
    c.x = i;
    c.y = j;
    c.z = k;
    return c;
}

/* Reads the map as double precision affine transforms (NanoVDB stores the 3x3
 * row-major: world = M index + t, index = M^-1 (world - t)). */
static void read_transforms(grid *g)
{
    pnanovdb_map_handle_t map = pnanovdb_grid_get_map(g->buf, g->handle);
    mat4 m = mat4_identity(), m_inv = mat4_identity();
    double t[3];
    for (int r = 0; r < 3; ++r)
        t[r] = pnanovdb_map_get_vecd(g->buf, map, (uint32_t)r);
    for (int r = 0; r < 3; ++r) {
        m.m[r][3] = t[r];
        double inv_t = 0.0;
        for (int c = 0; c < 3; ++c) {
            m.m[r][c] = pnanovdb_map_get_matd(g->buf, map, (uint32_t)(3 * r + c));
            m_inv.m[r][c] = pnanovdb_map_get_invmatd(g->buf, map, (uint32_t)(3 * r + c));
            inv_t -= m_inv.m[r][c] * t[c];
        }
        m_inv.m[r][3] = inv_t;
    }
    g->world_from_index = (transform){m, m_inv};
    g->index_from_world = (transform){m_inv, m};
}

static hz_status validate(const vdb_buffer *b, const char *name, hz_error *err)
{
    if (!b || !b->data || b->size < PNANOVDB_GRID_SIZE + PNANOVDB_TREE_SIZE)
        return hz_fail(err, "grid \"%s\": buffer too small to hold a NanoVDB grid", name);
    if ((uintptr_t)b->data % 8 != 0)
        return hz_fail(err, "grid \"%s\": NanoVDB buffer is not 8-byte aligned", name);
    pnanovdb_buf_t buf = pnanovdb_make_buf((uint32_t *)b->data, b->size / 4);
    pnanovdb_grid_handle_t h = {pnanovdb_address_null()};
    if (pnanovdb_grid_get_magic(buf, h) != PNANOVDB_MAGIC_NUMBER)
        return hz_fail(err, "grid \"%s\": not a NanoVDB grid (bad magic number)", name);
    uint32_t version = pnanovdb_grid_get_version(buf, h);
    if (pnanovdb_version_get_major(version) != PNANOVDB_MAJOR_VERSION_NUMBER)
        return hz_fail(err, "grid \"%s\": NanoVDB version %u.%u, expected %u.x", name,
                       pnanovdb_version_get_major(version), pnanovdb_version_get_minor(version),
                       PNANOVDB_MAJOR_VERSION_NUMBER);
    if (pnanovdb_grid_get_grid_size(buf, h) > b->size)
        return hz_fail(err, "grid \"%s\": NanoVDB grid larger than its buffer", name);
    uint32_t type = pnanovdb_grid_get_grid_type(buf, h);
    if (type != FLOAT_GRID && type != VEC3_GRID)
        return hz_fail(err, "grid \"%s\" is %s, expected float or vec3f", name,
                       nanovdb_type_name(type));
    char why[256];
    if (nvdb_check_tree(b->data, b->size, why, sizeof why) != 0)
        return hz_fail(err, "grid \"%s\" is corrupt (%s)", name, why);
    /* The majorant and the motion bounds come from the min/max statistics. */
    pnanovdb_tree_handle_t tree = pnanovdb_grid_get_tree(buf, h);
    if (pnanovdb_tree_get_voxel_count(buf, tree) > 0 &&
        !(pnanovdb_grid_get_flags(buf, h) & PNANOVDB_GRID_FLAGS_HAS_MIN_MAX))
        return hz_fail(err,
                       "grid \"%s\" has no min/max statistics (write the NanoVDB file with "
                       "statistics, or use the .vdb file)",
                       name);
    return HZ_OK;
}

/* A vec3f value stored at `addr` (three floats). */
static vec3 read_vec3(pnanovdb_buf_t buf, pnanovdb_address_t addr)
{
    return v3(pnanovdb_read_float(buf, addr),
              pnanovdb_read_float(buf, pnanovdb_address_offset(addr, 4)),
              pnanovdb_read_float(buf, pnanovdb_address_offset(addr, 8)));
}

hz_status grid_create_from_buffer(vdb_buffer *buf, const char *name, grid **out, hz_error *err)
{
    *out = NULL;
    if (!name)
        name = "";
    if (validate(buf, name, err) != HZ_OK)
        return HZ_ERROR;
    grid *g = calloc(1, sizeof *g);
    if (!g)
        return hz_fail(err, "grid \"%s\": out of memory", name);
    g->owned = *buf;
    snprintf(g->name, sizeof g->name, "%s", name);
    g->buf = pnanovdb_make_buf((uint32_t *)g->owned.data, g->owned.size / 4);
    g->handle.address = pnanovdb_address_null();
    g->root = pnanovdb_tree_get_root(g->buf, pnanovdb_grid_get_tree(g->buf, g->handle));
    g->type = pnanovdb_grid_get_grid_type(g->buf, g->handle);
    pnanovdb_address_t bg = pnanovdb_address_offset(
        g->root.address, PNANOVDB_GRID_TYPE_GET(g->type, root_off_background));
    pnanovdb_address_t lo_addr = pnanovdb_root_get_min_address(g->type, g->buf, g->root);
    pnanovdb_address_t hi_addr = pnanovdb_root_get_max_address(g->type, g->buf, g->root);
    if (g->type == VEC3_GRID) {
        /* NanoVDB's statistics of vectors are the shortest and longest value. */
        g->background_vec = read_vec3(g->buf, bg);
        g->background = (float)v3_length(g->background_vec);
        g->min_value = (float)v3_length(read_vec3(g->buf, lo_addr));
        g->max_value = (float)v3_length(read_vec3(g->buf, hi_addr));
    } else {
        g->background = pnanovdb_read_float(g->buf, bg);
        g->min_value = pnanovdb_read_float(g->buf, lo_addr);
        g->max_value = pnanovdb_read_float(g->buf, hi_addr);
    }
    pnanovdb_coord_t lo = pnanovdb_root_get_bbox_min(g->buf, g->root);
    pnanovdb_coord_t hi = pnanovdb_root_get_bbox_max(g->buf, g->root);
    g->empty =
        pnanovdb_tree_get_voxel_count(g->buf, pnanovdb_grid_get_tree(g->buf, g->handle)) == 0 ||
        lo.x > hi.x || lo.y > hi.y || lo.z > hi.z;
    g->bounds = (grid_ibox){{lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z}};
    if (g->empty) {
        g->support_lo = v3(1, 1, 1);
        g->support_hi = v3(0, 0, 0);
    } else {
        g->support_lo = v3(lo.x - 1.0, lo.y - 1.0, lo.z - 1.0);
        g->support_hi = v3(hi.x + 1.0, hi.y + 1.0, hi.z + 1.0);
    }
    read_transforms(g);
    *buf = (vdb_buffer){NULL, 0, NULL, 0};
    *out = g;
    return HZ_OK;
}

hz_status grid_load_set(const char *path, const grid_request *req, size_t n, grid **outs,
                        size_t *failed, hz_error *err)
{
    vdb_grid_request r[VDB_MAX_GRID_REQUESTS] = {{0}};
    vdb_buffer bufs[VDB_MAX_GRID_REQUESTS];
    int present[VDB_MAX_GRID_REQUESTS];
    *failed = 0;
    for (size_t i = 0; i < n; ++i)
        outs[i] = NULL;
    if (n > VDB_MAX_GRID_REQUESTS)
        return hz_fail(err, "%s: too many grids asked for at once", path);
    for (size_t i = 0; i < n; ++i)
        r[i] = (vdb_grid_request){req[i].name, req[i].type == GRID_VEC3 ? VDB_VEC3 : VDB_FLOAT,
                                  req[i].optional};
    char msg[sizeof err->message];
    if (vdb_load_grid_set(path, r, n, bufs, present, failed, msg, sizeof msg) != HZ_OK)
        return hz_fail(err, "%s", msg);
    for (size_t i = 0; i < n; ++i) {
        if (!present[i])
            continue;
        if (grid_create_from_buffer(&bufs[i], req[i].name, &outs[i], err) != HZ_OK) {
            *failed = i;
            for (size_t k = i; k < n; ++k)
                vdb_buffer_free(&bufs[k]);
            for (size_t k = 0; k < i; ++k) {
                grid_destroy(outs[k]);
                outs[k] = NULL;
            }
            return HZ_ERROR;
        }
    }
    return HZ_OK;
}

static hz_status load_one(const char *path, const char *gridname, grid_value_type type,
                          grid **out, hz_error *err)
{
    grid_request r = {gridname, type, false};
    size_t failed;
    return grid_load_set(path, &r, 1, out, &failed, err);
}

hz_status grid_load(const char *path, const char *gridname, grid **out, hz_error *err)
{
    return load_one(path, gridname, GRID_FLOAT, out, err);
}

hz_status grid_load_vec3(const char *path, const char *gridname, grid **out, hz_error *err)
{
    return load_one(path, gridname, GRID_VEC3, out, err);
}

grid_value_type grid_type(const grid *g) { return g->type == VEC3_GRID ? GRID_VEC3 : GRID_FLOAT; }

void grid_destroy(grid *g)
{
    if (!g)
        return;
    vdb_buffer_free(&g->owned);
    free(g->leaves.leaf);
    free(g->leaves.mask);
    free(g);
}

void grid_accessor_init(const grid *g, grid_accessor *a)
{
    pnanovdb_readaccessor_init(&a->acc, g->root);
}

transform grid_world_from_index_transform(const grid *g) { return g->world_from_index; }

vec3 grid_index_from_world(const grid *g, vec3 p_world)
{
    return transform_point(&g->index_from_world, p_world);
}

vec3 grid_world_from_index(const grid *g, vec3 p_index)
{
    return transform_point(&g->world_from_index, p_index);
}

float grid_voxel(const grid *g, grid_accessor *a, int32_t i, int32_t j, int32_t k)
{
    assert(g->type == FLOAT_GRID);
    pnanovdb_coord_t ijk = coord(i, j, k);
    pnanovdb_address_t addr =
        pnanovdb_readaccessor_get_value_address(FLOAT_GRID, g->buf, &a->acc, &ijk);
    return pnanovdb_read_float(g->buf, addr);
}

/* Outside [min - 1, max + 1] the trilinear field is the background. Written so
 * that NaN coordinates also land there. */
static inline bool outside_support(const grid *g, vec3 p)
{
    return !(p.x >= g->support_lo.x && p.x <= g->support_hi.x && p.y >= g->support_lo.y &&
             p.y <= g->support_hi.y && p.z >= g->support_lo.z && p.z <= g->support_hi.z);
}

/* floor(x) as an integer and x - floor(x), for x inside the support (so in
 * int32 range): the truncation, one less below zero where it rounded up.
 * The same values as floor() (a libm call without SSE4.1: 3 per lookup were
 * 12% of its instructions). */
static inline int32_t floor_frac(double x, double *frac)
{
    int32_t i = (int32_t)x;
    i -= x < (double)i;
    *frac = x - (double)i;
    return i;
}

/* The addresses of the eight voxels (i + dx, j + dy, k + dz), dx, dy, dz in
 * {0, 1}, of a trilinear lookup, corner c having dx = c & 1, dy = (c >> 1) & 1,
 * dz = c >> 2. The first corner is found through the accessor, which tells at
 * what level its value is stored: in a leaf (level 0), or as a tile covering
 * 8^3 (level 1), 128^3 (level 2) or 4096^3 (level 3, root tile or background)
 * voxels aligned to that size. When all eight corners lie in that leaf or tile
 * (most lookups), the others are offsets into the leaf's value table (leaf
 * offset x << 6 | y << 3 | z) or the same tile; else each goes through the
 * accessor. The values read are the same either way. One function per value
 * type (a macro), so that PNanoVDB's per-type offsets are constants: measured
 * 7-8% fewer instructions per plume render than one function taking the type. */
#define CORNER_ADDRESSES(name, type)                                                               \
    static void name(const grid *g, grid_accessor *a, int32_t i, int32_t j, int32_t k,            \
                     pnanovdb_address_t addr[8])                                                  \
    {                                                                                              \
        static const int32_t last[4] = {7, 7, 127, 4095};                                          \
        pnanovdb_coord_t ijk = coord(i, j, k);                                                     \
        pnanovdb_uint32_t level = 0;                                                               \
        addr[0] = pnanovdb_readaccessor_get_value_address_and_level(type, g->buf, &a->acc, &ijk,   \
                                                                    &level);                       \
        int32_t m = last[level < 4 ? level : 3];                                                   \
        if ((i & m) != m && (j & m) != m && (k & m) != m) {                                        \
            uint32_t n = (uint32_t)(i & 7) << 6 | (uint32_t)(j & 7) << 3 | (uint32_t)(k & 7);      \
            for (uint32_t c = 1; c < 8; ++c)                                                       \
                addr[c] = level > 0 ? addr[0]                                                      \
                                    : pnanovdb_leaf_get_table_address(                             \
                                          type, g->buf, a->acc.leaf,                               \
                                          n + ((c & 1u) << 6) + ((c & 2u) << 2) + (c >> 2));       \
            return;                                                                                \
        }                                                                                          \
        /* The corners lie in up to 8 aligned 8^3 blocks (leaves, or tiles                      \
         * whose value covers the block): one tree lookup per block, then                      \
         * offsets in its leaf. */                                                               \
        const int bx = (i & 7) == 7, by = ((j & 7) == 7) << 1, bz = ((k & 7) == 7) << 2;          \
        pnanovdb_uint32_t blevel[8];                                                             \
        pnanovdb_leaf_handle_t bleaf[8];                                                         \
        pnanovdb_address_t baddr[8];                                                             \
        bool done[8] = {true, false, false, false, false, false, false, false};                  \
        blevel[0] = level;                                                                       \
        bleaf[0] = a->acc.leaf;                                                                  \
        baddr[0] = addr[0];                                                                      \
        for (int c = 1; c < 8; ++c) {                                                            \
            int32_t ci = i + (c & 1), cj = j + ((c >> 1) & 1), ck = k + (c >> 2);                 \
            int b = ((c & 1) & bx) | (c & 2 & by) | (c & 4 & bz);                                 \
            if (!done[b]) {                                                                      \
                ijk = coord(ci, cj, ck);                                                         \
                baddr[b] = pnanovdb_readaccessor_get_value_address_and_level(                    \
                    type, g->buf, &a->acc, &ijk, &blevel[b]);                                    \
                bleaf[b] = a->acc.leaf;                                                          \
                done[b] = true;                                                                  \
                addr[c] = baddr[b];                                                              \
                continue;                                                                        \
            }                                                                                    \
            addr[c] = blevel[b] > 0 ? baddr[b]                                                   \
                                    : pnanovdb_leaf_get_table_address(                           \
                                          type, g->buf, bleaf[b],                                \
                                          (uint32_t)(ci & 7) << 6 | (uint32_t)(cj & 7) << 3 |     \
                                              (uint32_t)(ck & 7));                               \
        }                                                                                        \
    }

CORNER_ADDRESSES(float_corners, FLOAT_GRID)
CORNER_ADDRESSES(vec3_corners, VEC3_GRID)

double grid_density_index(const grid *g, grid_accessor *a, vec3 p)
{
    assert(g->type == FLOAT_GRID);
    if (outside_support(g, p))
        return g->background;
    double tx, ty, tz;
    int32_t i = floor_frac(p.x, &tx), j = floor_frac(p.y, &ty), k = floor_frac(p.z, &tz);
    pnanovdb_address_t addr[8];
    float_corners(g, a, i, j, k, addr);
    double v[8];
    for (int c = 0; c < 8; ++c)
        v[c] = pnanovdb_read_float(g->buf, addr[c]);
    double y0 = hz_lerp(ty, hz_lerp(tx, v[0], v[1]), hz_lerp(tx, v[2], v[3]));
    double y1 = hz_lerp(ty, hz_lerp(tx, v[4], v[5]), hz_lerp(tx, v[6], v[7]));
    return hz_lerp(tz, y0, y1);
}

vec3 grid_vec3_voxel(const grid *g, grid_accessor *a, int32_t i, int32_t j, int32_t k)
{
    assert(g->type == VEC3_GRID);
    pnanovdb_coord_t ijk = coord(i, j, k);
    return read_vec3(g->buf,
                     pnanovdb_readaccessor_get_value_address(VEC3_GRID, g->buf, &a->acc, &ijk));
}

vec3 grid_vec3_index(const grid *g, grid_accessor *a, vec3 p)
{
    assert(g->type == VEC3_GRID);
    if (outside_support(g, p))
        return g->background_vec;
    double tx, ty, tz;
    int32_t i = floor_frac(p.x, &tx), j = floor_frac(p.y, &ty), k = floor_frac(p.z, &tz);
    pnanovdb_address_t addr[8];
    vec3_corners(g, a, i, j, k, addr);
    vec3 v[8];
    for (int c = 0; c < 8; ++c)
        v[c] = read_vec3(g->buf, addr[c]);
    vec3 y0 = v3_lerp(ty, v3_lerp(tx, v[0], v[1]), v3_lerp(tx, v[2], v[3]));
    vec3 y1 = v3_lerp(ty, v3_lerp(tx, v[4], v[5]), v3_lerp(tx, v[6], v[7]));
    return v3_lerp(tz, y0, y1);
}

bool grid_index_bounds(const grid *g, grid_ibox *out)
{
    *out = g->bounds;
    return !g->empty;
}

bool grid_support_bounds(const grid *g, vec3 *lo, vec3 *hi)
{
    *lo = g->support_lo;
    *hi = g->support_hi;
    return !g->empty;
}

float grid_max_value(const grid *g) { return g->max_value; }
float grid_min_value(const grid *g) { return g->min_value; }

static hz_status check_values(grid *g, int nonnegative, hz_error *err)
{
    float lo, hi;
    char why[512];
    free(g->leaves.leaf);
    free(g->leaves.mask);
    if (nvdb_check_float_values(g->owned.data, g->owned.size, nonnegative, &lo, &hi,
                                &g->inactive_folded, &g->leaves, why, sizeof why) != 0)
        return hz_fail(err, "%s", why);
    g->min_value = lo;
    g->max_value = hi;
    g->checked = true;
    return HZ_OK;
}

void grid_drop_leaf_stats(grid *g)
{
    free(g->leaves.leaf);
    free(g->leaves.mask);
    g->leaves = (nvdb_leaf_table){NULL, NULL, 0, 0, 0};
}

hz_status grid_check_density(grid *g, hz_error *err) { return check_values(g, 1, err); }
hz_status grid_check_finite(grid *g, hz_error *err) { return check_values(g, 0, err); }
float grid_background(const grid *g) { return g->background; }
size_t grid_buffer_bytes(const grid *g) { return g->owned.size; }
uint64_t grid_inactive_folded(const grid *g) { return g->inactive_folded; }

const char *grid_name(const grid *g) { return g->name; }

uint64_t grid_active_voxel_count(const grid *g)
{
    return pnanovdb_tree_get_voxel_count(g->buf, pnanovdb_grid_get_tree(g->buf, g->handle));
}

/* ---- node statistics ---------------------------------------------------- */

int32_t grid_level_dim(grid_level level)
{
    switch (level) {
    case GRID_LEAF: return 8;
    case GRID_LOWER: return 128;
    case GRID_UPPER: return 4096;
    }
    assert(!"unknown grid level");
    return 0;
}

/* Largest multiple of dim (a power of two) <= v, without relying on >> of negatives. */
static int32_t align_down(int32_t v, int32_t dim)
{
    int64_t q = v >= 0 ? (int64_t)v / dim : -(((int64_t)-v + dim - 1) / dim);
    return (int32_t)(q * dim);
}

static grid_node constant_node(grid_node_kind kind, float value, grid_level level,
                               pnanovdb_coord_t ijk)
{
    int32_t dim = grid_level_dim(level);
    return (grid_node){kind,
                       {align_down(ijk.x, dim), align_down(ijk.y, dim), align_down(ijk.z, dim)},
                       dim,
                       value,
                       value};
}

static grid_node stats_node(const grid *g, pnanovdb_address_t min_addr, pnanovdb_address_t max_addr,
                            grid_level level, pnanovdb_coord_t ijk)
{
    grid_node n = constant_node(GRID_NODE_CHILD, 0.0f, level, ijk);
    n.min = pnanovdb_read_float(g->buf, min_addr);
    n.max = pnanovdb_read_float(g->buf, max_addr);
    return n;
}

grid_node grid_node_at(const grid *g, grid_level level, int32_t i, int32_t j, int32_t k)
{
    assert(g->type == FLOAT_GRID);
    pnanovdb_coord_t ijk = coord(i, j, k);
    pnanovdb_buf_t buf = g->buf;
    pnanovdb_root_tile_handle_t tile = pnanovdb_root_find_tile(FLOAT_GRID, buf, g->root, &ijk);
    if (pnanovdb_address_is_null(tile.address))
        return constant_node(GRID_NODE_BACKGROUND, g->background, level, ijk);
    if (pnanovdb_int64_is_zero(pnanovdb_root_tile_get_child(buf, tile)))
        return constant_node(
            GRID_NODE_TILE,
            pnanovdb_read_float(buf, pnanovdb_root_tile_get_value_address(FLOAT_GRID, buf, tile)),
            level, ijk);
    pnanovdb_upper_handle_t upper = pnanovdb_root_get_child(FLOAT_GRID, buf, g->root, tile);
    if (level == GRID_UPPER)
        return stats_node(g, pnanovdb_upper_get_min_address(FLOAT_GRID, buf, upper),
                          pnanovdb_upper_get_max_address(FLOAT_GRID, buf, upper), level, ijk);
    uint32_t n = pnanovdb_upper_coord_to_offset(&ijk);
    if (!pnanovdb_upper_get_child_mask(buf, upper, n))
        return constant_node(
            GRID_NODE_TILE,
            pnanovdb_read_float(buf, pnanovdb_upper_get_table_address(FLOAT_GRID, buf, upper, n)),
            level, ijk);
    pnanovdb_lower_handle_t lower = pnanovdb_upper_get_child(FLOAT_GRID, buf, upper, n);
    if (level == GRID_LOWER)
        return stats_node(g, pnanovdb_lower_get_min_address(FLOAT_GRID, buf, lower),
                          pnanovdb_lower_get_max_address(FLOAT_GRID, buf, lower), level, ijk);
    n = pnanovdb_lower_coord_to_offset(&ijk);
    if (!pnanovdb_lower_get_child_mask(buf, lower, n))
        return constant_node(
            GRID_NODE_TILE,
            pnanovdb_read_float(buf, pnanovdb_lower_get_table_address(FLOAT_GRID, buf, lower, n)),
            level, ijk);
    pnanovdb_leaf_handle_t leaf = pnanovdb_lower_get_child(FLOAT_GRID, buf, lower, n);
    return stats_node(g, pnanovdb_leaf_get_min_address(FLOAT_GRID, buf, leaf),
                      pnanovdb_leaf_get_max_address(FLOAT_GRID, buf, leaf), level, ijk);
}

/* The child-table index range [lo, hi] (per axis) of a node at `origin` whose
 * children span `child_dim` voxels, restricted to `box`. False when disjoint. */
static bool child_range(const int32_t origin[3], int32_t node_dim, int32_t child_dim, grid_ibox box,
                        int32_t lo[3], int32_t hi[3])
{
    for (int a = 0; a < 3; ++a) {
        int64_t first = (int64_t)origin[a], last = first + node_dim - 1;
        if (box.max[a] < first || box.min[a] > last)
            return false;
        int64_t b0 = box.min[a] > first ? box.min[a] : first;
        int64_t b1 = box.max[a] < last ? box.max[a] : last;
        lo[a] = (int32_t)((b0 - first) / child_dim);
        hi[a] = (int32_t)((b1 - first) / child_dim);
    }
    return true;
}

/* Bounds of the values in a region, and how many of its voxels stored nodes
 * and tiles cover (the rest reads the background). */
typedef struct {
    float min, max;
    int64_t covered;
} region_range;

/* fminf and fmaxf (a NaN operand gives the other), inline: the libm calls
 * were a seventh of a majorant build of a sparse grid. */
static float min_of(float a, float b) { return a < b || b != b ? a : b; }
static float max_of(float a, float b) { return a > b || b != b ? a : b; }

static void range_add(region_range *r, float lo, float hi)
{
    r->min = min_of(r->min, lo);
    r->max = max_of(r->max, hi);
}

/* Voxels of `box` inside the node of edge `dim` at `origin`. */
static int64_t overlap_voxels(const int32_t origin[3], int32_t dim, grid_ibox box)
{
    int64_t n = 1;
    for (int a = 0; a < 3; ++a) {
        int64_t lo = box.min[a] > origin[a] ? box.min[a] : origin[a];
        int64_t hi = box.max[a] < (int64_t)origin[a] + dim - 1 ? box.max[a]
                                                               : (int64_t)origin[a] + dim - 1;
        if (hi < lo)
            return 0;
        n *= hi - lo + 1;
    }
    return n;
}

static bool leaf_fully_active(pnanovdb_buf_t buf, pnanovdb_leaf_handle_t leaf)
{
    for (uint32_t w = 0; w < 16; ++w)
        if (pnanovdb_read_uint32(buf, pnanovdb_address_offset(leaf.address,
                                                              PNANOVDB_LEAF_OFF_VALUE_MASK + 4u * w)) !=
            0xFFFFFFFFu)
            return false;
    return true;
}

static void lower_region_range(const grid *g, pnanovdb_lower_handle_t lower, const int32_t origin[3],
                               grid_ibox box, region_range *r)
{
    int32_t lo[3], hi[3];
    if (!child_range(origin, 128, 8, box, lo, hi))
        return;
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
            for (int32_t z = lo[2]; z <= hi[2]; ++z) {
                uint32_t n = (uint32_t)((x << 8) | (y << 4) | z);
                int32_t child_origin[3] = {origin[0] + 8 * x, origin[1] + 8 * y, origin[2] + 8 * z};
                r->covered += overlap_voxels(child_origin, 8, box);
                if (pnanovdb_lower_get_child_mask(g->buf, lower, n)) {
                    pnanovdb_leaf_handle_t leaf =
                        pnanovdb_lower_get_child(FLOAT_GRID, g->buf, lower, n);
                    float vmin = pnanovdb_read_float(
                        g->buf, pnanovdb_leaf_get_min_address(FLOAT_GRID, g->buf, leaf));
                    float vmax = pnanovdb_read_float(
                        g->buf, pnanovdb_leaf_get_max_address(FLOAT_GRID, g->buf, leaf));
                    /* Statistics cover active voxels; the others hold the background. */
                    if (!leaf_fully_active(g->buf, leaf))
                        vmin = min_of(vmin, g->background);
                    range_add(r, vmin, vmax);
                } else {
                    float v = pnanovdb_read_float(
                        g->buf, pnanovdb_lower_get_table_address(FLOAT_GRID, g->buf, lower, n));
                    range_add(r, v, v);
                }
            }
}

static void upper_region_range(const grid *g, pnanovdb_upper_handle_t upper, const int32_t origin[3],
                               grid_ibox box, region_range *r)
{
    int32_t lo[3], hi[3];
    if (!child_range(origin, 4096, 128, box, lo, hi))
        return;
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
            for (int32_t z = lo[2]; z <= hi[2]; ++z) {
                uint32_t n = (uint32_t)((x << 10) | (y << 5) | z);
                int32_t child_origin[3] = {origin[0] + 128 * x, origin[1] + 128 * y,
                                           origin[2] + 128 * z};
                if (pnanovdb_upper_get_child_mask(g->buf, upper, n)) {
                    pnanovdb_lower_handle_t lower =
                        pnanovdb_upper_get_child(FLOAT_GRID, g->buf, upper, n);
                    lower_region_range(g, lower, child_origin, box, r);
                } else {
                    float v = pnanovdb_read_float(
                        g->buf, pnanovdb_upper_get_table_address(FLOAT_GRID, g->buf, upper, n));
                    range_add(r, v, v);
                    r->covered += overlap_voxels(child_origin, 128, box);
                }
            }
}

/* Inverse of pnanovdb_coord_to_key (64-bit keys): 21 bits per axis, x highest. */
static int32_t key_axis(uint64_t key, int shift)
{
    uint32_t bits = (uint32_t)((key >> shift) & 0x1FFFFFu);
    return (int32_t)(bits << 12);
}

/* Root tile t (a 4096^3 child or tile), its first voxel, and whether it
 * overlaps `box`. */
static bool root_tile_overlaps(const grid *g, uint32_t t, grid_ibox box,
                               pnanovdb_root_tile_handle_t *tile, int32_t origin[3])
{
    *tile = pnanovdb_root_get_tile(FLOAT_GRID, g->root, t);
    uint64_t key = pnanovdb_root_tile_get_key(g->buf, *tile);
    origin[0] = key_axis(key, 42);
    origin[1] = key_axis(key, 21);
    origin[2] = key_axis(key, 0);
    int32_t lo[3], hi[3];
    return child_range(origin, 4096, 4096, box, lo, hi);
}

void grid_region_range(const grid *g, grid_ibox box, float *min, float *max)
{
    assert(g->type == FLOAT_GRID);
    region_range r = {INFINITY, -INFINITY, 0};
    uint32_t count = pnanovdb_root_get_tile_count(g->buf, g->root);
    for (uint32_t t = 0; t < count; ++t) {
        pnanovdb_root_tile_handle_t tile;
        int32_t origin[3];
        if (!root_tile_overlaps(g, t, box, &tile, origin))
            continue;
        if (pnanovdb_int64_is_zero(pnanovdb_root_tile_get_child(g->buf, tile))) {
            float v = pnanovdb_read_float(
                g->buf, pnanovdb_root_tile_get_value_address(FLOAT_GRID, g->buf, tile));
            range_add(&r, v, v);
            r.covered += overlap_voxels(origin, 4096, box);
        } else {
            pnanovdb_upper_handle_t upper =
                pnanovdb_root_get_child(FLOAT_GRID, g->buf, g->root, tile);
            upper_region_range(g, upper, origin, box, &r);
        }
    }
    /* Saturating: a box spanning most of index space holds more than 2^63
     * voxels, and no tree covers that many. */
    int64_t volume = 1;
    for (int a = 0; a < 3; ++a) {
        int64_t side = box.max[a] >= box.min[a] ? (int64_t)box.max[a] - box.min[a] + 1 : 0;
        volume = side != 0 && volume > INT64_MAX / side ? INT64_MAX : volume * side;
    }
    /* Voxels no node or tile covers read the background. */
    if (r.covered < volume || volume == 0)
        range_add(&r, g->background, g->background);
    *min = r.min;
    *max = r.max;
}

/* ---- where a region may be non-zero ---- */

static void support_add(grid_ibox *acc, bool *any, const int64_t lo[3], const int64_t hi[3])
{
    for (int a = 0; a < 3; ++a) {
        if (!*any || lo[a] < acc->min[a])
            acc->min[a] = (int32_t)lo[a];
        if (!*any || hi[a] > acc->max[a])
            acc->max[a] = (int32_t)hi[a];
    }
    *any = true;
}

/* A node or tile of edge `dim` at `origin`, constant over its voxels of `box`. */
static void support_add_block(const int32_t origin[3], int32_t dim, grid_ibox box, grid_ibox *acc,
                              bool *any)
{
    int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = box.min[a] > origin[a] ? box.min[a] : origin[a];
        hi[a] = box.max[a] < (int64_t)origin[a] + dim - 1 ? box.max[a] : (int64_t)origin[a] + dim - 1;
        if (hi[a] < lo[a])
            return;
    }
    support_add(acc, any, lo, hi);
}

static int lowest_bit(uint32_t m) { return __builtin_ctz(m); }
static int highest_bit(uint32_t m) { return 31 - __builtin_clz(m); }

/* Bits of the voxels (y, z) with y in [y0, y1] and z in [z0, z1] in one x
 * slice of a leaf's mask (bit 8 y + z). */
static uint64_t leaf_yz_mask(int y0, int y1, int z0, int z1)
{
    uint64_t zbits = ((1ull << (z1 + 1)) - 1) & ~((1ull << z0) - 1), m = 0;
    for (int y = y0; y <= y1; ++y)
        m |= zbits << (8 * y);
    return m;
}

/* The index of the leaf at byte offset `at` in the value check's table, or
 * UINT32_MAX. Once per block of every brick the majorant grid bounds: the
 * quotient by a multiplication, corrected to the exact one, not a 64-bit
 * division (tens of cycles). */
static uint32_t leaf_stats_index(const grid *g, uint64_t at)
{
    const nvdb_leaf_table *t = &g->leaves;
    if (!t->leaf || at < t->first || t->stride == 0)
        return UINT32_MAX;
    uint64_t d = at - t->first;
    uint64_t i = (uint64_t)((double)d * (1.0 / (double)t->stride));
    while (i > 0 && i * t->stride > d)
        --i;
    while ((i + 1) * t->stride <= d)
        ++i;
    if (i * t->stride != d || i >= t->count || i >= UINT32_MAX)
        return UINT32_MAX;
    return (uint32_t)i;
}

static const nvdb_leaf_stats *stats_at(const grid *g, uint32_t i)
{
    return i == UINT32_MAX ? NULL : &g->leaves.leaf[i];
}

/* When the check's table says where a leaf's active voxels lie and the
 * window r0 .. r1 (per axis, in the leaf) holds all of them or none:
 * true, having added their bounding box (what the mask scan would find). */
static bool leaf_support_from_stats(const nvdb_leaf_stats *s, const int32_t origin[3],
                                    const int r0[3], const int r1[3], grid_ibox *acc, bool *any)
{
    if (!s)
        return false;
    const uint8_t bits[3] = {s->xs, s->ys, s->zs};
    int64_t lo[3], hi[3];
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
        if (!bits[a])
            return true; /* no active voxel */
        int first = lowest_bit(bits[a]), last = highest_bit(bits[a]);
        if (last < r0[a] || first > r1[a])
            return true; /* none inside the window */
        inside = inside && first >= r0[a] && last <= r1[a];
        lo[a] = origin[a] + first;
        hi[a] = origin[a] + last;
    }
    if (inside)
        support_add(acc, any, lo, hi);
    return inside;
}

/* The active voxels of a leaf inside `box`, from its value mask (bit
 * 64 x + 8 y + z is voxel origin + (x, y, z)); `si`: its entry in the value
 * check's table (UINT32_MAX: none). */
static void leaf_support(const grid *g, pnanovdb_leaf_handle_t leaf, uint32_t si,
                         const int32_t origin[3], grid_ibox box, grid_ibox *acc, bool *any)
{
    const nvdb_leaf_stats *s = stats_at(g, si);
    int r0[3], r1[3];
    for (int a = 0; a < 3; ++a) {
        int64_t lo = (int64_t)box.min[a] - origin[a], hi = (int64_t)box.max[a] - origin[a];
        r0[a] = lo < 0 ? 0 : (int)lo;
        r1[a] = hi > 7 ? 7 : (int)hi;
        if (r1[a] < r0[a])
            return;
    }
    if (leaf_support_from_stats(s, origin, r0, r1, acc, any))
        return;
    uint64_t yz = leaf_yz_mask(r0[1], r1[1], r0[2], r1[2]), all = 0;
    uint32_t xs = 0;
    for (int x = r0[0]; x <= r1[0]; ++x) {
        uint64_t slice;
        if (s && s->active == NVDB_LEAF_SOME_ACTIVE) { /* the check kept its mask */
            slice = g->leaves.mask[si].slice[x] & yz;
        } else {
            pnanovdb_address_t at = pnanovdb_address_offset(
                leaf.address, PNANOVDB_LEAF_OFF_VALUE_MASK + 8u * (uint32_t)x);
            slice = ((uint64_t)pnanovdb_read_uint32(g->buf, pnanovdb_address_offset(at, 4u)) << 32 |
                     pnanovdb_read_uint32(g->buf, at)) &
                    yz;
        }
        if (slice) {
            xs |= 1u << x;
            all |= slice;
        }
    }
    if (!xs)
        return;
    uint32_t ys = 0, zs = 0;
    for (int y = 0; y < 8; ++y) {
        uint32_t byte = (uint32_t)(all >> (8 * y)) & 0xFFu;
        if (byte)
            ys |= 1u << y;
        zs |= byte;
    }
    const int64_t lo[3] = {origin[0] + lowest_bit(xs), origin[1] + lowest_bit(ys),
                           origin[2] + lowest_bit(zs)};
    const int64_t hi[3] = {origin[0] + highest_bit(xs), origin[1] + highest_bit(ys),
                           origin[2] + highest_bit(zs)};
    support_add(acc, any, lo, hi);
}

/* The children of an internal node (GRID_LOWER: 16^3 leaves of 8^3 voxels;
 * GRID_UPPER: 32^3 lower nodes of 128^3) that overlap `box`. */
static void internal_support(const grid *g, grid_level level, pnanovdb_address_t node,
                             const int32_t origin[3], grid_ibox box, grid_ibox *acc, bool *any)
{
    bool upper = level == GRID_UPPER;
    int32_t child_dim = upper ? 128 : 8, shift = upper ? 5 : 4;
    int32_t lo[3], hi[3];
    if (!child_range(origin, child_dim << shift, child_dim, box, lo, hi))
        return;
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
            for (int32_t z = lo[2]; z <= hi[2]; ++z) {
                uint32_t n = (uint32_t)((x << (2 * shift)) | (y << shift) | z);
                int32_t child_origin[3] = {origin[0] + child_dim * x, origin[1] + child_dim * y,
                                           origin[2] + child_dim * z};
                pnanovdb_upper_handle_t up = {node};
                pnanovdb_lower_handle_t low = {node};
                if (upper ? pnanovdb_upper_get_child_mask(g->buf, up, n)
                          : pnanovdb_lower_get_child_mask(g->buf, low, n)) {
                    if (upper)
                        internal_support(g, GRID_LOWER,
                                         pnanovdb_upper_get_child(FLOAT_GRID, g->buf, up, n).address,
                                         child_origin, box, acc, any);
                    else {
                        pnanovdb_leaf_handle_t leaf =
                            pnanovdb_lower_get_child(FLOAT_GRID, g->buf, low, n);
                        leaf_support(g, leaf,
                                     leaf_stats_index(g, leaf.address.byte_offset),
                                     child_origin, box, acc, any);
                    }
                    continue;
                }
                pnanovdb_address_t tile =
                    upper ? pnanovdb_upper_get_table_address(FLOAT_GRID, g->buf, up, n)
                          : pnanovdb_lower_get_table_address(FLOAT_GRID, g->buf, low, n);
                if (pnanovdb_read_float(g->buf, tile) != 0.0f)
                    support_add_block(child_origin, child_dim, box, acc, any);
            }
}

bool grid_region_support(const grid *g, grid_ibox box, grid_ibox *out)
{
    assert(g->type == FLOAT_GRID);
    if (g->background != 0.0f) {
        *out = box;
        return true;
    }
    bool any = false;
    uint32_t count = pnanovdb_root_get_tile_count(g->buf, g->root);
    for (uint32_t t = 0; t < count; ++t) {
        pnanovdb_root_tile_handle_t tile;
        int32_t origin[3];
        if (!root_tile_overlaps(g, t, box, &tile, origin))
            continue;
        if (pnanovdb_int64_is_zero(pnanovdb_root_tile_get_child(g->buf, tile))) {
            if (pnanovdb_read_float(g->buf, pnanovdb_root_tile_get_value_address(
                                                FLOAT_GRID, g->buf, tile)) != 0.0f)
                support_add_block(origin, 4096, box, out, &any);
        } else {
            internal_support(g, GRID_UPPER,
                             pnanovdb_root_get_child(FLOAT_GRID, g->buf, g->root, tile).address,
                             origin, box, out, &any);
        }
    }
    return any;
}

/* ---- the tree per block of 8^3 voxels ---- */

static grid_block tile_block(float v)
{
    return (grid_block){v, v, 0, UINT32_MAX, v != 0.0f ? GRID_BLOCK_FULL : GRID_BLOCK_ZERO};
}

/* A leaf of stored statistics vmin, vmax as lower_region_range and
 * leaf_support see it. */
static grid_block leaf_block_of(const grid *g, uint64_t leaf, uint32_t stats, float vmin,
                                float vmax, bool all, bool some)
{
    if (!all) /* statistics cover active voxels; the others hold the background */
        vmin = min_of(vmin, g->background);
    return (grid_block){vmin, vmax, leaf, stats,
                        all    ? GRID_BLOCK_FULL
                        : some ? GRID_BLOCK_PARTIAL
                               : GRID_BLOCK_ZERO};
}

/* A leaf as lower_region_range and leaf_support see it: from what the value
 * check gathered when the leaf lies in the leaf array (not touching the
 * leaf), else from the leaf itself. */
static grid_block leaf_block(const grid *g, pnanovdb_leaf_handle_t leaf)
{
    uint64_t at = leaf.address.byte_offset;
    uint32_t i = leaf_stats_index(g, at);
    const nvdb_leaf_stats *s = stats_at(g, i);
    if (s) {
        return leaf_block_of(g, at, i, s->min, s->max, s->active == NVDB_LEAF_ALL_ACTIVE,
                             s->active != NVDB_LEAF_NONE_ACTIVE);
    }
    uint32_t all = 0xFFFFFFFFu, some = 0;
    for (uint32_t i = 0; i < 16; ++i) {
        uint32_t m = pnanovdb_read_uint32(
            g->buf, pnanovdb_address_offset(leaf.address, PNANOVDB_LEAF_OFF_VALUE_MASK + 4u * i));
        all &= m;
        some |= m;
    }
    float vmin = pnanovdb_read_float(g->buf, pnanovdb_leaf_get_min_address(FLOAT_GRID, g->buf, leaf));
    float vmax = pnanovdb_read_float(g->buf, pnanovdb_leaf_get_max_address(FLOAT_GRID, g->buf, leaf));
    return leaf_block_of(g, at, UINT32_MAX, vmin, vmax, all == 0xFFFFFFFFu, some != 0);
}

/* Calls fn with the blocks [lo, hi] of `blocks` that the node or tile of
 * edge `dim` at `origin` covers, when there are any. */
static inline __attribute__((always_inline)) void
visit_node(grid_ibox blocks, const int32_t origin[3], int32_t dim, grid_block b,
           grid_block_fn fn, void *ctx)
{
    int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        int64_t b0 = (int64_t)origin[a] / 8, b1 = b0 + dim / 8 - 1; /* origin: a multiple of 8 */
        lo[a] = b0 > blocks.min[a] ? b0 : blocks.min[a];
        hi[a] = b1 < blocks.max[a] ? b1 : blocks.max[a];
        if (hi[a] < lo[a])
            return;
    }
    fn(ctx, lo, hi, b);
}

/* Child n of a lower node (block b): a leaf, or a tile. */
static inline __attribute__((always_inline)) void
visit_lower_child(const grid *g, pnanovdb_lower_handle_t lower, uint32_t n, const int64_t b[3],
                  grid_block_fn fn, void *ctx)
{
    grid_block gb =
        pnanovdb_lower_get_child_mask(g->buf, lower, n)
            ? leaf_block(g, pnanovdb_lower_get_child(FLOAT_GRID, g->buf, lower, n))
        : g->checked && !pnanovdb_lower_get_value_mask(g->buf, lower, n)
            ? tile_block(g->background) /* the mask, not the value table */
            : tile_block(pnanovdb_read_float(
                  g->buf, pnanovdb_lower_get_table_address(FLOAT_GRID, g->buf, lower, n)));
    fn(ctx, b, b, gb);
}

/* Word w of the child mask or'ed with the value mask of a node (off: the
 * node's child mask; its value mask follows at value_off). */
static inline uint32_t node_word(pnanovdb_buf_t buf, pnanovdb_address_t node, uint32_t child_off,
                                 uint32_t value_off, uint32_t w)
{
    return pnanovdb_read_uint32(buf, pnanovdb_address_offset(node, child_off + 4u * w)) |
           pnanovdb_read_uint32(buf, pnanovdb_address_offset(node, value_off + 4u * w));
}

static inline bool in_range(const int32_t lo[3], const int32_t hi[3], int32_t x, int32_t y,
                            int32_t z)
{
    return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2];
}

/* Child n (x, y, z) of an upper node at `origin`: a lower node's leaves and
 * tiles in `box` (all of them, or with `sparse` those a child or value mask
 * sets, a word at a time), or a tile. */
static inline __attribute__((always_inline)) void
visit_upper_child(const grid *g, grid_ibox blocks, grid_ibox box, pnanovdb_upper_handle_t upper,
                  uint32_t n, const int32_t origin[3], int32_t x, int32_t y, int32_t z, bool sparse,
                  grid_block_fn fn, void *ctx)
{
    int32_t uo[3] = {origin[0] + 128 * x, origin[1] + 128 * y, origin[2] + 128 * z};
    if (!pnanovdb_upper_get_child_mask(g->buf, upper, n)) {
        visit_node(blocks, uo, 128,
                   g->checked && !pnanovdb_upper_get_value_mask(g->buf, upper, n)
                       ? tile_block(g->background)
                       : tile_block(pnanovdb_read_float(
                             g->buf, pnanovdb_upper_get_table_address(FLOAT_GRID, g->buf, upper, n))),
                   fn, ctx);
        return;
    }
    pnanovdb_lower_handle_t lower = pnanovdb_upper_get_child(FLOAT_GRID, g->buf, upper, n);
    int32_t llo[3], lhi[3];
    if (!child_range(uo, 128, 8, box, llo, lhi))
        return;
    if (sparse) {
        for (uint32_t v = 0; v < PNANOVDB_LOWER_TABLE_COUNT / 32; ++v)
            for (uint32_t lb = node_word(g->buf, lower.address, PNANOVDB_LOWER_OFF_CHILD_MASK,
                                         PNANOVDB_LOWER_OFF_VALUE_MASK, v);
                 lb; lb &= lb - 1) {
                uint32_t m = 32 * v + (uint32_t)__builtin_ctz(lb);
                int32_t i = (int32_t)(m >> 8), j = (int32_t)(m >> 4 & 15u), k = (int32_t)(m & 15u);
                if (!in_range(llo, lhi, i, j, k))
                    continue;
                const int64_t b[3] = {(int64_t)uo[0] / 8 + i, (int64_t)uo[1] / 8 + j,
                                      (int64_t)uo[2] / 8 + k};
                visit_lower_child(g, lower, m, b, fn, ctx);
            }
        return;
    }
    for (int32_t i = llo[0]; i <= lhi[0]; ++i)
        for (int32_t j = llo[1]; j <= lhi[1]; ++j)
            for (int32_t k = llo[2]; k <= lhi[2]; ++k) {
                const int64_t b[3] = {(int64_t)uo[0] / 8 + i, (int64_t)uo[1] / 8 + j,
                                      (int64_t)uo[2] / 8 + k};
                visit_lower_child(g, lower, (uint32_t)((i << 8) | (j << 4) | k), b, fn, ctx);
            }
}

/* Every leaf and tile of the tree that covers blocks of `blocks`, in the
 * tree's order: fn gets each with the blocks it covers there and what
 * grid_region_range and grid_region_support find in each of them. With
 * `active_only` (and a checked grid), not the tiles that are inactive:
 * they read the background, as blocks no call covers do, and a sparse
 * grid's nodes are mostly those (its masks are then read a word at a
 * time). Inline with fn a constant at each call: the fills of grid_blocks
 * stay a store. */
static inline __attribute__((always_inline)) void visit_blocks(const grid *g, grid_ibox blocks,
                                                               bool active_only, grid_block_fn fn,
                                                               void *ctx)
{
    grid_ibox box; /* the blocks' voxels */
    for (int a = 0; a < 3; ++a) {
        assert(blocks.min[a] <= blocks.max[a] && blocks.min[a] >= INT32_MIN / 8 &&
               blocks.max[a] <= INT32_MAX / 8);
        box.min[a] = blocks.min[a] * 8;
        box.max[a] = blocks.max[a] * 8 + 7;
    }
    bool sparse = active_only && g->checked;
    uint32_t count = pnanovdb_root_get_tile_count(g->buf, g->root);
    for (uint32_t t = 0; t < count; ++t) {
        pnanovdb_root_tile_handle_t tile;
        int32_t origin[3], lo[3], hi[3];
        if (!root_tile_overlaps(g, t, box, &tile, origin))
            continue;
        if (pnanovdb_int64_is_zero(pnanovdb_root_tile_get_child(g->buf, tile))) {
            visit_node(blocks, origin, 4096,
                       tile_block(pnanovdb_read_float(
                           g->buf, pnanovdb_root_tile_get_value_address(FLOAT_GRID, g->buf, tile))),
                       fn, ctx);
            continue;
        }
        pnanovdb_upper_handle_t upper = pnanovdb_root_get_child(FLOAT_GRID, g->buf, g->root, tile);
        if (!child_range(origin, 4096, 128, box, lo, hi))
            continue;
        if (sparse) {
            for (uint32_t w = 0; w < PNANOVDB_UPPER_TABLE_COUNT / 32; ++w)
                for (uint32_t bits = node_word(g->buf, upper.address, PNANOVDB_UPPER_OFF_CHILD_MASK,
                                               PNANOVDB_UPPER_OFF_VALUE_MASK, w);
                     bits; bits &= bits - 1) {
                    uint32_t n = 32 * w + (uint32_t)__builtin_ctz(bits);
                    int32_t x = (int32_t)(n >> 10), y = (int32_t)(n >> 5 & 31u),
                            z = (int32_t)(n & 31u);
                    if (in_range(lo, hi, x, y, z))
                        visit_upper_child(g, blocks, box, upper, n, origin, x, y, z, true, fn, ctx);
                }
            continue;
        }
        for (int32_t x = lo[0]; x <= hi[0]; ++x)
            for (int32_t y = lo[1]; y <= hi[1]; ++y)
                for (int32_t z = lo[2]; z <= hi[2]; ++z)
                    visit_upper_child(g, blocks, box, upper, (uint32_t)((x << 10) | (y << 5) | z),
                                      origin, x, y, z, false, fn, ctx);
    }
}

void grid_visit_active_blocks(const grid *g, grid_ibox blocks, grid_block_fn fn, void *ctx)
{
    assert(g->type == FLOAT_GRID);
    visit_blocks(g, blocks, true, fn, ctx);
}

typedef struct {
    grid_ibox blocks; /* the window, in blocks */
    int64_t n[3];
    grid_block *out;
} block_window;

/* Blocks [lo, hi] of the window set to b. */
static inline void fill_window(void *ctx, const int64_t lo[3], const int64_t hi[3], grid_block b)
{
    const block_window *w = ctx;
    for (int64_t z = lo[2]; z <= hi[2]; ++z)
        for (int64_t y = lo[1]; y <= hi[1]; ++y) {
            grid_block *row = w->out + (((z - w->blocks.min[2]) * w->n[1] + (y - w->blocks.min[1])) *
                                            w->n[0] +
                                        (lo[0] - w->blocks.min[0]));
            for (int64_t x = 0; x <= hi[0] - lo[0]; ++x)
                row[x] = b;
        }
}

void grid_blocks(const grid *g, grid_ibox blocks, grid_block *out)
{
    assert(g->type == FLOAT_GRID);
    block_window w = {blocks, {0, 0, 0}, out};
    size_t total = 1;
    for (int a = 0; a < 3; ++a) {
        w.n[a] = (int64_t)blocks.max[a] - blocks.min[a] + 1;
        total *= (size_t)w.n[a];
    }
    /* Where no root tile lies, every voxel reads the background. */
    const grid_block none = {g->background, g->background, 0, UINT32_MAX, GRID_BLOCK_ZERO};
    for (size_t i = 0; i < total; ++i)
        out[i] = none;
    visit_blocks(g, blocks, false, fill_window, &w);
}

void grid_block_support_add(const grid *g, const grid_block *b, const int32_t origin[3],
                            grid_ibox box, grid_ibox *acc, bool *any)
{
    switch (b->support) {
    case GRID_BLOCK_ZERO:
        return;
    case GRID_BLOCK_FULL:
        support_add_block(origin, 8, box, acc, any);
        return;
    case GRID_BLOCK_PARTIAL:
        leaf_support(g, (pnanovdb_leaf_handle_t){{b->leaf}}, b->stats, origin, box,
                     acc, any);
        return;
    }
}
