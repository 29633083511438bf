/* media/majorant: the per-cell bounds hold the trilinear density everywhere in
 * their cell (checked against dense lookups on the generated volumes), they
 * are tight where the data is known exactly (box.vdb), empty space reads 0,
 * the two-level DDA walk reports exactly the bounds along a ray, in order, its
 * coarse form (bricks whole) covers every interval that holds density, and
 * memory follows the active data, not the support's box. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "core/transform.h"
#include "media/grid.h"
#include "media/majorant.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

typedef struct {
    grid *g;
    majorant_grid mg;
} fixture;

static fixture build(const char *file, int32_t pad)
{
    fixture f = {0};
    hz_error err = {0};
    if (grid_load(file, "density", &f.g, &err) != HZ_OK)
        fail_msg("%s", err.message);
    vec3 lo, hi;
    assert_true(grid_support_bounds(f.g, &lo, &hi));
    int32_t p[3] = {pad, pad, pad};
    assert_int_equal(majorant_grid_build(f.g, NULL, lo, hi, p, &f.mg, &err), HZ_OK);
    return f;
}

static void destroy(fixture *f)
{
    majorant_grid_free(&f->mg);
    grid_destroy(f->g);
}

/* The bounds of the cell holding p, which must be inside the grid. */
static majorant_bounds cell_of(const majorant_grid *mg, vec3 p)
{
    majorant_bounds b;
    if (!majorant_grid_bounds_at(mg, p, &b))
        fail_msg("(%g %g %g) is outside the majorant grid", p.x, p.y, p.z);
    return b;
}

/* Cells per axis (bricks times their cells). */
static int32_t cells_along(const majorant_grid *mg, int a) { return mg->res[a] * MAJORANT_BRICK; }

/* The centre of cell (x, y, z). */
static vec3 cell_centre(const majorant_grid *mg, int32_t x, int32_t y, int32_t z)
{
    return v3(mg->origin[0] + (x + 0.5) * mg->cell, mg->origin[1] + (y + 0.5) * mg->cell,
              mg->origin[2] + (z + 0.5) * mg->cell);
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
        majorant_bounds c = cell_of(&f.mg, p);
        if (d > c.max || d < c.min)
            fail_msg("%s: density %.9g at (%g %g %g) outside its cell's [%g, %g]", file, d, p.x,
                     p.y, p.z, c.min, c.max);
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
 * cells whose voxels read touch the box [0, 1], every other cell 0. */
static void box_bounds_are_tight(void **state)
{
    (void)state;
    fixture f = build(VOLUMES "box.vdb", 0);
    assert_int_equal(f.mg.cell, 8);
    /* Support [-1, 32]: bricks of 64 voxels from -64 to 64. */
    assert_int_equal(f.mg.origin[0], -64);
    assert_int_equal(f.mg.res[0], 2);
    int full = 0, touching = 0;
    for (int32_t z = 0; z < cells_along(&f.mg, 2); ++z)
        for (int32_t y = 0; y < cells_along(&f.mg, 1); ++y)
            for (int32_t x = 0; x < cells_along(&f.mg, 0); ++x) {
                majorant_bounds b = cell_of(&f.mg, cell_centre(&f.mg, x, y, z));
                /* Cell [a, a + 8) reads voxels a - 1 .. a + 9: it touches
                 * [0, 31] for a in -8 .. 24 + 8 and is inside for a in 8, 16. */
                const int32_t c3[3] = {x, y, z};
                bool touches = true, inside = true;
                for (int a = 0; a < 3; ++a) {
                    int32_t first = f.mg.origin[a] + c3[a] * f.mg.cell;
                    touches = touches && first >= -8 && first <= 32;
                    inside = inside && first >= 8 && first <= 16;
                }
                assert_true(b.max == (touches ? 1.0f : 0.0f));
                assert_true(b.min == (inside ? 1.0f : 0.0f));
                full += inside;
                touching += touches;
            }
    assert_int_equal(full, 2 * 2 * 2);
    assert_int_equal(touching, 6 * 6 * 6);
    destroy(&f);
}

/* A velocity pad widens every cell's box: more cells see the medium. */
static void padding_widens(void **state)
{
    (void)state;
    fixture a = build(VOLUMES "sheet.vdb", 0), b = build(VOLUMES "sheet.vdb", 9);
    for (int ax = 0; ax < 3; ++ax)
        assert_int_equal(a.mg.res[ax], b.mg.res[ax]);
    int wider = 0;
    for (int32_t z = 0; z < cells_along(&a.mg, 2); ++z)
        for (int32_t y = 0; y < cells_along(&a.mg, 1); ++y)
            for (int32_t x = 0; x < cells_along(&a.mg, 0); ++x) {
                vec3 p = cell_centre(&a.mg, x, y, z);
                majorant_bounds ba = cell_of(&a.mg, p), bb = cell_of(&b.mg, p);
                assert_true(bb.max >= ba.max && bb.min <= ba.min);
                wider += bb.max > ba.max || bb.min < ba.min;
            }
    assert_true(wider > 0);
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
    vec3 size = v3((double)cells_along(mg, 0) * mg->cell, (double)cells_along(mg, 1) * mg->cell,
                   (double)cells_along(mg, 2) * mg->cell);
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
                majorant_bounds c =
                    cell_of(mg, v3(o.x + tm * d.x, o.y + tm * d.y, o.z + tm * d.z));
                /* the cell's bounds, or 0 outside the cell's box */
                assert_true((c.max == (float)s.max && c.min == (float)s.min) || s.max == 0.0);
            }
            assert_true(n < 3 * (cells_along(mg, 0) + cells_along(mg, 1) + cells_along(mg, 2)));
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

/* A coarse walk (majorant_walk_coarsen) covers the same span as the fine one
 * with at most a step per brick crossed; every interval of the fine walk
 * that holds density lies in one of the coarse walk's that does, under
 * bounds at least as wide: a marching consumer samples the same places and
 * skips only space the fine walk calls empty. */
static void coarse_walk_covers_fine(const char *file, bool dense)
{
    fixture f = build(file, 0);
    const majorant_grid *mg = &f.mg;
    rng r = rng_seeded(5);
    vec3 lo = v3(mg->origin[0], mg->origin[1], mg->origin[2]);
    double edge = (double)MAJORANT_BRICK * mg->cell;
    vec3 size = v3(mg->res[0] * edge, mg->res[1] * edge, mg->res[2] * edge);
    int hits = 0;
    int64_t all_f = 0, all_c = 0;
    for (int i = 0; i < 4000; ++i) {
        vec3 o = v3(lo.x + (rng_uniform(&r) * 1.4 - 0.2) * size.x,
                    lo.y + (rng_uniform(&r) * 1.4 - 0.2) * size.y,
                    lo.z + (rng_uniform(&r) * 1.4 - 0.2) * size.z);
        vec3 d = v3(rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5);
        double t1 = 4.0 * (size.x + size.y + size.z);
        majorant_walk fine, coarse;
        bool a = majorant_walk_start(&fine, mg, o, d, 0.0, t1);
        bool b = majorant_walk_start(&coarse, mg, o, d, 0.0, t1);
        assert_true(a == b);
        if (!a)
            continue;
        ++hits;
        majorant_walk_coarsen(&coarse, 0.5 * edge - 1e-9); /* just under: still fine */
        assert_false(coarse.coarse);
        majorant_walk_coarsen(&coarse, 0.5 * edge);
        assert_true(coarse.coarse);
        enum { MAX_COARSE = 4096 };
        static majorant_segment cs[MAX_COARSE];
        int nc = 0, nf = 0, k = 0;
        while (majorant_walk_next(&coarse, &cs[nc])) {
            assert_true(nc == 0 || cs[nc].t0 == cs[nc - 1].t1);
            assert_true(++nc < MAX_COARSE);
        }
        majorant_segment fs;
        double first = NAN;
        while (majorant_walk_next(&fine, &fs)) {
            if (nf++ == 0)
                first = fs.t0;
            if (!(fs.max > 0.0) && !(fs.emit > 0.0))
                continue;
            /* a fine interval that holds density: inside a coarse one that does */
            while (k < nc && !(cs[k].t1 >= fs.t1 - 1e-9 * (1.0 + fabs(fs.t1))))
                ++k;
            assert_true(k < nc);
            assert_true(cs[k].t0 <= fs.t0 + 1e-9 * (1.0 + fabs(fs.t0)));
            assert_true(cs[k].max >= fs.max && cs[k].min <= fs.min && cs[k].emit >= fs.emit);
        }
        assert_true(nc >= 1 && cs[0].t0 == first && cs[nc - 1].t1 == fs.t1); /* the same span */
        all_f += nf;
        all_c += nc;
        /* a step per brick crossed at most: bricks along each axis, plus one */
        assert_true(nc <= mg->res[0] + mg->res[1] + mg->res[2] + 1);
    }
    assert_true(hits > 1000);
    /* Where density fills most of the bricks it touches, fewer steps (on
     * smoke.vdb 2577 against 4520); on the sparse balls more (4044 against
     * 2910: a ray through only the empty cells of a brick that holds
     * density is part of an empty run of the fine walk, a brick of the
     * coarse one), but never over a step per brick. */
    if (dense)
        assert_true(all_c < 0.7 * all_f);
    destroy(&f);
}

static void coarse_walk_covers_fine_on_every_volume(void **state)
{
    (void)state;
    coarse_walk_covers_fine(VOLUMES "smoke.vdb", true);
    coarse_walk_covers_fine(VOLUMES "sparse.vdb", false);
}

/* The cells' boxes: along random rays, every interval reported empty inside
 * a cell that holds density (cut off by the cell's box) reads exactly 0 at
 * points all along it, also moved by up to `pad` voxels (a velocity field's
 * reach), on every volume; on the sparse one (eight balls, 1% of the box)
 * the boxes cut most of the length the cells' bounds would march. */
static void boxes_hold_no_density(const char *file, int32_t pad, double least_cut)
{
    fixture f = build(file, pad);
    const majorant_grid *mg = &f.mg;
    assert_true(mg->boxed);
    grid_accessor acc;
    grid_accessor_init(f.g, &acc);
    rng r = rng_seeded(11);
    vec3 lo = v3(mg->origin[0], mg->origin[1], mg->origin[2]);
    vec3 size = v3((double)cells_along(mg, 0) * mg->cell, (double)cells_along(mg, 1) * mg->cell,
                   (double)cells_along(mg, 2) * mg->cell);
    double cut = 0.0, kept = 0.0;
    int checked = 0;
    for (int i = 0; i < 4000; ++i) {
        vec3 o = v3(lo.x + rng_uniform(&r) * size.x, lo.y + rng_uniform(&r) * size.y,
                    lo.z + rng_uniform(&r) * size.z);
        vec3 d = v3(rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5);
        if (i % 8 == 0) /* axis-parallel too */
            d = i % 24 == 0 ? v3(0, 0, -1) : i % 24 == 8 ? v3(1, 0, 0) : v3(0, 1, 0);
        majorant_walk w;
        if (!majorant_walk_start(&w, mg, o, d, -1000.0, 1000.0))
            continue;
        majorant_segment s;
        while (majorant_walk_next(&w, &s)) {
            double len = s.t1 - s.t0;
            if (!(len > 0.0))
                continue;
            majorant_bounds c;
            double tm = 0.5 * (s.t0 + s.t1);
            if (!majorant_grid_bounds_at(mg, v3(o.x + tm * d.x, o.y + tm * d.y, o.z + tm * d.z), &c))
                continue;
            if (!(c.max > 0.0f))
                continue;
            if (s.max > 0.0) {
                kept += len;
                continue;
            }
            cut += len;
            for (int k = 0; k <= 16; ++k) {
                double t = s.t0 + len * k / 16.0;
                vec3 p = v3(o.x + t * d.x, o.y + t * d.y, o.z + t * d.z);
                vec3 q = v3(p.x + pad * (2.0 * rng_uniform(&r) - 1.0),
                            p.y + pad * (2.0 * rng_uniform(&r) - 1.0),
                            p.z + pad * (2.0 * rng_uniform(&r) - 1.0));
                double dp = grid_density_index(f.g, &acc, p), dq = grid_density_index(f.g, &acc, q);
                if (dp != 0.0 || dq != 0.0)
                    fail_msg("%s: density %g / %g at (%g %g %g) in an interval reported empty "
                             "[%.17g %.17g] k %d d (%g %g %g) o (%.17g %.17g %.17g)", file,
                             dp, dq, p.x, p.y, p.z, s.t0, s.t1, k, d.x, d.y, d.z, o.x, o.y, o.z);
                ++checked;
            }
        }
    }
    assert_true(checked > 1000);
    if (cut < least_cut * (cut + kept))
        fail_msg("%s: boxes cut %.3f of the length in non-empty cells, expected >= %.3f", file,
                 cut / (cut + kept), least_cut);
    destroy(&f);
}

static void boxes_hold_on_every_volume(void **state)
{
    (void)state;
    boxes_hold_no_density(VOLUMES "box.vdb", 0, 0.0);
    boxes_hold_no_density(VOLUMES "fog_sphere.vdb", 0, 0.0);
    boxes_hold_no_density(VOLUMES "smoke.vdb", 0, 0.05);
    boxes_hold_no_density(VOLUMES "smoke.vdb", 3, 0.0);
    boxes_hold_no_density(VOLUMES "plume.vdb", 0, 0.0);
    boxes_hold_no_density(VOLUMES "sparse.vdb", 0, 0.3);
    boxes_hold_no_density(VOLUMES "sparse.vdb", 2, 0.1);
}

/* With an emission grid (smoke.vdb's density standing in for the flame of
 * sparse.vdb's balls, or the balls themselves shifted) the boxes hold both:
 * every interval a box cut reads 0 in the density and in the emission,
 * whether the emission grid shares the density's index space or has voxels
 * of its own (half as many per axis and shifted, or shifted by 4.5 voxels). */
static void boxes_hold_emission_in(const char *emission_file, bool aligned, transform shifted)
{
    grid *g = NULL, *e = NULL;
    hz_error err = {0};
    if (grid_load(VOLUMES "sparse.vdb", "density", &g, &err) != HZ_OK ||
        grid_load(emission_file, "density", &e, &err) != HZ_OK)
        fail_msg("%s", err.message);
    vec3 lo, hi, elo, ehi;
    assert_true(grid_support_bounds(g, &lo, &hi));
    assert_true(grid_support_bounds(e, &elo, &ehi));
    lo = v3(fmin(lo.x, elo.x), fmin(lo.y, elo.y), fmin(lo.z, elo.z));
    hi = v3(fmax(hi.x, ehi.x), fmax(hi.y, ehi.y), fmax(hi.z, ehi.z));
    transform eindex_from_index = aligned ? transform_identity() : shifted;
    if (!aligned) { /* the support: the emission's box mapped into the density's index space */
        transform index_from_eindex = transform_inverse(eindex_from_index);
        transform_box(&index_from_eindex, elo, ehi, &elo, &ehi);
        assert_true(grid_support_bounds(g, &lo, &hi));
        lo = v3(fmin(lo.x, elo.x), fmin(lo.y, elo.y), fmin(lo.z, elo.z));
        hi = v3(fmax(hi.x, ehi.x), fmax(hi.y, ehi.y), fmax(hi.z, ehi.z));
    }
    majorant_emission em = {e, aligned, eindex_from_index};
    majorant_grid mg;
    int32_t pad[3] = {0, 0, 0};
    assert_int_equal(majorant_grid_build(g, &em, lo, hi, pad, &mg, &err), HZ_OK);
    assert_true(mg.boxed);
    grid_accessor ga, ea;
    grid_accessor_init(g, &ga);
    grid_accessor_init(e, &ea);
    rng r = rng_seeded(5);
    int checked = 0, glowing = 0;
    for (int i = 0; i < 4000; ++i) {
        vec3 o = v3(lo.x + rng_uniform(&r) * (hi.x - lo.x), lo.y + rng_uniform(&r) * (hi.y - lo.y),
                    lo.z + rng_uniform(&r) * (hi.z - lo.z));
        vec3 d = v3(rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5);
        majorant_walk w;
        if (!majorant_walk_start(&w, &mg, o, d, -1000.0, 1000.0))
            continue;
        majorant_segment s;
        while (majorant_walk_next(&w, &s)) {
            double len = s.t1 - s.t0;
            majorant_bounds c;
            double tm = 0.5 * (s.t0 + s.t1);
            if (!(len > 0.0) || s.max > 0.0 ||
                !majorant_grid_bounds_at(&mg, v3(o.x + tm * d.x, o.y + tm * d.y, o.z + tm * d.z), &c) ||
                !(c.max > 0.0f))
                continue; /* only intervals a box cut */
            glowing += c.emit > 0.0f;
            for (int k = 0; k <= 8; ++k) {
                double t = s.t0 + len * k / 8.0;
                vec3 p = v3(o.x + t * d.x, o.y + t * d.y, o.z + t * d.z);
                double dp = grid_density_index(g, &ga, p),
                       ep = grid_density_index(e, &ea, transform_point(&eindex_from_index, p));
                if (dp != 0.0 || ep != 0.0)
                    fail_msg("density %g, emission %g at (%g %g %g) in an interval reported empty",
                             dp, ep, p.x, p.y, p.z);
                ++checked;
            }
        }
    }
    assert_true(checked > 1000);
    assert_true(glowing > 0); /* cut cells where the emission grid is non-zero elsewhere */
    majorant_grid_free(&mg);
    grid_destroy(g);
    grid_destroy(e);
}

static void boxes_hold_emission(void **state)
{
    (void)state;
    boxes_hold_emission_in(VOLUMES "smoke.vdb", true, transform_identity());
    boxes_hold_emission_in(VOLUMES "smoke.vdb", false,
                           transform_compose(transform_translate(v3(3, -2, 5)),
                                             transform_scale(v3(0.5, 0.5, 0.5))));
    /* the balls' own flame, 4.5 voxels off: the cut edges meet it */
    boxes_hold_emission_in(VOLUMES "sparse.vdb", false, transform_translate(v3(4.5, 0, 0)));
}

static void empty_support_has_no_cells(void **state)
{
    (void)state;
    fixture f = build(VOLUMES "box.vdb", 0);
    majorant_grid empty;
    hz_error err = {0};
    int32_t pad[3] = {0, 0, 0};
    assert_int_equal(majorant_grid_build(f.g, NULL, v3(1, 1, 1), v3(-1, -1, -1), pad, &empty, &err),
                     HZ_OK);
    majorant_walk w;
    assert_false(majorant_walk_start(&w, &empty, v3(0, 0, 0), v3(1, 0, 0), 0.0, 100.0));
    majorant_grid_free(&empty);
    destroy(&f);
}

/* Supports spanning most of index space (voxels 3.3e7 and 2e9 apart, and
 * the whole int32 range) once overflowed the cell count (signed overflow,
 * then malloc(0) and writes). The grid stays within MAJORANT_MAX_BRICKS and
 * MAJORANT_MAX_STORED_CELLS, and every cell still bounds the data (box.vdb: 1
 * on [0,31]^3): the cell holding the box has the upper bound 1. */
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
        assert_int_equal(majorant_grid_build(f.g, NULL, lo, hi, pad, &mg, &err), HZ_OK);
        uint64_t bricks = (uint64_t)mg.res[0] * (uint64_t)mg.res[1] * (uint64_t)mg.res[2];
        assert_true(bricks >= 1 && bricks <= MAJORANT_MAX_BRICKS);
        size_t sb, sc;
        majorant_grid_count(&mg, &sb, &sc);
        assert_true(sc <= MAJORANT_MIN_STORED_CELLS);
        assert_true(cell_of(&mg, v3(16, 16, 16)).max == 1.0f);
        majorant_grid_free(&mg);
    }
    destroy(&f);
}

/* Memory follows the active data, not the support's box: box.vdb (32^3
 * voxels) over a support of 2048^3 keeps leaf-sized cells, stores the cells
 * of the 8 bricks that touch it only, and of those only the 6^3 cells that
 * hold something (the box [0, 31] read one voxel out, and one more for
 * rounding: cells -8 .. 39; the dense grid of cells would be 256^3 x 12
 * bytes = 192 MiB; this is under 0.6 MiB), and a ray through empty space is
 * one interval, however many bricks and cells it crosses. */
static void memory_follows_active_data(void **state)
{
    (void)state;
    fixture f = build(VOLUMES "box.vdb", 0);
    majorant_grid mg;
    hz_error err = {0};
    int32_t pad[3] = {0, 0, 0};
    assert_int_equal(
        majorant_grid_build(f.g, NULL, v3(-1024, -1024, -1024), v3(1023, 1023, 1023), pad, &mg, &err),
        HZ_OK);
    assert_int_equal(mg.cell, 8);
    assert_int_equal(mg.res[0], 32);
    size_t sb, sc;
    majorant_grid_count(&mg, &sb, &sc);
    assert_int_equal(sb, 8);
    assert_int_equal(sc, 6 * 6 * 6);
    assert_true(majorant_grid_bytes(&mg) < 600 * 1024);
    assert_true(cell_of(&mg, v3(16, 16, 16)).min == 1.0f);
    assert_true(cell_of(&mg, v3(500, -700, 3)).max == 0.0f);

    majorant_walk w;
    majorant_segment s;
    assert_true(majorant_walk_start(&w, &mg, v3(-2000, -500, -500), v3(1, 0, 0), 0.0, 5000.0));
    int n = 0;
    while (majorant_walk_next(&w, &s)) {
        assert_true(s.max == 0.0 && s.t0 == 976.0 && s.t1 == 3024.0);
        ++n;
    }
    assert_int_equal(n, 1);
    /* Through the box: the empty space before it, its 6 cells, the empty
     * space after it. */
    assert_true(majorant_walk_start(&w, &mg, v3(-2000, 12, 12), v3(1, 0, 0), 0.0, 5000.0));
    n = 0;
    double lit = 0.0;
    while (majorant_walk_next(&w, &s)) {
        ++n;
        lit += s.max > 0.0 ? s.t1 - s.t0 : 0.0;
    }
    /* and the cells at the box's faces split where their box begins and
     * ends: the density is 0 below x = -1 and from x = 32 on, and a voxel
     * more absorbs rounding */
    assert_int_equal(n, 1 + 6 + 1);
    assert_true(fabs(lit - 35.0) < 1e-9); /* [-2, 33) */
    majorant_grid_free(&mg);
    destroy(&f);
}

/* Every brick of a and b as walks see it (majorant_grid_brick: built at
 * first use or not), bit for bit: bounds, cell maps, cells and boxes. */
static void same_bricks(const majorant_grid *a, const majorant_grid *b, const char *what,
                        int32_t pad)
{
    size_t bricks = (size_t)a->res[0] * (size_t)a->res[1] * (size_t)a->res[2];
    for (size_t i = 0; i < bricks; ++i) {
        majorant_bounds ba, bb;
        const majorant_cellmap *ma = majorant_grid_brick(a, i, &ba);
        const majorant_cellmap *mb = majorant_grid_brick(b, i, &bb);
        if (memcmp(&ba, &bb, sizeof ba) != 0 || (ma == NULL) != (mb == NULL))
            fail_msg("%s, pad %d: brick %zu differs", what, pad, i);
        /* coarse walks read a brick not built yet by the bounds it has */
        if (a->brick_bounds_exact && memcmp(&a->bricks[i].bounds, &ba, sizeof ba) != 0)
            fail_msg("%s, pad %d: brick %zu's bounds change when built", what, pad, i);
        if (!ma)
            continue;
        size_t n = 0;
        for (int w = 0; w < MAJORANT_MAP_WORDS; ++w)
            n += majorant_popcount(ma->occupied[w]);
        if (memcmp(ma->occupied, mb->occupied, sizeof ma->occupied) != 0 ||
            memcmp(ma->before, mb->before, sizeof ma->before) != 0 ||
            memcmp(ma->cells, mb->cells, n * sizeof *ma->cells) != 0)
            fail_msg("%s, pad %d: the cells of brick %zu differ", what, pad, i);
        if ((ma->boxes == NULL) != (mb->boxes == NULL) ||
            (ma->boxes && memcmp(ma->boxes, mb->boxes, n * sizeof *ma->boxes) != 0))
            fail_msg("%s, pad %d: the boxes of brick %zu differ", what, pad, i);
    }
}

/* majorant_grid_build (the tree walked once per brick, the cells at their
 * first use where they fit) of g and majorant_grid_build_by_queries (one
 * query per brick and cell, every brick at once) of q make the same grid,
 * bit for bit: layout, bricks, cells and boxes. */
static void same_as_by_queries_of(const grid *g, const grid *q, const majorant_emission *em,
                                  vec3 lo, vec3 hi, int32_t pad, const char *what)
{
    majorant_grid a, b;
    hz_error err = {0};
    int32_t p[3] = {pad, pad + 1, 2 * pad}; /* unequal axes too */
    assert_int_equal(majorant_grid_build(g, em, lo, hi, p, &a, &err), HZ_OK);
    assert_int_equal(majorant_grid_build_by_queries(q, em, lo, hi, p, &b, &err), HZ_OK);
    assert_null(b.lazy); /* the reference builds every brick at once */
    assert_int_equal(majorant_grid_work(&b).bricks, 0);
    if (memcmp(a.res, b.res, sizeof a.res) != 0 || memcmp(a.origin, b.origin, sizeof a.origin) != 0 ||
        a.cell != b.cell || a.boxed != b.boxed)
        fail_msg("%s, pad %d: the layouts differ", what, pad);
    same_bricks(&a, &b, what, pad);
    size_t ab, ac, bb, bc;
    majorant_grid_count(&a, &ab, &ac);
    majorant_grid_count(&b, &bb, &bc);
    if (ab != bb || ac != bc)
        fail_msg("%s, pad %d: %zu and %zu bricks store %zu and %zu cells", what, pad, ab, bb, ac, bc);
    majorant_grid_free(&a);
    majorant_grid_free(&b);
}

static void same_as_by_queries(const grid *g, const majorant_emission *em, vec3 lo, vec3 hi,
                               int32_t pad, const char *what)
{
    same_as_by_queries_of(g, g, em, lo, hi, pad, what);
}

/* A checked grid's build takes each leaf from the check's table of leaf
 * statistics (grid_blocks, partial leaves' supports); the queries of the
 * same grid without the table read the leaves. */
static void bottom_up_is_by_queries(void **state)
{
    (void)state;
    const char *files[] = {"box.vdb",  "box_inactive.vdb", "fog_sphere.vdb", "sheet.vdb",
                           "smoke.vdb", "plume.vdb",       "sparse.vdb",     "explosion.vdb"};
    int stored = 0, boxed = 0, left = 0;
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[512];
        snprintf(path, sizeof path, "%s%s", VOLUMES, files[i]);
        grid *g = NULL, *q = NULL;
        hz_error err = {0};
        if (grid_load(path, "density", &g, &err) != HZ_OK || grid_check_density(g, &err) != HZ_OK ||
            grid_load(path, "density", &q, &err) != HZ_OK || grid_check_density(q, &err) != HZ_OK)
            fail_msg("%s", err.message);
        grid_drop_leaf_stats(q);
        vec3 lo, hi;
        assert_true(grid_support_bounds(g, &lo, &hi));
        for (int32_t pad = 0; pad <= 9; pad += 3)
            same_as_by_queries_of(g, q, NULL, lo, hi, pad, files[i]);
        /* a support wider than the data, off centre: empty bricks and
         * windows past the tree's nodes */
        same_as_by_queries_of(g, q, NULL, v3(lo.x - 300, lo.y - 40, lo.z),
                              v3(hi.x + 90, hi.y, hi.z + 700), 0, files[i]);
        majorant_grid mg;
        int32_t p0[3] = {0, 0, 0};
        assert_int_equal(majorant_grid_build(g, NULL, lo, hi, p0, &mg, &err), HZ_OK);
        /* The work report counts each first use: none yet, then every
         * brick left to it once, and nothing more on a second count. */
        size_t waiting = 0;
        for (size_t b = 0; b < (size_t)mg.res[0] * mg.res[1] * mg.res[2]; ++b)
            waiting += mg.bricks[b].cells <= MAJORANT_BRICK_LAZY;
        majorant_work w = majorant_grid_work(&mg);
        assert_int_equal(w.bricks, 0);
        assert_true(w.seconds == 0.0);
        size_t sb, sc;
        majorant_grid_count(&mg, &sb, &sc);
        w = majorant_grid_work(&mg);
        assert_int_equal(w.bricks, waiting);
        assert_true(waiting == 0 ? w.seconds == 0.0 : w.seconds > 0.0);
        majorant_grid_count(&mg, &sb, &sc);
        assert_int_equal(majorant_grid_work(&mg).bricks, waiting);
        stored += sb > 0;
        boxed += mg.boxed;
        left += mg.lazy != NULL;
        majorant_grid_free(&mg);
        grid_destroy(g);
        grid_destroy(q);
    }
    assert_true(stored >= 6); /* the comparisons saw cells, not only bricks */
    assert_true(boxed >= 6);
    assert_true(left >= 6); /* ... and bricks built at their first use */
}

/* ... and with an emission grid, in the density's index space or not. */
static void bottom_up_is_by_queries_with_emission(void **state)
{
    (void)state;
    grid *g = NULL, *e = NULL;
    hz_error err = {0};
    if (grid_load(VOLUMES "sparse.vdb", "density", &g, &err) != HZ_OK ||
        grid_load(VOLUMES "smoke.vdb", "density", &e, &err) != HZ_OK)
        fail_msg("%s", err.message);
    vec3 lo, hi, elo, ehi;
    assert_true(grid_support_bounds(g, &lo, &hi));
    assert_true(grid_support_bounds(e, &elo, &ehi));
    lo = v3(fmin(lo.x, elo.x), fmin(lo.y, elo.y), fmin(lo.z, elo.z));
    hi = v3(fmax(hi.x, ehi.x), fmax(hi.y, ehi.y), fmax(hi.z, ehi.z));
    majorant_emission aligned = {e, true, transform_identity()};
    majorant_emission moved = {e, false,
                               transform_compose(transform_translate(v3(3, -2, 5)),
                                                 transform_scale(v3(0.5, 0.5, 0.5)))};
    for (int32_t pad = 0; pad <= 2; pad += 2) {
        same_as_by_queries(g, &aligned, lo, hi, pad, "sparse.vdb lit by smoke.vdb");
        same_as_by_queries(g, &moved, lo, hi, pad, "sparse.vdb lit by smoke.vdb, moved");
    }
    grid_destroy(g);
    grid_destroy(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(bounds_hold_on_every_volume),
        cmocka_unit_test(box_bounds_are_tight),
        cmocka_unit_test(padding_widens),
        cmocka_unit_test(walk_visits_crossed_cells),
        cmocka_unit_test(coarse_walk_covers_fine_on_every_volume),
        cmocka_unit_test(boxes_hold_on_every_volume),
        cmocka_unit_test(boxes_hold_emission),
        cmocka_unit_test(empty_support_has_no_cells),
        cmocka_unit_test(huge_supports_stay_bounded),
        cmocka_unit_test(memory_follows_active_data),
        cmocka_unit_test(bottom_up_is_by_queries),
        cmocka_unit_test(bottom_up_is_by_queries_with_emission),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
