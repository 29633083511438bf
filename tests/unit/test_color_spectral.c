/* color/spectral: the error RGB rendering makes on a product of two colours
 * (what --color auto decides by), against values worked out by hand from
 * the tables: greys scale a spectrum exactly, a white light reflects a
 * colour as its RGB, saturated colours times themselves do not. */
#include "assert_util.h"

#include "color/rgb2spec_module.h"
#include "color/spectral.h"

static double product_error(const rgb2spec_table *t, spectrum_value a, spectrum_value b)
{
    spectral_samples sa, sb;
    spectral_samples_make(t, &a, &sa);
    spectral_samples_make(t, &b, &sb);
    return spectral_product_error(t, &sa, &sb);
}

static void test_product_errors(void **state)
{
    (void)state;
    const rgb2spec_table *tables = NULL;
    hz_error err;
    assert_int_equal(rgb2spec_tables_load(&tables, &err), HZ_OK);
    const rgb2spec_table *t = &tables[COLOR_SPACE_SRGB];
    spectrum_value red = spectrum_value_rgb(rgb_make(0.6, 0.12, 0.1), SPECTRUM_USE_ALBEDO);
    spectrum_value grey = spectrum_value_rgb(rgb_grey(0.5), SPECTRUM_USE_ALBEDO);
    spectrum_value near_grey = spectrum_value_rgb(rgb_make(0.7, 0.7, 0.68), SPECTRUM_USE_ALBEDO);
    spectrum_value white = spectrum_value_rgb(rgb_grey(1.0), SPECTRUM_USE_ILLUMINANT);
    spectrum_value blue = spectrum_value_rgb(rgb_make(1.5, 3.0, 6.0), SPECTRUM_USE_ILLUMINANT);
    /* The tables' own round trip (< 1e-3 over their largest channel). */
    assert_true(product_error(t, grey, red) < 2e-3);
    assert_true(product_error(t, white, red) < 2e-3);
    assert_true(product_error(t, near_grey, near_grey) < 2e-3);
    /* Two bounces of a saturated red: the green channel's 0.0144 is 0.0023
     * spectrally, red 0.36 is 0.349: 3.5% of 0.36. */
    double e = product_error(t, red, red);
    assert_true(e > 0.03 && e < 0.04);
    /* A blue light on it: far off (red 0.90 in RGB, about 1.09). */
    assert_true(product_error(t, blue, red) > 0.15);
    /* Black: nothing to be wrong about. */
    spectrum_value black = spectrum_value_rgb(rgb_grey(0.0), SPECTRUM_USE_ALBEDO);
    assert_true(product_error(t, black, red) == 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_product_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
