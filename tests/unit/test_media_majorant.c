/* media/majorant: the per-cell bounds hold the trilinear density everywhere in
 * their cell (checked against dense lookups on the generated volumes), they
 * are tight where the data is known exactly (box.vdb), empty space reads 0,
 * and the DDA walk visits exactly the cells a ray crosses, in order. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include "core/rng.h"
#include "media/grid.h"
#include "media/majorant.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

typedef struct {
    grid *g;
    majorant_grid mg;
} fixture;

static fixture build(const char *file, int32_t pad)
{
    fixture f = {NULL, {{0}, {0}, 0, NULL, NULL}};
    hz_error err = {0};
    if (grid_load(file, "density", &f.g, &err) != HZ_OK)
        fail_msg("%s", err.message);
    vec3 lo, hi;
    assert_true(grid_support_bounds(f.g, &lo, &hi));
    int32_t p[3] = {pad, pad, pad};
    assert_int_equal(majorant_grid_build(f.g, lo, hi, p, &f.mg, &err), HZ_OK);
    return f;
}

static void destroy(fixture *f)
{
    majorant_grid_free(&f->mg);
    grid_destroy(f->g);
}

static size_t cell_of(const majorant_grid *mg, vec3 p)
{
    const double p3[3] = {p.x, p.y, p.z};
    int32_t c[3];
    for (int a = 0; a < 3; ++a) {
        c[a] = (int32_t)floor((p3[a] - mg->origin[a]) / mg->cell);
        assert_in_range(c[a], 0, mg->res[a] - 1);
    }
    return ((size_t)c[2] * mg->res[1] + c[1]) * mg->res[0] + c[0];
}

/* Random points of the support: min <= density <= max of their cell. */
static void bounds_hold(const char *file)
{
    fixture f = build(file, 0);
    vec3 lo, hi;
    grid_support_bounds(f.g, &lo, &hi);
    grid_accessor acc;
    grid_accessor_init(f.g, &acc);
    rng r = rng_seeded(7);
    int inside = 0;
    for (int i = 0; i < 200000; ++i) {
        vec3 p = v3(lo.x + rng_uniform(&r) * (hi.x - lo.x), lo.y + rng_uniform(&r) * (hi.y - lo.y),
                    lo.z + rng_uniform(&r) * (hi.z - lo.z));
        double d = grid_density_index(f.g, &acc, p);
        size_t c = cell_of(&f.mg, p);
        if (d > f.mg.max[c] || d < f.mg.min[c])
            fail_msg("%s: density %.9g at (%g %g %g) outside its cell's [%g, %g]", file, d, p.x,
                     p.y, p.z, f.mg.min[c], f.mg.max[c]);
        inside += d > 0.0;
    }
    assert_true(inside > 1000); /* the test looked at the medium, not only at empty space */
    destroy(&f);
}

static void bounds_hold_on_every_volume(void **state)
{
    (void)state;
    bounds_hold(VOLUMES "box.vdb");
    bounds_hold(VOLUMES "fog_sphere.vdb");
    bounds_hold(VOLUMES "sheet.vdb");
    bounds_hold(VOLUMES "smoke.vdb");
    bounds_hold(VOLUMES "plume.vdb");
}

/* box.vdb is 1 on voxels [0,31]^3 (fully active leaves): the cells wholly
 * inside have min = max = 1 (residual tracking is then exact and free), the
 * edge cells [0, 1], and cells beyond the support would be 0. */
static void box_bounds_are_tight(void **state)
{
    (void)state;
    fixture f = build(VOLUMES "box.vdb", 0);
    assert_int_equal(f.mg.cell, 8);
    assert_int_equal(f.mg.origin[0], -8);
    assert_int_equal(f.mg.res[0], 6); /* support [-1, 32]: cells -8 .. 40 */
    size_t n = (size_t)f.mg.res[0] * f.mg.res[1] * f.mg.res[2];
    int full = 0, empty = 0;
    for (size_t i = 0; i < n; ++i) {
        assert_true(f.mg.max[i] == 0.0f || f.mg.max[i] == 1.0f);
        full += f.mg.min[i] == 1.0f;
        empty += f.mg.max[i] == 0.0f;
    }
    /* Interior cells [8,16) and [16,24) per axis read voxels 7..25: inside. */
    assert_int_equal(full, 2 * 2 * 2);
    /* Cells [-8,0) read voxels -9..1 (touch the box); [32,40) read 31..41. So
     * only cells beyond 40 could be empty, and there are none: every cell
     * touches the box. */
    assert_int_equal(empty, 0);
    destroy(&f);
}

/* A velocity pad widens every cell's box: more cells see the medium. */
static void padding_widens(void **state)
{
    (void)state;
    fixture a = build(VOLUMES "sheet.vdb", 0), b = build(VOLUMES "sheet.vdb", 9);
    size_t n = (size_t)a.mg.res[0] * a.mg.res[1] * a.mg.res[2];
    assert_int_equal(n, (size_t)b.mg.res[0] * b.mg.res[1] * b.mg.res[2]);
    for (size_t i = 0; i < n; ++i)
        assert_true(b.mg.max[i] >= a.mg.max[i] && b.mg.min[i] <= a.mg.min[i]);
    destroy(&a);
    destroy(&b);
}

/* The walk covers [t0, t1] clipped to the grid with contiguous segments whose
 * midpoints lie in the cells whose bounds they report. */
static void walk_visits_crossed_cells(void **state)
{
    (void)state;
    fixture f = build(VOLUMES "smoke.vdb", 0);
    const majorant_grid *mg = &f.mg;
    rng r = rng_seeded(3);
    vec3 lo = v3(mg->origin[0], mg->origin[1], mg->origin[2]);
    vec3 size = v3((double)mg->res[0] * mg->cell, (double)mg->res[1] * mg->cell,
                   (double)mg->res[2] * mg->cell);
    int hits = 0;
    for (int i = 0; i < 20000; ++i) {
        /* Origins around the grid, directions random; every 8th axis-parallel. */
        vec3 o = v3(lo.x + (rng_uniform(&r) * 1.4 - 0.2) * size.x,
                    lo.y + (rng_uniform(&r) * 1.4 - 0.2) * size.y,
                    lo.z + (rng_uniform(&r) * 1.4 - 0.2) * size.z);
        vec3 d = v3(rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5);
        if (i % 8 == 0)
            d = i % 24 == 0 ? v3(0, 0, -3) : i % 24 == 8 ? v3(0.5, 0, 0) : v3(0, 2, 0);
        double t0 = rng_uniform(&r) * 10.0, t1 = t0 + rng_uniform(&r) * 600.0;
        majorant_walk w;
        if (!majorant_walk_start(&w, mg, o, d, t0, t1))
            continue;
        ++hits;
        majorant_segment s;
        double prev = NAN, first = NAN;
        int n = 0;
        while (majorant_walk_next(&w, &s)) {
            if (n == 0)
                first = s.t0;
            else
                assert_true(s.t0 == prev);
            assert_true(s.t1 >= s.t0);
            prev = s.t1;
            ++n;
            if (s.t1 - s.t0 > 1e-6) {
                double tm = 0.5 * (s.t0 + s.t1);
                size_t c = cell_of(mg, v3(o.x + tm * d.x, o.y + tm * d.y, o.z + tm * d.z));
                assert_true(mg->max[c] == (float)s.max && mg->min[c] == (float)s.min);
            }
            assert_true(n < 3 * (mg->res[0] + mg->res[1] + mg->res[2]));
        }
        assert_true(n >= 1);
        assert_true(first >= t0 && prev <= t1);
        /* Points just inside the ends are inside the grid's box. */
        double e = 1e-7 * (prev - first);
        const double ends[2] = {first + e, prev - e};
        for (int k = 0; k < 2; ++k)
            (void)cell_of(mg, v3(o.x + ends[k] * d.x, o.y + ends[k] * d.y, o.z + ends[k] * d.z));
    }
    assert_true(hits > 5000);
    destroy(&f);
}

static void empty_support_has_no_cells(void **state)
{
    (void)state;
    fixture f = build(VOLUMES "box.vdb", 0);
    majorant_grid empty;
    hz_error err = {0};
    int32_t pad[3] = {0, 0, 0};
    assert_int_equal(majorant_grid_build(f.g, v3(1, 1, 1), v3(-1, -1, -1), pad, &empty, &err),
                     HZ_OK);
    majorant_walk w;
    assert_false(majorant_walk_start(&w, &empty, v3(0, 0, 0), v3(1, 0, 0), 0.0, 100.0));
    majorant_grid_free(&empty);
    destroy(&f);
}

/* Supports spanning most of index space (voxels 3.3e7 and 2e9 apart, and
 * the whole int32 range) once overflowed the cell count (signed overflow,
 * then malloc(0) and writes). The grid stays within MAJORANT_MAX_CELLS, its
 * memory bounded, and every cell still bounds the data (box.vdb: 1 on
 * [0,31]^3): the cell holding the box has the upper bound 1. */
static void huge_supports_stay_bounded(void **state)
{
    (void)state;
    fixture f = build(VOLUMES "box.vdb", 0);
    const double spans[][2] = {{-1.65e7, 1.65e7}, {-1e9, 1e9}, {-3e9, 3e9}, {0, 2147483647.0}};
    for (size_t k = 0; k < sizeof spans / sizeof spans[0]; ++k) {
        majorant_grid mg;
        hz_error err = {0};
        int32_t pad[3] = {0, 0, 0};
        vec3 lo = v3(spans[k][0], spans[k][0], spans[k][0]);
        vec3 hi = v3(spans[k][1], spans[k][1], spans[k][1]);
        assert_int_equal(majorant_grid_build(f.g, lo, hi, pad, &mg, &err), HZ_OK);
        uint64_t cells = (uint64_t)mg.res[0] * (uint64_t)mg.res[1] * (uint64_t)mg.res[2];
        assert_true(cells >= 1 && cells <= MAJORANT_MAX_CELLS);
        assert_true(majorant_grid_bytes(&mg) <= 2 * sizeof(float) * MAJORANT_MAX_CELLS);
        assert_int_equal(mg.max[cell_of(&mg, v3(16, 16, 16))], 1.0f);
        majorant_grid_free(&mg);
    }
    destroy(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(bounds_hold_on_every_volume),
        cmocka_unit_test(box_bounds_are_tight),
        cmocka_unit_test(padding_widens),
        cmocka_unit_test(walk_visits_crossed_cells),
        cmocka_unit_test(empty_support_has_no_cells),
        cmocka_unit_test(huge_supports_stay_bounded),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
