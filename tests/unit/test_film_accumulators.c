/* film_get_accumulators: films that rendered disjoint pixels, summed element
 * by element in any order, are bit for bit the film that rendered them all
 * (the gather of an MPI render relies on it), including depth (Z = INFINITY
 * where no sample hit), the variance state, sample counts, zero and negative
 * weights and dropped non-finite samples. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "film/film.h"

enum { PARTS = 3 };

static film_params test_params(void)
{
    film_params p;
    film_params_default(&p);
    p.xres = 30;
    p.yres = 28;
    p.bounds = (pixel_bounds){2, 3, 26, 23};
    p.write_z = true;
    p.write_variance = true;
    p.write_sample_count = true;
    return p;
}

/* Which of the PARTS films renders pixel (x, y): an irregular pattern. */
static int owner(int x, int y) { return (x * 7 + y * 3 + (x * y) % 5) % PARTS; }

/* Deterministic samples of pixel (x, y), including awkward ones: zero and
 * negative weights with zero radiance (w * L = -0), misses (INFINITY depth),
 * non-finite radiance (dropped and counted). */
static void add_pixel_samples(film *f, int x, int y)
{
    uint64_t st = (uint64_t)(y * 1000 + x) * 0x9E3779B97F4A7C15ull + 1;
    int n = 1 + (x + y) % 6;
    for (int i = 0; i < n; ++i) {
        st = st * 6364136223846793005ull + 1442695040888963407ull;
        double u = (double)(st >> 11) * 0x1.0p-53;
        double w = (i % 4 == 1) ? -0.25 * u : (i % 4 == 3 ? 0.0 : 0.5 + u);
        rgb L = rgb_make(u * 3.0, (i % 3 == 0) ? 0.0 : u * u, 1.0 - u);
        if ((x + y + i) % 11 == 0)
            L = rgb_make(NAN, 0.0, 0.0);
        double depth = (i % 2 == 0) ? INFINITY : 1.0 + 10.0 * u;
        film_add_sample(f, x, y, L, w, depth);
    }
}

/* Adds src's accumulators to dst's, element by element. */
static void add_film(film *dst, film *src)
{
    film_accumulators a, b;
    film_get_accumulators(dst, &a);
    film_get_accumulators(src, &b);
    for (int k = 0; k < 3; ++k) {
        assert_int_equal(a.double_count[k], b.double_count[k]);
        for (size_t i = 0; i < a.double_count[k]; ++i)
            a.doubles[k][i] += b.doubles[k][i];
    }
    assert_int_equal(a.count_count, b.count_count);
    for (size_t i = 0; i < a.count_count; ++i)
        a.counts[i] += b.counts[i];
    film_add_nonfinite(dst, film_nonfinite_count(src));
}

static void assert_same_accumulators(film *x, film *y)
{
    film_accumulators a, b;
    film_get_accumulators(x, &a);
    film_get_accumulators(y, &b);
    for (int k = 0; k < 3; ++k) {
        assert_non_null(a.doubles[k]);
        assert_int_equal(a.double_count[k], b.double_count[k]);
        assert_memory_equal(a.doubles[k], b.doubles[k], a.double_count[k] * sizeof(double));
    }
    assert_int_equal(a.count_count, b.count_count);
    assert_memory_equal(a.counts, b.counts, a.count_count * sizeof(uint32_t));
    assert_int_equal(film_nonfinite_count(x), film_nonfinite_count(y));
}

static void test_disjoint_films_sum_exactly(void **state)
{
    (void)state;
    film_params p = test_params();
    hz_error err = {0};
    film *all = film_create(&p, &err), *parts[PARTS], *again[PARTS];
    assert_non_null(all);
    for (int k = 0; k < PARTS; ++k) {
        parts[k] = film_create(&p, &err);
        again[k] = film_create(&p, &err);
        assert_non_null(parts[k]);
        assert_non_null(again[k]);
    }
    for (int y = p.bounds.y0; y < p.bounds.y1; ++y)
        for (int x = p.bounds.x0; x < p.bounds.x1; ++x) {
            add_pixel_samples(all, x, y);
            add_pixel_samples(parts[owner(x, y)], x, y);
            add_pixel_samples(again[owner(x, y)], x, y);
        }
    assert_true(film_nonfinite_count(all) > 0);

    /* (0 + 1) + 2 and (2 + 1) + 0: any reduction order. */
    add_film(parts[0], parts[1]);
    add_film(parts[0], parts[2]);
    assert_same_accumulators(parts[0], all);
    add_film(again[2], again[1]);
    add_film(again[2], again[0]);
    assert_same_accumulators(again[2], all);

    /* And so every output value, Z = INFINITY where nothing hit included. */
    film_accumulators acc;
    film_get_accumulators(all, &acc);
    int no_hit = 0;
    for (int y = p.bounds.y0; y < p.bounds.y1; ++y)
        for (int x = p.bounds.x0; x < p.bounds.x1; ++x) {
            rgb a = film_get_pixel(all, x, y, 1.0), b = film_get_pixel(parts[0], x, y, 1.0);
            assert_memory_equal(&a, &b, sizeof a);
            rgb va = film_get_variance(all, x, y, 1.0), vb = film_get_variance(parts[0], x, y, 1.0);
            assert_memory_equal(&va, &vb, sizeof va);
            assert_int_equal(film_get_sample_count(all, x, y), film_get_sample_count(parts[0], x, y));
            size_t i = (size_t)(y - p.bounds.y0) * 24 + (size_t)(x - p.bounds.x0);
            if ((x + y) % 6 == 0) { /* one sample (i = 0), a miss: Z = INFINITY */
                assert_true(acc.doubles[1][2 * i + 1] == 0.0);
                ++no_hit;
            }
        }
    assert_true(no_hit > 0);

    film_destroy(all);
    for (int k = 0; k < PARTS; ++k) {
        film_destroy(parts[k]);
        film_destroy(again[k]);
    }
}

/* Where no sample landed every accumulator is +0 (not -0), and zero or
 * negative weights with zero radiance do not make a -0 either: x + 0 = x then
 * holds for every element. */
static void test_untouched_and_zero_samples_are_plus_zero(void **state)
{
    (void)state;
    film_params p = test_params();
    hz_error err = {0};
    film *f = film_create(&p, &err);
    assert_non_null(f);
    film_add_sample(f, 5, 5, rgb_grey(0.0), -1.0, INFINITY);
    film_add_sample(f, 6, 5, rgb_grey(0.0), 0.0, 2.0);
    film_add_sample(f, 6, 5, rgb_grey(0.0), -0.0, 2.0);
    film_accumulators a;
    film_get_accumulators(f, &a);
    size_t n = 0;
    for (int k = 0; k < 3; ++k)
        for (size_t i = 0; i < a.double_count[k]; ++i, ++n)
            if (a.doubles[k][i] == 0.0)
                assert_false(signbit(a.doubles[k][i]));
    assert_int_equal(n, (size_t)24 * 20 * (4 + 2 + 8));
    film_destroy(f);

    /* A film without the optional AOVs has only the pixel sums. */
    p.write_z = p.write_variance = p.write_sample_count = false;
    f = film_create(&p, &err);
    assert_non_null(f);
    film_get_accumulators(f, &a);
    assert_int_equal(a.double_count[0], (size_t)24 * 20 * 4);
    assert_null(a.doubles[1]);
    assert_null(a.doubles[2]);
    assert_null(a.counts);
    assert_int_equal(a.count_count, 0);
    film_destroy(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_disjoint_films_sum_exactly),
        cmocka_unit_test(test_untouched_and_zero_samples_are_plus_zero),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
