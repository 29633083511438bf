/* core/sampling: warps land in their domains and have the stated densities
 * (checked by moments with known closed forms). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "core/sampling.h"
#include "core/vec.h"
#include "unit/assert_util.h"

enum { N = 200000 };

static void test_disks(void **state)
{
    (void)state;
    uint64_t rng = 1;
    double inner_c = 0, inner_p = 0, mean_r2 = 0;
    for (int i = 0; i < N; ++i) {
        vec2 u = v2(rng_next(&rng), rng_next(&rng));
        vec2 c = sample_uniform_disk_concentric(u), p = sample_uniform_disk_polar(u);
        double rc = hypot(c.x, c.y), rp = hypot(p.x, p.y);
        assert_true(rc <= 1 + 1e-15 && rp <= 1 + 1e-15);
        inner_c += rc < 0.5;
        inner_p += rp < 0.5;
        mean_r2 += rc * rc;
    }
    /* Uniform by area: a quarter of the samples within r = 1/2, E[r^2] = 1/2. */
    assert_near(inner_c / N, 0.25, 0.005);
    assert_near(inner_p / N, 0.25, 0.005);
    assert_near(mean_r2 / N, 0.5, 0.003);
}

static void test_regular_polygon(void **state)
{
    (void)state;
    assert_near(sample_regular_polygon_area(4), 2.0, 1e-15);
    assert_near(sample_regular_polygon_area(6), 3 * sqrt(3.0) / 2, 1e-15);
    assert_near(sample_regular_polygon_area(3), 3 * sqrt(3.0) / 4, 1e-15);
    /* A square with a vertex at 45 degrees is the axis-aligned [-a, a]^2, a = 1/sqrt2. */
    double a = sqrt(0.5), rot = HZ_PI / 4;
    assert_true(regular_polygon_contains(4, rot, v2(0.7, -0.7), 0));
    assert_false(regular_polygon_contains(4, rot, v2(0.72, 0), 0));
    uint64_t rng = 2;
    double mx2 = 0, quadrant = 0;
    for (int i = 0; i < N; ++i) {
        vec2 p = sample_regular_polygon(4, rot, v2(rng_next(&rng), rng_next(&rng)));
        assert_true(fabs(p.x) <= a + 1e-15 && fabs(p.y) <= a + 1e-15);
        mx2 += p.x * p.x;
        quadrant += p.x > 0 && p.y > 0;
    }
    assert_near(mx2 / N, a * a / 3, 0.003); /* uniform on [-a, a]: E[x^2] = a^2/3 */
    assert_near(quadrant / N, 0.25, 0.005);
    /* The corners of the unit square map inside too. */
    const vec2 corners[] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.999999, 0.999999}};
    for (int n = 3; n < 12; ++n)
        for (size_t k = 0; k < 5; ++k)
            assert_true(regular_polygon_contains(
                n, 0.1 * n, sample_regular_polygon(n, 0.1 * n, corners[k]), 1e-12));
}

static void test_triangle(void **state)
{
    (void)state;
    uint64_t rng = 3;
    double m0 = 0, m1 = 0;
    for (int i = 0; i < N; ++i) {
        vec2 b = sample_uniform_triangle(v2(rng_next(&rng), rng_next(&rng)));
        assert_true(b.x >= 0 && b.y >= 0 && b.x + b.y <= 1 + 1e-15);
        m0 += b.x;
        m1 += b.y;
    }
    assert_near(m0 / N, 1.0 / 3, 0.003);
    assert_near(m1 / N, 1.0 / 3, 0.003);
}

static void test_sphere_and_hemispheres(void **state)
{
    (void)state;
    uint64_t rng = 4;
    double s_z = 0, s_z2 = 0, h_z = 0, c_z = 0, cone_z = 0;
    const double cos_max = cos(0.3);
    for (int i = 0; i < N; ++i) {
        vec2 u = v2(rng_next(&rng), rng_next(&rng));
        vec3 s = sample_uniform_sphere(u), h = sample_uniform_hemisphere(u);
        vec3 c = sample_cosine_hemisphere(u), k = sample_uniform_cone(u, cos_max);
        assert_near(v3_length(s), 1, 1e-12);
        assert_near(v3_length(h), 1, 1e-12);
        assert_near(v3_length(c), 1, 1e-12);
        assert_near(v3_length(k), 1, 1e-12);
        assert_true(h.z >= 0 && c.z >= 0 && k.z >= cos_max - 1e-15);
        s_z += s.z;
        s_z2 += s.z * s.z;
        h_z += h.z;
        c_z += c.z;
        cone_z += k.z;
    }
    assert_near(s_z / N, 0, 0.005);
    assert_near(s_z2 / N, 1.0 / 3, 0.003);
    assert_near(h_z / N, 0.5, 0.003);
    assert_near(c_z / N, 2.0 / 3, 0.003); /* E[cos] under cos/pi */
    assert_near(cone_z / N, (1 + cos_max) / 2, 0.001);
    assert_near(uniform_sphere_pdf(), 1 / (4 * HZ_PI), 1e-17);
    assert_near(cosine_hemisphere_pdf(1), 1 / HZ_PI, 1e-17);
    assert_near(uniform_cone_pdf(0), 1 / (2 * HZ_PI), 1e-17);
}

static void test_exponential(void **state)
{
    (void)state;
    uint64_t rng = 5;
    double mean = 0;
    for (int i = 0; i < N; ++i)
        mean += sample_exponential(rng_next(&rng), 4.0);
    assert_near(mean / N, 0.25, 0.003);
    assert_near(sample_exponential(0, 2), 0, 0);
    assert_near(sample_exponential(1 - exp(-1.0), 2), 0.5, 1e-15);
}

/* hz_next_up is nextafter(x, INFINITY), bit for bit: at zeros, subnormals,
 * powers of two (where the spacing changes), infinities, NaN and random
 * doubles of both signs. */
static void test_next_up(void **state)
{
    (void)state;
    const double special[] = {0.0, -0.0, 0x1p-1074, -0x1p-1074, 0x1p-1022, -0x1p-1022, 1.0, -1.0,
                              0x1.fffffffffffffp-1, -0x1.fffffffffffffp-1, 0x1.fffffffffffffp+1023,
                              -0x1.fffffffffffffp+1023, INFINITY, -INFINITY, 1e-310, -1e-310};
    for (size_t i = 0; i < sizeof special / sizeof special[0]; ++i) {
        double x = special[i], a = hz_next_up(x), b = nextafter(x, INFINITY);
        if (memcmp(&a, &b, sizeof a) != 0)
            fail_msg("hz_next_up(%a) = %a, nextafter gives %a", x, a, b);
    }
    assert_true(isnan(hz_next_up(NAN)));
    uint64_t r = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < 100000; ++i) {
        r ^= r << 13;
        r ^= r >> 7;
        r ^= r << 17;
        double x;
        memcpy(&x, &r, sizeof x);
        if (isnan(x))
            continue;
        double a = hz_next_up(x), b = nextafter(x, INFINITY);
        if (memcmp(&a, &b, sizeof a) != 0)
            fail_msg("hz_next_up(%a) = %a, nextafter gives %a", x, a, b);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_disks),       cmocka_unit_test(test_regular_polygon),
        cmocka_unit_test(test_triangle),    cmocka_unit_test(test_sphere_and_hemispheres),
        cmocka_unit_test(test_exponential),
        cmocka_unit_test(test_next_up),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
