/* media/grid: trilinear density with values at integer index points, transforms,
 * bounds and node statistics, and vec3 (velocity) grids, checked on the
 * generated volumes whose contents are known exactly (volumes/generate.cpp). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "media/grid.h"
#include "unit/assert_util.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

static void assert_exact(double got, double want)
{
    if (got != want)
        fail_msg("got %.17g, want exactly %.17g", got, want);
}

static grid *load(const char *file)
{
    grid *g = NULL;
    hz_error err = {0};
    if (grid_load(file, "density", &g, &err) != HZ_OK)
        fail_msg("%s", err.message);
    return g;
}

static double density(grid *g, double x, double y, double z)
{
    grid_accessor a;
    grid_accessor_init(g, &a);
    return grid_density_index(g, &a, v3(x, y, z));
}

/* box.vdb: density 1 on voxels [0,31]^3, background 0. */
static void box_is_one_inside(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "box.vdb");
    const double pts[][3] = {{0, 0, 0},       {31, 31, 31},   {15.3, 7.7, 30.9},
                             {0.5, 0.5, 0.5}, {30.99, 0, 12}, {16, 16, 16}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; ++i)
        assert_exact(density(g, pts[i][0], pts[i][1], pts[i][2]), 1.0);
    grid_destroy(g);
}

/* The field falls off linearly over the voxel beyond each face. */
static void box_falls_off_over_one_voxel(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "box.vdb");
    assert_exact(density(g, 31.5, 16, 16), 0.5);
    assert_exact(density(g, -0.5, 16, 16), 0.5);
    assert_exact(density(g, 31.75, 16, 16), 0.25);
    assert_exact(density(g, -0.25, 16, 16), 0.75);
    assert_exact(density(g, 16, 31.5, 16), 0.5);
    assert_exact(density(g, 16, 16, -0.5), 0.5);
    /* A corner: one of eight neighbours inside along each axis. */
    assert_exact(density(g, 31.5, 31.5, 31.5), 0.125);
    assert_exact(density(g, -0.5, -0.5, -0.5), 0.125);
    /* Outside the support [-1, 32]. */
    assert_exact(density(g, -1, 16, 16), 0.0);
    assert_exact(density(g, 32, 16, 16), 0.0);
    assert_exact(density(g, -1.5, 16, 16), 0.0);
    assert_exact(density(g, 40, 16, 16), 0.0);
    assert_exact(density(g, 1e12, -1e12, 3), 0.0);
    assert_exact(density(g, NAN, 16, 16), 0.0);
    grid_destroy(g);
}

static void box_bounds_and_statistics(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "box.vdb");
    grid_ibox b;
    assert_true(grid_index_bounds(g, &b));
    for (int a = 0; a < 3; ++a) {
        assert_int_equal(b.min[a], 0);
        assert_int_equal(b.max[a], 31);
    }
    vec3 lo, hi;
    assert_true(grid_support_bounds(g, &lo, &hi));
    assert_v3_near(lo, v3(-1, -1, -1), 0);
    assert_v3_near(hi, v3(32, 32, 32), 0);
    assert_exact(grid_max_value(g), 1.0);
    assert_exact(grid_min_value(g), 1.0);
    assert_exact(grid_background(g), 0.0);
    assert_int_equal(grid_active_voxel_count(g), 32 * 32 * 32);
    assert_string_equal(grid_name(g), "density");
    grid_destroy(g);
}

static void box_transforms(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "box.vdb");
    /* Voxel size 1/32, no offset. */
    assert_v3_near(grid_world_from_index(g, v3(32, 16, 0)), v3(1, 0.5, 0), 1e-15);
    assert_v3_near(grid_world_from_index(g, v3(-1, 3, 7)), v3(-1.0 / 32, 3.0 / 32, 7.0 / 32),
                   1e-15);
    assert_v3_near(grid_index_from_world(g, v3(0.5, 0.25, 1)), v3(16, 8, 32), 1e-12);
    vec3 p = v3(0.123, -4.5, 9.75);
    assert_v3_near(grid_index_from_world(g, grid_world_from_index(g, p)), p, 1e-12);
    transform t = grid_world_from_index_transform(g);
    assert_v3_near(transform_point(&t, v3(8, 8, 8)), v3(0.25, 0.25, 0.25), 1e-15);
    grid_destroy(g);
}

/* fog_sphere.vdb: voxel size 1/32, offset -1: index (32,32,32) is the world origin. */
static void sphere_values_and_transform(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "fog_sphere.vdb");
    assert_v3_near(grid_world_from_index(g, v3(32, 32, 32)), v3(0, 0, 0), 1e-15);
    assert_v3_near(grid_index_from_world(g, v3(0.75, 0, -0.5)), v3(56, 32, 16), 1e-12);
    grid_accessor a;
    grid_accessor_init(g, &a);
    assert_exact(grid_voxel(g, &a, 32, 32, 32), 1.0);
    /* r = 23 voxels: 1 - smoothstep(20, 24, 23) = 1 - 0.84375. */
    assert_exact(grid_voxel(g, &a, 55, 32, 32), 0.15625);
    assert_exact(grid_voxel(g, &a, 32, 9, 32), 0.15625);
    assert_exact(grid_voxel(g, &a, 56, 32, 32), 0.0);
    /* Halfway between r = 22 (1 - 0.5) and r = 23: the mean. */
    assert_near(grid_density_index(g, &a, v3(54.5, 32, 32)), 0.5 * (0.5 + 0.15625), 1e-7);
    assert_exact(grid_max_value(g), 1.0);
    assert_true(grid_min_value(g) > 0.0f);
    grid_ibox b;
    assert_true(grid_index_bounds(g, &b));
    for (int ax = 0; ax < 3; ++ax) {
        assert_int_equal(b.min[ax], 9);
        assert_int_equal(b.max[ax], 55);
    }
    grid_destroy(g);
}

/* sheet.vdb: one voxel thick at y = 0, so a tent of width two voxels in y. */
static void sheet_is_a_tent(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "sheet.vdb");
    assert_exact(density(g, 10, 0, 10), 1.0);
    assert_exact(density(g, 10, 0.5, 10), 0.5);
    assert_exact(density(g, 10, -0.5, 10), 0.5);
    assert_exact(density(g, 10, 0.25, 10), 0.75);
    assert_exact(density(g, 10, 1, 10), 0.0);
    assert_exact(density(g, 10, -1, 10), 0.0);
    /* Voxel size 1/64 with x, z offset -1/2: the sheet spans world [-0.5, 0.5). */
    assert_v3_near(grid_world_from_index(g, v3(32, 0, 0)), v3(0, 0, -0.5), 1e-15);
    grid_destroy(g);
}

static uint32_t lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static double uniform(uint32_t *s) { return lcg(s) * (1.0 / 16777216.0); }

/* smoke.vdb: densities in (0, 1], and every trilinear value lies within the range
 * of the active values and the background. */
static void smoke_values_in_range(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "smoke.vdb");
    float lo = grid_min_value(g), hi = grid_max_value(g);
    assert_true(lo >= 0.01f && hi <= 1.0f && hi > 0.5f);
    vec3 slo, shi;
    assert_true(grid_support_bounds(g, &slo, &shi));
    grid_accessor a;
    grid_accessor_init(g, &a);
    uint32_t seed = 7;
    int nonzero = 0;
    for (int i = 0; i < 20000; ++i) {
        vec3 p = v3(hz_lerp(uniform(&seed), slo.x, shi.x), hz_lerp(uniform(&seed), slo.y, shi.y),
                    hz_lerp(uniform(&seed), slo.z, shi.z));
        double d = grid_density_index(g, &a, p);
        assert_true(d >= 0.0 && d <= hi);
        nonzero += d > 0.0;
    }
    assert_true(nonzero > 1000);
    grid_destroy(g);
}

static void node_statistics(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "box.vdb");
    grid_node n = grid_node_at(g, GRID_LEAF, 5, 6, 7);
    assert_int_equal(n.kind, GRID_NODE_CHILD);
    assert_int_equal(n.dim, 8);
    assert_int_equal(n.origin[0], 0);
    assert_exact(n.min, 1.0);
    assert_exact(n.max, 1.0);
    n = grid_node_at(g, GRID_LEAF, 25, 17, 9);
    assert_int_equal(n.kind, GRID_NODE_CHILD);
    assert_int_equal(n.origin[0], 24);
    assert_int_equal(n.origin[1], 16);
    assert_int_equal(n.origin[2], 8);
    /* Inside the lower node, outside every leaf: an (inactive) tile of background. */
    n = grid_node_at(g, GRID_LEAF, 40, 0, 0);
    assert_int_equal(n.kind, GRID_NODE_TILE);
    assert_int_equal(n.origin[0], 40);
    assert_exact(n.max, 0.0);
    n = grid_node_at(g, GRID_LOWER, 100, 3, 3);
    assert_int_equal(n.kind, GRID_NODE_CHILD);
    assert_int_equal(n.dim, 128);
    assert_exact(n.max, 1.0);
    n = grid_node_at(g, GRID_UPPER, 0, 0, 0);
    assert_int_equal(n.kind, GRID_NODE_CHILD);
    assert_int_equal(n.dim, 4096);
    /* Negative coordinates: no root tile there. */
    n = grid_node_at(g, GRID_LEAF, -5, -5, -9);
    assert_int_equal(n.kind, GRID_NODE_BACKGROUND);
    assert_int_equal(n.origin[0], -8);
    assert_int_equal(n.origin[2], -16);
    assert_exact(n.max, 0.0);
    grid_destroy(g);
}

static void expect_range(const grid *g, grid_ibox box, float lo, float hi)
{
    float got_lo, got_hi;
    grid_region_range(g, box, &got_lo, &got_hi);
    assert_exact(got_lo, lo);
    assert_exact(got_hi, hi);
}

/* box.vdb: 1 on the fully active voxels [0,31]^3, background 0 elsewhere. */
static void region_max_box(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "box.vdb");
    expect_range(g, (grid_ibox){{0, 0, 0}, {31, 31, 31}}, 1.0f, 1.0f);
    expect_range(g, (grid_ibox){{31, 0, 0}, {40, 3, 3}}, 0.0f, 1.0f);
    expect_range(g, (grid_ibox){{32, 0, 0}, {40, 3, 3}}, 0.0f, 0.0f);
    expect_range(g, (grid_ibox){{-100, -100, -100}, {-1, 50, 50}}, 0.0f, 0.0f);
    expect_range(g, (grid_ibox){{-100, -100, -100}, {0, 0, 0}}, 0.0f, 1.0f);
    expect_range(g, (grid_ibox){{5000, 0, 0}, {9000, 10, 10}}, 0.0f, 0.0f);
    grid_destroy(g);
}

/* On smoke, the region range bounds every voxel in the region (brute force)
 * and the region max every trilinear sample in the matching index-space region. */
static void region_max_is_a_majorant(void **state)
{
    (void)state;
    grid *g = load(VOLUMES "smoke.vdb");
    grid_ibox all;
    assert_true(grid_index_bounds(g, &all));
    float all_lo, all_hi;
    grid_region_range(g, all, &all_lo, &all_hi);
    assert_exact(all_hi, grid_max_value(g));
    grid_accessor a;
    grid_accessor_init(g, &a);
    uint32_t seed = 11;
    for (int trial = 0; trial < 200; ++trial) {
        grid_ibox b;
        for (int ax = 0; ax < 3; ++ax) {
            int32_t span = all.max[ax] - all.min[ax] + 4;
            b.min[ax] = all.min[ax] - 2 + (int32_t)(uniform(&seed) * span);
            b.max[ax] = b.min[ax] + (int32_t)(uniform(&seed) * 12);
        }
        float lo, m;
        grid_region_range(g, b, &lo, &m);
        float brute_lo = INFINITY, brute = -INFINITY;
        for (int32_t i = b.min[0]; i <= b.max[0]; ++i)
            for (int32_t j = b.min[1]; j <= b.max[1]; ++j)
                for (int32_t k = b.min[2]; k <= b.max[2]; ++k) {
                    float v = grid_voxel(g, &a, i, j, k);
                    brute_lo = fminf(brute_lo, v);
                    brute = fmaxf(brute, v);
                }
        assert_true(lo <= brute_lo && brute <= m);
        /* Trilinear samples in [min, max] read voxels min .. max + 1. */
        grid_ibox dilated = b;
        for (int ax = 0; ax < 3; ++ax)
            dilated.max[ax] += 1;
        float lo_d, md;
        grid_region_range(g, dilated, &lo_d, &md);
        for (int s = 0; s < 50; ++s) {
            vec3 p = v3(hz_lerp(uniform(&seed), b.min[0], b.max[0]),
                        hz_lerp(uniform(&seed), b.min[1], b.max[1]),
                        hz_lerp(uniform(&seed), b.min[2], b.max[2]));
            assert_true(grid_density_index(g, &a, p) <= md);
        }
    }
    /* Over whole leaves the leaf statistics make it exact. */
    for (int32_t i = all.min[0] & ~7; i <= all.max[0]; i += 8)
        for (int32_t j = all.min[1] & ~7; j <= all.max[1]; j += 8)
            for (int32_t k = all.min[2] & ~7; k <= all.max[2]; k += 8) {
                float brute = grid_background(g);
                for (int32_t x = i; x < i + 8; ++x)
                    for (int32_t y = j; y < j + 8; ++y)
                        for (int32_t z = k; z < k + 8; ++z)
                            brute = fmaxf(brute, grid_voxel(g, &a, x, y, z));
                float leaf_lo, leaf_hi;
                grid_region_range(g, (grid_ibox){{i, j, k}, {i + 7, j + 7, k + 7}}, &leaf_lo,
                                  &leaf_hi);
                assert_exact(fmaxf(leaf_hi, grid_background(g)), brute);
            }
    grid_destroy(g);
}

static void rejects_bad_buffers(void **state)
{
    (void)state;
    hz_error err = {0};
    grid *g = NULL;
    vdb_buffer small = {aligned_alloc(32, 64), 64, NULL, 0};
    assert_int_equal(grid_create_from_buffer(&small, "x", &g, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "too small"));
    vdb_buffer_free(&small);
    vdb_buffer junk = {aligned_alloc(32, 4096), 4096, NULL, 0};
    memset(junk.data, 0xab, 4096);
    assert_int_equal(grid_create_from_buffer(&junk, "x", &g, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "not a NanoVDB grid"));
    assert_null(g);
    vdb_buffer_free(&junk);
}

/* ---- vec3 grids ---- */

static grid *load_vec3(const char *file, const char *name)
{
    grid *g = NULL;
    hz_error err = {0};
    if (grid_load_vec3(file, name, &g, &err) != HZ_OK)
        fail_msg("%s", err.message);
    return g;
}

/* vec_ramp: v(i,j,k) = (0.5 i - 1, 0.25 j, 2 - k) on voxels [0,7]^3. */
static vec3 ramp(double i, double j, double k) { return v3(0.5 * i - 1.0, 0.25 * j, 2.0 - k); }

static void check_ramp(const char *file)
{
    grid *g = load_vec3(file, "v");
    assert_int_equal(grid_type(g), GRID_VEC3);
    grid_accessor a;
    grid_accessor_init(g, &a);
    /* Voxel values, exactly. */
    for (int i = 0; i < 8; i += 3)
        for (int j = 0; j < 8; j += 2)
            for (int k = 0; k < 8; k += 7) {
                vec3 v = grid_vec3_voxel(g, &a, i, j, k), want = ramp(i, j, k);
                assert_exact(v.x, want.x);
                assert_exact(v.y, want.y);
                assert_exact(v.z, want.z);
            }
    /* Trilinear interpolation reproduces a linear field inside the active box. */
    uint64_t seed = 17;
    for (int n = 0; n < 200; ++n) {
        vec3 p = v3(7 * rng_next(&seed), 7 * rng_next(&seed), 7 * rng_next(&seed));
        assert_v3_near(grid_vec3_index(g, &a, p), ramp(p.x, p.y, p.z), 1e-12);
    }
    /* Beyond the active voxels the field falls to the background over one voxel,
     * and is the background (0) outside [-1, 8]. */
    assert_v3_near(grid_vec3_index(g, &a, v3(7.5, 4, 4)), v3_scale(ramp(7, 4, 4), 0.5), 1e-12);
    assert_v3_near(grid_vec3_index(g, &a, v3(3, 3, -0.25)), v3_scale(ramp(3, 3, 0), 0.75), 1e-12);
    assert_v3_near(grid_vec3_index(g, &a, v3(8, 4, 4)), v3(0, 0, 0), 0);
    assert_v3_near(grid_vec3_index(g, &a, v3(-3, 4, 4)), v3(0, 0, 0), 0);
    assert_v3_near(grid_vec3_index(g, &a, v3(NAN, 4, 4)), v3(0, 0, 0), 0);
    /* Statistics are lengths: the longest vector is v(7, 7, 7), the shortest 0. */
    assert_near(grid_max_value(g), v3_length(ramp(7, 7, 7)), 1e-6);
    assert_exact(grid_min_value(g), 0.0);
    assert_exact(grid_background(g), 0.0);
    assert_int_equal(grid_active_voxel_count(g), 512);
    /* Voxel size 0.25, offset (1, 2, 3). */
    assert_v3_near(grid_world_from_index(g, v3(4, 0, 8)), v3(2, 2, 5), 1e-15);
    grid_destroy(g);
}

static void vec3_ramp_vdb(void **state)
{
    (void)state;
    check_ramp(VOLUMES "vec_ramp.vdb");
}

/* The same grid from a (ZIP-compressed) NanoVDB file. */
static void vec3_ramp_nvdb(void **state)
{
    (void)state;
    check_ramp(VOLUMES "vec_ramp.nvdb");
}

/* The loaders insist on the value type, naming what they found. */
static void vec3_type_mismatch(void **state)
{
    (void)state;
    grid *g = NULL;
    hz_error err = {0};
    assert_int_equal(grid_load_vec3(VOLUMES "vec_ramp.vdb", "density", &g, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "grid \"density\" is float, expected vec3s"));
    assert_int_equal(grid_load_vec3(VOLUMES "vec_ramp.nvdb", "density", &g, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "grid \"density\" is float, expected Vec3f"));
    assert_int_equal(grid_load(VOLUMES "vec_ramp.nvdb", "v", &g, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "grid \"v\" is Vec3f, expected float"));
    assert_null(g);
    g = load(VOLUMES "vec_ramp.nvdb");
    assert_int_equal(grid_type(g), GRID_FLOAT);
    grid_destroy(g);
}

/* plume.vdb: the velocity has half the density's resolution and its own map. */
static void vec3_plume_velocity(void **state)
{
    (void)state;
    grid *d = load(VOLUMES "plume.vdb"), *v = load_vec3(VOLUMES "plume.vdb", "v");
    assert_v3_near(grid_world_from_index(d, v3(32, 64, 32)), v3(0, 1, 0), 1e-15);
    assert_v3_near(grid_world_from_index(v, v3(16, 32, 16)), v3(0, 1, 0), 1e-15);
    /* Rising everywhere it is defined: 0.7 to 1.3 m/s up, plus the swirl. */
    grid_accessor a;
    grid_accessor_init(v, &a);
    vec3 up = grid_vec3_voxel(v, &a, 16, 32, 16);
    assert_true(up.y > 0.7 && up.y < 1.31);
    assert_true(grid_max_value(v) > 1.0f && grid_max_value(v) < 1.6f);
    assert_true(grid_min_value(v) >= 0.7f);
    grid_destroy(d);
    grid_destroy(v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(box_is_one_inside),
        cmocka_unit_test(box_falls_off_over_one_voxel),
        cmocka_unit_test(box_bounds_and_statistics),
        cmocka_unit_test(box_transforms),
        cmocka_unit_test(sphere_values_and_transform),
        cmocka_unit_test(sheet_is_a_tent),
        cmocka_unit_test(smoke_values_in_range),
        cmocka_unit_test(node_statistics),
        cmocka_unit_test(region_max_box),
        cmocka_unit_test(region_max_is_a_majorant),
        cmocka_unit_test(rejects_bad_buffers),
        cmocka_unit_test(vec3_ramp_vdb),
        cmocka_unit_test(vec3_ramp_nvdb),
        cmocka_unit_test(vec3_type_mismatch),
        cmocka_unit_test(vec3_plume_velocity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
