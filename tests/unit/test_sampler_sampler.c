#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sampler/sampler.h"
#include "sampler/sampler_math.h"
#include "scene/params.h"
#include "unit/entity_util.h"

static sampler make(sampler_kind kind, int spp, uint64_t seed)
{
    sampler s;
    memset(&s, 0, sizeof s);
    s.kind = kind;
    s.seed = seed;
    s.jitter = true;
    s.spp = s.xsamples = s.ysamples = 1;
    sampler_set_spp(&s, spp);
    return s;
}

static void test_permutation(void **state)
{
    (void)state;
    static const uint32_t ns[] = {1, 2, 3, 7, 16, 100, 1000};
    for (size_t k = 0; k < sizeof ns / sizeof ns[0]; k++) {
        uint32_t n = ns[k];
        for (uint32_t p = 0; p < 20; p++) {
            char *seen = calloc(n, 1);
            assert_non_null(seen);
            for (uint32_t i = 0; i < n; i++) {
                uint32_t v = smp_permutation_element(i, n, (uint32_t)smp_mix64(p));
                assert_true(v < n);
                assert_false(seen[v]);
                seen[v] = 1;
            }
            free(seen);
        }
    }
    /* Owen scrambling permutes every aligned block of 2^k values. */
    for (uint32_t k = 0; k <= 8; k++) {
        uint32_t n = 1u << k;
        char seen[256] = {0};
        for (uint32_t i = 0; i < n; i++) {
            uint32_t v = smp_owen_scramble(i, 0x12345678u);
            uint32_t v0 = smp_owen_scramble(0, 0x12345678u);
            assert_int_equal(v >> k, v0 >> k);
            assert_false(seen[v & (n - 1)]);
            seen[v & (n - 1)] = 1;
        }
    }
    assert_int_equal(smp_sobol1(1), 0x80000000u);
    assert_int_equal(smp_sobol1(2), 0xc0000000u);
    assert_int_equal(smp_sobol1(3), 0x40000000u);
    assert_int_equal(smp_sobol0(1), 0x80000000u);
    assert_int_equal(smp_sobol0(2), 0x40000000u);
    /* Dimension 1 against its generator matrix column by column (column k:
     * v ^= v >> 1, k times, from the top bit), on scrambled 32-bit indices
     * (every bit in use), and its Owen scramble against the general one. */
    uint32_t col[32], v = 1u << 31;
    for (int k = 0; k < 32; k++, v ^= v >> 1)
        col[k] = v;
    uint64_t h = 1;
    for (int n = 0; n < 100000; n++) {
        h = smp_mix64(h + 0x9e3779b97f4a7c15ull);
        uint32_t i = (uint32_t)h, want = 0;
        for (int k = 0; k < 32; k++)
            if (i >> k & 1u)
                want ^= col[k];
        assert_int_equal(smp_sobol1(i), want);
        assert_int_equal(smp_owen_sobol1(i, (uint32_t)(h >> 32)),
                         smp_owen_scramble(want, (uint32_t)(h >> 32)));
    }
}

/* A seed whose dimension is reserved and whose value is computed later is
 * the one computed at the reservation, the reservation moves the later
 * dimensions as skipping one does; different pixels, samples and dimensions
 * give different seeds. */
static void test_deferred_stream_seed(void **state)
{
    (void)state;
    for (int kind = 0; kind < 3; kind++) {
        sampler s = make((sampler_kind)kind, 16, 7);
        for (int i = 0; i < 16; i++) {
            sampler_state a, b;
            sampler_start(&s, 4, 2, i, &a);
            sampler_start(&s, 4, 2, i, &b);
            double ua = sampler_1d(&a), ub = sampler_1d(&b);
            sampler_skip(&a, 1);
            int dim = sampler_reserve_dim(&b);
            uint64_t now = sampler_stream_seed_at(&b, dim);
            double va = sampler_1d(&a), vb = sampler_1d(&b);
            vec2 wa = sampler_2d(&a), wb = sampler_2d(&b);
            assert_true(ua == ub && va == vb && wa.x == wb.x && wa.y == wb.y);
            assert_true(sampler_stream_seed_at(&b, dim) == now);
            assert_true(sampler_stream_seed_at(&b, dim + 1) != now);
            sampler_state c;
            sampler_start(&s, 4, 2, (i + 1) % 16, &c);
            assert_true(sampler_stream_seed_at(&c, dim) != now);
            sampler_start(&s, 5, 2, i, &c);
            assert_true(sampler_stream_seed_at(&c, dim) != now);
        }
    }
}

static void test_range_and_determinism(void **state)
{
    (void)state;
    for (int kind = 0; kind < 3; kind++) {
        sampler s = make((sampler_kind)kind, 16, 7);
        double first[10] = {0};
        sampler_state st;
        sampler_start(&s, 3, 5, 7, &st);
        vec2 p0 = sampler_pixel_2d(&st);
        for (int d = 0; d < 10; d += 2) {
            first[d] = sampler_1d(&st);
            vec2 v = sampler_2d(&st);
            first[d + 1] = v.x + 2 * v.y;
        }
        /* Many other pixels and samples, in any order: all in [0, 1). */
        for (int py = 9; py >= -3; py--)
            for (int px = -2; px < 12; px++)
                for (int i = 0; i < 16; i++) {
                    sampler_start(&s, px, py, i, &st);
                    for (int d = 0; d < 12; d++) {
                        double u = sampler_1d(&st);
                        vec2 v = sampler_2d(&st);
                        vec2 p = sampler_pixel_2d(&st);
                        assert_true(u >= 0.0 && u < 1.0);
                        assert_true(v.x >= 0.0 && v.x < 1.0 && v.y >= 0.0 && v.y < 1.0);
                        assert_true(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0);
                    }
                }
        /* Same inputs, same values; the pixel sample does not depend on when it is asked. */
        sampler_start(&s, 3, 5, 7, &st);
        for (int d = 0; d < 10; d += 2) {
            assert_true(sampler_1d(&st) == first[d]);
            vec2 v = sampler_2d(&st);
            assert_true(v.x + 2 * v.y == first[d + 1]);
        }
        vec2 p1 = sampler_pixel_2d(&st);
        assert_true(p0.x == p1.x && p0.y == p1.y);
        /* Another seed gives another stream. */
        sampler t = make((sampler_kind)kind, 16, 8);
        sampler_start(&t, 3, 5, 7, &st);
        vec2 q = sampler_pixel_2d(&st);
        assert_false(q.x == p0.x && q.y == p0.y);
    }
}

static void test_stratified_strata(void **state)
{
    (void)state;
    sampler s = make(SAMPLER_STRATIFIED, 12, 3);
    assert_int_equal(s.xsamples, 4);
    assert_int_equal(s.ysamples, 3);
    for (int jitter = 0; jitter < 2; jitter++) {
        s.jitter = jitter;
        for (int px = 0; px < 5; px++) {
            int hits_pixel[12] = {0}, hits_2d[4][12] = {{0}}, hits_1d[4][12] = {{0}};
            for (int i = 0; i < 12; i++) {
                sampler_state st;
                sampler_start(&s, px, 2 * px, i, &st);
                vec2 p = sampler_pixel_2d(&st);
                hits_pixel[(int)(p.y * 3) * 4 + (int)(p.x * 4)]++;
                if (!jitter) { /* centre of the stratum */
                    assert_float_equal(fmod(p.x * 4, 1.0), 0.5, 1e-12);
                    assert_float_equal(fmod(p.y * 3, 1.0), 0.5, 1e-12);
                }
                for (int d = 0; d < 4; d++) {
                    hits_1d[d][(int)(sampler_1d(&st) * 12)]++;
                    vec2 v = sampler_2d(&st);
                    hits_2d[d][(int)(v.y * 3) * 4 + (int)(v.x * 4)]++;
                }
            }
            for (int k = 0; k < 12; k++) {
                assert_int_equal(hits_pixel[k], 1);
                for (int d = 0; d < 4; d++) {
                    assert_int_equal(hits_2d[d][k], 1);
                    assert_int_equal(hits_1d[d][k], 1);
                }
            }
        }
    }
    sampler_set_spp(&s, 7);
    assert_true(s.xsamples == 7 && s.ysamples == 1 && s.spp == 7);
    sampler_set_spp(&s, 16);
    assert_true(s.xsamples == 4 && s.ysamples == 4);
}

/* Every elementary interval [a 2^-i, (a+1) 2^-i) x [b 2^-j, (b+1) 2^-j) with
 * i + j = k holds exactly one of the 2^k points. */
static void assert_net(const vec2 *p, int k)
{
    int n = 1 << k;
    int *count = calloc((size_t)n, sizeof *count);
    assert_non_null(count);
    for (int i = 0; i <= k; i++) {
        int j = k - i;
        memset(count, 0, (size_t)n * sizeof *count);
        for (int s = 0; s < n; s++) {
            int a = (int)(p[s].x * (1 << i)), b = (int)(p[s].y * (1 << j));
            count[b * (1 << i) + a]++;
        }
        for (int c = 0; c < n; c++)
            if (count[c] != 1)
                fail_msg("2^%d points: interval shape 2^-%d x 2^-%d has %d points", k, i, j, count[c]);
    }
    free(count);
}

/* A fork (a split path's copy) draws its later dimensions from another
 * scramble: over a pixel's samples each copy's 2D dimension is still a
 * (0, k, 2)-net and its 1D dimension stratified, and the copies' values
 * differ from each other's and from the unforked path's. */
static void test_fork(void **state)
{
    (void)state;
    enum { K = 6, N = 1 << K, COPIES = 3 };
    sampler s = make(SAMPLER_SOBOL, N, 7);
    vec2 p[COPIES + 1][N];
    double one[COPIES + 1][N];
    for (int c = 0; c <= COPIES; c++)
        for (int i = 0; i < N; i++) {
            sampler_state st;
            sampler_start(&s, 3, 5, i, &st);
            (void)sampler_pixel_2d(&st);
            (void)sampler_1d(&st);
            if (c > 0)
                sampler_fork(&st, c);
            one[c][i] = sampler_1d(&st);
            p[c][i] = sampler_2d(&st);
        }
    for (int c = 0; c <= COPIES; c++) {
        assert_net(p[c], K);
        char seen[N] = {0};
        for (int i = 0; i < N; i++) {
            int b = (int)(one[c][i] * N);
            assert_false(seen[b]);
            seen[b] = 1;
        }
        for (int d = 0; d < c; d++) {
            int same = 0;
            for (int i = 0; i < N; i++)
                same += one[c][i] == one[d][i] || p[c][i].x == p[d][i].x;
            assert_int_equal(same, 0);
        }
    }
}

static void test_sobol_nets(void **state)
{
    (void)state;
    vec2 *pix = malloc(1024 * sizeof *pix), *dim[3];
    double *one = malloc(1024 * sizeof *one);
    for (int d = 0; d < 3; d++)
        dim[d] = malloc(1024 * sizeof *dim[d]);
    assert_true(pix && one);
    for (int k = 0; k <= 10; k++) {
        sampler s = make(SAMPLER_SOBOL, 1 << k, 11);
        assert_int_equal(s.spp, 1 << k);
        assert_string_equal(s.warning, "");
        for (int px = 0; px < 4; px++) {
            for (int i = 0; i < s.spp; i++) {
                sampler_state st;
                sampler_start(&s, px, 17, i, &st);
                pix[i] = sampler_pixel_2d(&st);
                one[i] = sampler_1d(&st);
                for (int d = 0; d < 3; d++)
                    dim[d][i] = sampler_2d(&st);
            }
            assert_net(pix, k);
            for (int d = 0; d < 3; d++)
                assert_net(dim[d], k);
            /* 1D dimensions: one sample per 1/spp stratum. */
            char *seen = calloc((size_t)s.spp, 1);
            for (int i = 0; i < s.spp; i++) {
                int c = (int)(one[i] * s.spp);
                assert_false(seen[c]);
                seen[c] = 1;
            }
            free(seen);
        }
    }
    for (int d = 0; d < 3; d++)
        free(dim[d]);
    free(pix);
    free(one);
    /* Not a power of two: rounded up with a warning. */
    sampler s = make(SAMPLER_SOBOL, 10, 1);
    assert_int_equal(s.spp, 16);
    assert_non_null(strstr(s.warning, "16"));
}

/* RMS error of the per-pixel estimate of a smooth integral. */
static double rms_error(sampler_kind kind, int spp, bool pixel_dim)
{
    sampler s = make(kind, spp, 5);
    const double exact = (sqrt(HZ_PI) / 2 * erf(1.0)) * (sqrt(HZ_PI) / 2 * erf(1.0)); /* ∫∫ e^-(x²+y²) */
    double se = 0.0;
    const int pixels = 256;
    for (int p = 0; p < pixels; p++) {
        double sum = 0.0;
        for (int i = 0; i < spp; i++) {
            sampler_state st;
            sampler_start(&s, p % 16, p / 16, i, &st);
            vec2 u;
            if (pixel_dim)
                u = sampler_pixel_2d(&st);
            else {
                sampler_1d(&st);
                sampler_2d(&st);
                u = sampler_2d(&st); /* a padded dimension */
            }
            sum += exp(-(u.x * u.x + u.y * u.y));
        }
        double e = sum / spp - exact;
        se += e * e;
    }
    return sqrt(se / pixels);
}

static void test_integration_error(void **state)
{
    (void)state;
    double ind = rms_error(SAMPLER_INDEPENDENT, 256, true);
    double sob = rms_error(SAMPLER_SOBOL, 256, true);
    double sob_pad = rms_error(SAMPLER_SOBOL, 256, false);
    double str = rms_error(SAMPLER_STRATIFIED, 256, true);
    print_message("RMS error at 256 spp: independent %.3g, stratified %.3g, sobol %.3g (padded dim %.3g)\n",
                  ind, str, sob, sob_pad);
    /* Independent: sigma/sqrt(256) with sigma ~ 0.2. */
    assert_true(ind > 0.005 && ind < 0.03);
    assert_true(sob < 0.25 * ind);
    assert_true(sob_pad < 0.25 * ind);
    assert_true(str < 0.25 * ind);
}

/* Issue 45: a path's decisions must not share randomness. Over the 64
 * samples of a pixel, every pair of the first 24 dimensions of a path as
 * the integrators draw them (a 1D, then two 2Ds, repeated; the 2D's x and
 * y of different dimensions paired too) must be as independent as
 * independent sampling makes them: the squared correlation r^2 averages
 * 1/(n - 1) for independent pairs, and a dimension used twice (or a
 * bounce repeating another's) gives 1. Also a chi-square over an 8x8 grid
 * of each pair: a (stratified) sampler may be more uniform than random,
 * never much less. Measured over 200 pixels (mean r^2 (n - 1), its worst
 * pair, mean chi2/dof): independent 1.00, 1.40, 1.00; stratified 1.01,
 * 1.36, 0.79; sobol 1.60, 2.22, 0.89 (its Owen-shuffled indices pair
 * strata more regularly than at random, with a heavier tail of
 * correlation, still far from reuse). */
static void pair_statistics(sampler_kind kind, double *r2, double *worst_r2, double *chi2)
{
    enum { N = 64, DIMS = 24, PIXELS = 200 };
    sampler s = make(kind, N, 3);
    static double v[N][2 * DIMS];
    static double pair_r2[2 * DIMS][2 * DIMS];
    memset(pair_r2, 0, sizeof pair_r2);
    double sum_r2 = 0.0, sum_chi = 0.0;
    long pairs = 0;
    for (int p = 0; p < PIXELS; ++p) {
        for (int i = 0; i < N; ++i) {
            sampler_state st;
            sampler_start(&s, p, 11, i, &st);
            for (int d = 0; d < DIMS; ++d) {
                if (d % 3 == 0) {
                    v[i][2 * d] = sampler_1d(&st);
                    v[i][2 * d + 1] = -1.0;
                } else {
                    vec2 u = sampler_2d(&st);
                    v[i][2 * d] = u.x;
                    v[i][2 * d + 1] = u.y;
                }
            }
        }
        for (int a = 0; a < 2 * DIMS; ++a)
            for (int b = a + 1; b < 2 * DIMS; ++b) {
                /* 1D slots' second half, and a 2D's own x and y (a net). */
                if (v[0][a] < 0.0 || v[0][b] < 0.0 || (a % 2 == 0 && b == a + 1))
                    continue;
                double ma = 0.0, mb = 0.0;
                for (int i = 0; i < N; ++i) {
                    ma += v[i][a];
                    mb += v[i][b];
                }
                ma /= N;
                mb /= N;
                double sab = 0.0, saa = 0.0, sbb = 0.0;
                int cell[8][8] = {{0}};
                for (int i = 0; i < N; ++i) {
                    double x = v[i][a] - ma, y = v[i][b] - mb;
                    sab += x * y;
                    saa += x * x;
                    sbb += y * y;
                    cell[(int)(v[i][a] * 8.0)][(int)(v[i][b] * 8.0)]++;
                }
                double chi = 0.0;
                for (int x = 0; x < 8; ++x)
                    for (int y = 0; y < 8; ++y)
                        chi += (cell[x][y] - 1.0) * (cell[x][y] - 1.0);
                sum_r2 += sab * sab / (saa * sbb);
                pair_r2[a][b] += sab * sab / (saa * sbb);
                sum_chi += chi / 63.0;
                ++pairs;
            }
    }
    *r2 = sum_r2 / pairs * (N - 1);
    *chi2 = sum_chi / pairs;
    *worst_r2 = 0.0;
    for (int a = 0; a < 2 * DIMS; ++a)
        for (int b = a + 1; b < 2 * DIMS; ++b)
            *worst_r2 = fmax(*worst_r2, pair_r2[a][b] / PIXELS * (N - 1));
}

static void test_dimensions_independent(void **state)
{
    (void)state;
    const sampler_kind kinds[3] = {SAMPLER_INDEPENDENT, SAMPLER_STRATIFIED, SAMPLER_SOBOL};
    const char *names[3] = {"independent", "stratified", "sobol"};
    for (int k = 0; k < 3; ++k) {
        double r2, worst, chi2;
        pair_statistics(kinds[k], &r2, &worst, &chi2);
        print_message("%s: mean r^2 (n - 1) %.3f (worst pair %.3f), chi2/dof %.3f\n", names[k],
                      r2, worst, chi2);
        assert_true(r2 > 0.8 && r2 < 2.0);
        /* A pair that shares its values would average 63. */
        assert_true(worst < 4.0);
        assert_true(chi2 < 1.1);
    }
}

static void test_from_entity(void **state)
{
    (void)state;
    scene_entity e;
    sampler s;
    hz_error err = {0};
    entity_init(&e, "zsobol");
    assert_int_equal(sampler_from_entity(&e, 42, &s, &err), HZ_OK);
    assert_int_equal(s.kind, SAMPLER_SOBOL);
    assert_int_equal(s.spp, 16);
    assert_true(s.seed == 42);
    assert_string_equal(s.warning, "");
    entity_free(&e);

    entity_init(&e, "independent");
    add_int(&e, "pixelsamples", 5);
    add_int(&e, "seed", 9);
    assert_int_equal(sampler_from_entity(&e, 42, &s, &err), HZ_OK);
    assert_true(s.kind == SAMPLER_INDEPENDENT && s.spp == 5 && s.seed == 9);
    entity_free(&e);

    entity_init(&e, "stratified");
    add_int(&e, "xsamples", 3);
    add_int(&e, "ysamples", 2);
    add_bool(&e, "jitter", false);
    assert_int_equal(sampler_from_entity(&e, 0, &s, &err), HZ_OK);
    assert_true(s.kind == SAMPLER_STRATIFIED && s.spp == 6 && s.xsamples == 3 && !s.jitter);
    entity_free(&e);

    entity_init(&e, "stratified");
    assert_int_equal(sampler_from_entity(&e, 0, &s, &err), HZ_OK);
    assert_true(s.spp == 16 && s.xsamples == 4 && s.ysamples == 4 && s.jitter);
    entity_free(&e);

    entity_init(&e, "halton");
    add_int(&e, "pixelsamples", 100);
    assert_int_equal(sampler_from_entity(&e, 0, &s, &err), HZ_OK);
    assert_true(s.kind == SAMPLER_SOBOL && s.spp == 128);
    assert_non_null(strstr(s.warning, "halton"));
    assert_non_null(strstr(s.warning, "128"));
    entity_free(&e);

    entity_init(&e, "sobol");
    add_string(&e, "randomization", "owen");
    assert_int_equal(sampler_from_entity(&e, 0, &s, &err), HZ_OK);
    entity_free(&e);

    const char *bad[][2] = {{"lowdiscrepancy", "stratified"}, {"independent", "pixelsamples"},
                            {"zsobol", "pixelsamples"}, {"sobol", "randomization"},
                            {"stratified", "xsamples"}, {"zsobol", "xsamples"}};
    for (int k = 0; k < 6; k++) {
        entity_init(&e, bad[k][0]);
        if (k == 1 || k == 2)
            add_int(&e, "pixelsamples", 0);
        if (k == 3)
            add_string(&e, "randomization", "shuffled");
        if (k == 4)
            add_int(&e, "xsamples", -2);
        if (k == 5)
            add_int(&e, "xsamples", 4); /* not a sobol parameter: unused */
        err.message[0] = 0;
        assert_int_equal(sampler_from_entity(&e, 0, &s, &err), HZ_ERROR);
        if (!strstr(err.message, bad[k][1]) || !strstr(err.message, "test.pbrt:3:"))
            fail_msg("error \"%s\" should mention \"%s\"", err.message, bad[k][1]);
        entity_free(&e);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_permutation),
        cmocka_unit_test(test_range_and_determinism),
        cmocka_unit_test(test_deferred_stream_seed),
        cmocka_unit_test(test_stratified_strata),
        cmocka_unit_test(test_sobol_nets),
        cmocka_unit_test(test_fork),
        cmocka_unit_test(test_integration_error),
        cmocka_unit_test(test_dimensions_independent),
        cmocka_unit_test(test_from_entity), /* needs scene/params: last */
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
