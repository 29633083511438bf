/* color/rgb2spec_module: the RGB -> spectrum tables come from the module
 * libhaze_rgb2spec.so, found in the build tree by this test program; a module
 * that cannot be loaded is one line naming the path tried and why, and a
 * later load from the right place still works. */
#define _POSIX_C_SOURCE 200809L
#include "assert_util.h"

#include <stdlib.h>
#include <string.h>

#include "color/rgb2spec_module.h"
#include "color/rgb_spectrum.h"

static void test_loads_every_space(void **state)
{
    (void)state;
    const rgb2spec_table *a = NULL, *b = NULL;
    hz_error err;
    assert_int_equal(rgb2spec_tables_load(&a, &err), HZ_OK);
    assert_int_equal(rgb2spec_tables_load(&b, &err), HZ_OK);
    assert_ptr_equal(a, b); /* the same module, loaded once */
    for (int cs = 0; cs < COLOR_SPACE_COUNT; ++cs) {
        const rgb2spec_solution *s = a[cs].solution;
        assert_int_equal(a[cs].cs, cs);
        assert_true(s->res >= 4);
        /* The nodes run from 0 to 1 and increase. */
        assert_near(s->z_nodes[0], 0.0, 0.0);
        assert_near(s->z_nodes[s->res - 1], 1.0, 0.0);
        for (int k = 1; k < s->res; ++k)
            assert_true(s->z_nodes[k] > s->z_nodes[k - 1] &&
                        s->xy_nodes[k] > s->xy_nodes[k - 1]);
        assert_near(s->white_xyz[1], 1.0, 1e-6);
    }
    /* A grey is its own exact polynomial; a colour goes through the table. */
    sigmoid_poly grey = sigmoid_poly_from_rgb(&a[COLOR_SPACE_SRGB], rgb_grey(0.5));
    assert_near(sigmoid_poly_eval(grey, 500.0), 0.5, 0.0);
    sigmoid_poly red = sigmoid_poly_from_rgb(&a[COLOR_SPACE_SRGB], rgb_make(0.8, 0.1, 0.1));
    assert_true(sigmoid_poly_eval(red, 650.0) > 0.7 && sigmoid_poly_eval(red, 450.0) < 0.2);
}

/* Loads with HAZE_RGB2SPEC_MODULE set to `path`: must fail, with one line
 * that names the path and contains `why`. */
static void expect_failure(const char *path, const char *why)
{
    assert_int_equal(setenv("HAZE_RGB2SPEC_MODULE", path, 1), 0);
    const rgb2spec_table *t = (const rgb2spec_table *)&t;
    hz_error err = {0};
    hz_status st = rgb2spec_tables_load(&t, &err);
    assert_int_equal(unsetenv("HAZE_RGB2SPEC_MODULE"), 0);
    print_message("%s\n", err.message);
    assert_int_equal(st, HZ_ERROR);
    assert_null(t);
    assert_non_null(strstr(err.message, "cannot load the RGB -> spectrum tables"));
    assert_non_null(strstr(err.message, path));
    assert_non_null(strstr(err.message, why));
    assert_non_null(strstr(err.message, "HAZE_RGB2SPEC_MODULE"));
    assert_null(strchr(err.message, '\n'));
}

static void test_missing_module_is_an_error(void **state)
{
    (void)state;
    expect_failure("/nonexistent/libhaze_rgb2spec.so", "No such file");
    /* Not a shared object: this test's own source. */
    expect_failure(HAZE_TESTS "/unit/test_color_rgb2spec_module.c", "");
    /* With the variable gone the build tree's module is found again. */
    const rgb2spec_table *t = NULL;
    hz_error err;
    assert_int_equal(rgb2spec_tables_load(&t, &err), HZ_OK);
    assert_int_equal(t[COLOR_SPACE_DCI_P3].cs, COLOR_SPACE_DCI_P3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_loads_every_space),
        cmocka_unit_test(test_missing_module_is_an_error),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
