/* The filter sampler's guide tables (src/film/filter.c) give exactly the
 * intervals of the plain binary search, so images do not change: checked
 * here on the file's own static functions (it is compiled into this test;
 * the library's copy is then not linked). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "film/filter.c"
#include "unit/filter_util.h"


static uint64_t xorshift(uint64_t *x)
{
    *x ^= *x << 13;
    *x ^= *x >> 7;
    *x ^= *x << 17;
    return *x;
}

/* One cdf: random u, every entry and its neighbours in double, the bucket
 * boundaries j / FILTER_GUIDE and theirs, 0 and 1 - epsilon. */
static long check_cdf(const double *cdf, size_t n, const uint32_t *g)
{
    long checked = 0;
    uint64_t rng = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < 20000; ++i) {
        double u = (double)(xorshift(&rng) >> 11) * 0x1p-53;
        assert_int_equal(find_interval_guided(cdf, n, g, u), find_interval(cdf, n, u));
        ++checked;
    }
    for (size_t i = 0; i <= n; ++i)
        for (int k = -1; k <= 1; ++k) {
            double u = k < 0 ? nextafter(cdf[i], -1.0) : k > 0 ? nextafter(cdf[i], 2.0) : cdf[i];
            if (!(u >= 0.0 && u < 1.0))
                continue;
            assert_int_equal(find_interval_guided(cdf, n, g, u), find_interval(cdf, n, u));
            ++checked;
        }
    for (int j = 0; j <= FILTER_GUIDE; ++j)
        for (int k = -1; k <= 1; ++k) {
            double b = (double)j / FILTER_GUIDE;
            double u = k < 0 ? nextafter(b, -1.0) : k > 0 ? nextafter(b, 2.0) : b;
            if (!(u >= 0.0 && u < 1.0))
                continue;
            assert_int_equal(find_interval_guided(cdf, n, g, u), find_interval(cdf, n, u));
            ++checked;
        }
    assert_int_equal(find_interval_guided(cdf, n, g, ONE_MINUS_EPSILON),
                     find_interval(cdf, n, ONE_MINUS_EPSILON));
    return checked + 1;
}

static void test_guided_equals_binary_search(void **state)
{
    (void)state;
    /* Each tabulated filter; the gaussian's and lanczos' (negative lobes)
     * tables have zero-width cells at their rims. */
    const char *types[] = {"gaussian", "mitchell", "sinc"};
    for (size_t t = 0; t < sizeof types / sizeof *types; ++t) {
        filter *f = make_filter(types[t]);
        size_t nx = (size_t)f->nx, ny = (size_t)f->ny;
        long checked = check_cdf(f->marg_cdf, ny, f->marg_guide);
        for (size_t y = 0; y < ny; ++y)
            checked += check_cdf(f->row_cdf + y * (nx + 1), nx, f->row_guide + y * (FILTER_GUIDE + 1));
        print_message("%s: %zux%zu table, %ld lookups the same\n", types[t], nx, ny, checked);
        filter_destroy(f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_guided_equals_binary_search),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
