/* Perlin noise (media/noise.h) and pbrt-v4's procedural cloud density
 * (media/cloud.h): properties that pin them down. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "media/cloud.h"
#include "core/noise.h"

/* Gradient noise is 0 at every lattice point, within [-1, 1], periodic with
 * period 256, continuous, and not constant. */
static void noise_properties(void **state)
{
    (void)state;
    for (int x = -3; x < 4; ++x)
        for (int y = 0; y < 3; ++y)
            assert_true(noise3((float)x, (float)y, 7.0f) == 0.0f);
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (int i = 0; i < 20000; ++i) {
        float x = 0.0037f * i, y = 0.00113f * i + 0.5f, z = 0.00071f * i + 0.25f;
        float v = noise3(x, y, z);
        assert_true(v >= -1.0f && v <= 1.0f);
        assert_true(fabsf(noise3(x + 256.0f, y, z) - v) < 1e-4f);
        assert_true(fabsf(noise3(x + 1e-4f, y, z) - v) < 1e-2f);
        sum += v;
        sum2 += v * v;
        ++n;
    }
    double mean = sum / n, sd = sqrt(sum2 / n - mean * mean);
    assert_true(fabs(mean) < 0.02);
    assert_true(sd > 0.1 && sd < 0.5);
}

/* Below y = 0 the cloud is solid (2 (0.5 - y) >= 1 after the clamp); at
 * y = 1 both terms vanish; in between it is noise in [0, 1]. */
static void cloud_density_regions(void **state)
{
    (void)state;
    cloud_params c = {2.0f, 1.0f, 5.0f};
    double lo = 1.0, hi = 0.0;
    for (int i = 0; i < 2000; ++i) {
        double x = 0.0137 * i, z = 0.0271 * i;
        assert_true(cloud_density(&c, v3(x, -0.01 - 0.001 * (i % 500), z)) == 1.0);
        assert_true(cloud_density(&c, v3(x, 1.0, z)) == 0.0);
        double d = cloud_density(&c, v3(x, 0.55 + 0.0002 * i, z));
        assert_true(d >= 0.0 && d <= 1.0);
        lo = fmin(lo, d);
        hi = fmax(hi, d);
    }
    assert_true(lo == 0.0 && hi > 0.5); /* both clear air and dense puffs */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(noise_properties),
        cmocka_unit_test(cloud_density_regions),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
