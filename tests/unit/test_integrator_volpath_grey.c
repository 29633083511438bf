/* integrator/volpath_media: the scalar walks of grey media against closed
 * forms. Along a ray through a grid medium the optical depth tau(t) is
 * integrated by a fine midpoint rule over the grid's trilinear density; then
 * ratio tracking's mean transmittance is e^-tau(t1) (its roulette included)
 * and delta tracking's first real collision falls before t with probability
 * 1 - e^-tau(t). Both within 4.5 standard errors of many runs. Marching
 * (volpath_march, "stepsize"): its jittered strata integrate the density
 * without bias at any step, and at a fine step its flights follow
 * 1 - e^-tau(t) too. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "integrator/volpath_media.h"
#include "media/medium.h"
#include "scene/scene_desc.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

typedef struct {
    scene_desc sd;
    medium m;
} built;

/* The one medium that `params` (a MakeNamedMedium's parameters) declares. */
static void build(built *b, const char *params)
{
    char src[1024];
    snprintf(src, sizeof src, "WorldBegin\nMakeNamedMedium \"m\" %s\n", params);
    hz_error err;
    if (scene_parse_string(src, "t.pbrt", &b->sd, &err) != HZ_OK)
        fail_msg("parse error: %s", err.message);
    assert_int_equal(b->sd.medium_count, 1);
    medium_times times = {0.0, 1.0, 0.0, 1.0};
    if (medium_create(&b->sd.media[0], transform_identity(), &times, NULL, &b->m, &err) != HZ_OK)
        fail_msg("medium: %s", err.message);
}

static void unbuild(built *b)
{
    medium_destroy(&b->m);
    scene_desc_free(&b->sd);
}

/* The optical depth sigma_t * integral of the density over [t0, t] along
 * o + t w, by the midpoint rule at 1/200 voxel (the trilinear field is
 * smooth between voxel planes). */
static double optical_depth(const medium *m, vec3 o, vec3 w, double t0, double t)
{
    medium_ray r;
    double a = t0, b = t;
    if (!medium_ray_start(m, o, w, 0.0, &a, &b, &r))
        return 0.0;
    uint64_t lookups = 0;
    double n = ceil((b - a) * r.voxels_per_t * 200.0), h = (b - a) / n, sum = 0.0;
    for (double k = 0.5; k < n; k += 1.0)
        sum += medium_ray_density(&r, a + k * h, &lookups);
    return (m->sigma_a.r + m->sigma_s.r) * sum * h;
}

static const char *const grey_media[] = {
    /* smooth: a sphere of density 1 with a soft edge */
    "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "fog_sphere.vdb\" "
    "\"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [3 3 3]",
    /* noisy: fBm smoke, majorant cells far above most of their voxels */
    "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "smoke.vdb\" "
    "\"string gridname\" \"density\" \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [9 9 9]",
};

typedef struct {
    vec3 o, w;
} line;

/* Rays through each medium's middle: along an axis, off axis, diagonal. */
static line ray_through(const medium *m, int k)
{
    vec3 corner[8];
    double voxel;
    assert_true(medium_support(m, corner, &voxel));
    vec3 lo = corner[0], hi = corner[0];
    for (int i = 1; i < 8; ++i) {
        lo = v3(fmin(lo.x, corner[i].x), fmin(lo.y, corner[i].y), fmin(lo.z, corner[i].z));
        hi = v3(fmax(hi.x, corner[i].x), fmax(hi.y, corner[i].y), fmax(hi.z, corner[i].z));
    }
    vec3 c = v3_scale(v3_add(lo, hi), 0.5), e = v3_sub(hi, lo);
    vec3 d[3] = {v3(1, 0, 0), v3(0.3, 0.2, 1), v3(1, 1, 1)};
    vec3 off[3] = {v3(0, 0, 0), v3(0.2 * e.x, 0.1 * e.y, 0), v3(0, 0.05 * e.y, -0.1 * e.z)};
    vec3 w = v3_normalize(d[k]);
    vec3 p = v3_add(c, off[k]);
    return (line){v3_sub(p, v3_scale(w, 2.0 * v3_length(e))), w};
}

/* The fractions of the optical depth tau at which flights are counted. */
static const double depth_fraction[3] = {0.25, 0.5, 1.0};

/* at[q]: where the optical depth along l reaches depth_fraction[q] of tau,
 * its value at t1 (bisection; at[2] = t1). */
static void depth_points(const medium *m, line l, double t1, double tau, double at[3])
{
    for (int q = 0; q < 2; ++q) {
        double lo = 0.0, hi = t1;
        while (hi - lo > 1e-9) {
            double mid = 0.5 * (lo + hi);
            if (optical_depth(m, l.o, l.w, 0.0, mid) < depth_fraction[q] * tau)
                lo = mid;
            else
                hi = mid;
        }
        at[q] = 0.5 * (lo + hi);
    }
    at[2] = t1;
}

/* before[q] of n flights ended before depth_points' at[q]: each share within
 * 4.5 standard errors (plus `slack`) of 1 - e^-(fraction tau). */
static void expect_depth_fractions(const int before[3], int n, double tau, double slack)
{
    for (int q = 0; q < 3; ++q) {
        double p = 1.0 - exp(-depth_fraction[q] * tau), got = (double)before[q] / n;
        double se = sqrt(p * (1.0 - p) / n);
        print_message("  P(t < depth at %.2f tau) %.5f, 1 - e^-tau %.5f (se %.5f)\n",
                      depth_fraction[q], got, p, se);
        assert_true(fabs(got - p) < 4.5 * se + slack);
    }
}

/* A check of one ray through a medium: l over [0, t1], its optical depth
 * tau; j is the ray's index (for seeds). */
typedef void (*ray_check)(const medium *m, line l, double t1, double tau, int j);

/* `check` on each grey medium and each of its rays (ray_through), whose
 * optical depths are all above 1. */
static void each_ray(ray_check check)
{
    for (size_t k = 0; k < 2; ++k) {
        built b;
        build(&b, grey_media[k]);
        for (int j = 0; j < 3; ++j) {
            line l = ray_through(&b.m, j);
            double t1 = 1e3, tau = optical_depth(&b.m, l.o, l.w, 0.0, t1);
            print_message("medium %zu ray %d: tau %.4f\n", k, j, tau);
            assert_true(tau > 1.0);
            check(&b.m, l, t1, tau, j);
        }
        unbuild(&b);
    }
}

static void test_grey_predicate(void **state)
{
    (void)state;
    built b;
    for (size_t k = 0; k < 2; ++k) {
        build(&b, grey_media[k]);
        assert_true(volpath_grey(&b.m));
        unbuild(&b);
    }
    build(&b, "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "fog_sphere.vdb\" "
              "\"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [3 2 3]");
    assert_false(volpath_grey(&b.m)); /* chromatic: volpath_track */
    assert_true(volpath_marches(&b.m)); /* marched in every lane */
    unbuild(&b);
    build(&b, "\"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [1 1 1]");
    assert_false(volpath_grey(&b.m)); /* no grid: volpath_track's closed form */
    assert_false(volpath_marches(&b.m));
    unbuild(&b);
}

/* Mean of ratio tracking's T (a fresh shadow ray: T = r_l = r_u = 1) against
 * e^-tau; the rays' optical depths are 1.9 to 4.8 (T well below pbrt-v4's
 * roulette threshold 0.05 on the deepest), so the roulette acts. */
static void check_ratio(const medium *m, line l, double t1, double tau, int j)
{
    const int n = 100000;
    media_walk walk = {.time = 0.0, .r = rng_seeded(17 + 31 * (uint64_t)j)};
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        double T, r_u;
        double x = volpath_grey_ratio(m, l.o, l.w, 0.0, t1, &walk, 1.0, 1.0, 1.0, &T, &r_u) ? T
                                                                                            : 0.0;
        assert_true(x >= 0.0 && isfinite(x));
        sum += x;
        sum2 += x * x;
    }
    double mean = sum / n, se = sqrt(fmax(sum2 / n - mean * mean, 0.0) / n);
    double want = exp(-tau);
    print_message("  T %.5f +- %.5f, e^-tau %.5f, %.1f lookups a ray\n", mean, se, want,
                  (double)walk.lookups / n);
    assert_true(walk.lookups > 0);
    assert_true(fabs(mean - want) < 4.5 * se + 1e-4 * want);
}

static void test_ratio_mean_is_transmittance(void **state)
{
    (void)state;
    each_ray(check_ratio);
}

/* Delta tracking: P(real collision before t) = 1 - e^-tau(t) at a quarter,
 * half and all of the ray's depth, and the density reported is the grid's
 * there. */
static void check_flights(const medium *m, line l, double t1, double tau, int j)
{
    const int n = 100000;
    double at[3];
    depth_points(m, l, t1, tau, at);
    media_walk walk = {.time = 0.0, .r = rng_seeded(5 + 7 * (uint64_t)j)};
    int before[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
        double t, d;
        volpath_flight f = volpath_grey_flight(m, l.o, l.w, 0.0, t1,
                                               i % 2 ? -1.0 : (i / 2 + 0.5) / (n / 2), &walk, &t,
                                               &d);
        assert_int_not_equal(f, VOLPATH_OPAQUE);
        if (f != VOLPATH_REAL)
            continue;
        if (i % 97 == 0) { /* the density is the grid's at t */
            medium_ray r;
            double a = 0.0, c = t1;
            assert_true(medium_ray_start(m, l.o, l.w, 0.0, &a, &c, &r));
            uint64_t lk = 0;
            assert_true(d > 0.0);
            assert_true(fabs(d - medium_ray_density(&r, t, &lk)) <= 1e-12);
        }
        for (int q = 0; q < 3; ++q)
            before[q] += t < at[q];
    }
    expect_depth_fractions(before, n, tau, 1e-4);
}

static void test_flight_distribution(void **state)
{
    (void)state;
    each_ray(check_flights);
}

/* The strata's density integral along l: sigma_t D is tau in the mean over
 * rays (one jittered offset each) at a step of 4 voxels, and close to it on
 * every ray at 1/8 voxel. */
static void check_march_integral(const medium *m, line l, double t1, double tau, uint64_t seed)
{
    const int n = 20000;
    double sigma_t = m->sigma_a.r + m->sigma_s.r;
    media_walk walk = {.time = 0.0, .r = rng_seeded(seed)};
    double sum = 0.0, sum2 = 0.0, D, t, d;
    for (int i = 0; i < n; ++i) {
        assert_int_equal(volpath_march(m, l.o, l.w, 0.0, t1, 4.0, INFINITY, &walk, &D, &t, &d),
                         VOLPATH_PASSED);
        sum += sigma_t * D;
        sum2 += sigma_t * D * sigma_t * D;
    }
    double mean = sum / n, se = sqrt(fmax(sum2 / n - mean * mean, 0.0) / n);
    double worst = 0.0;
    for (int i = 0; i < 20; ++i) {
        volpath_march(m, l.o, l.w, 0.0, t1, 0.125, INFINITY, &walk, &D, &t, &d);
        worst = fmax(worst, fabs(sigma_t * D / tau - 1.0));
    }
    print_message("  tau %.4f, step 4: %.4f +- %.4f (%.1f lookups a ray); step 1/8: worst %.2g "
                  "relative\n",
                  tau, mean, se, (double)walk.lookups / (n + 20), worst);
    assert_true(fabs(mean - tau) < 4.5 * se + 1e-6);
    assert_true(worst < 2e-3);
}

/* Marched flights along l at 1/8 voxel: P(collision before t) = 1 -
 * e^-tau(t) at a quarter, half and all of the depth, within noise and the
 * strata's error; at a collision D is the stop asked for and t lies on the
 * segment. */
static void check_march_flights(const medium *m, line l, double t1, double tau, uint64_t seed)
{
    const int n = 40000;
    double sigma_t = m->sigma_a.r + m->sigma_s.r, at[3];
    depth_points(m, l, t1, tau, at);
    media_walk walk = {.time = 0.0, .r = rng_seeded(seed)};
    int before[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
        double stop = -log(1.0 - (i + 0.5) / n) / sigma_t, D, t, d;
        if (volpath_march(m, l.o, l.w, 0.0, t1, 0.125, stop, &walk, &D, &t, &d) != VOLPATH_REAL)
            continue;
        assert_true(D == stop && t >= 0.0 && t <= t1 && d > 0.0);
        for (int q = 0; q < 3; ++q)
            before[q] += t < at[q];
    }
    expect_depth_fractions(before, n, tau, 2e-3);
}

/* Marching (volpath_march) on each medium and ray. */
static void check_march(const medium *m, line l, double t1, double tau, int j)
{
    check_march_integral(m, l, t1, tau, 3 + 11 * (uint64_t)j);
    check_march_flights(m, l, t1, tau, 9 + 13 * (uint64_t)j);
}

static void test_march(void **state)
{
    (void)state;
    each_ray(check_march);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grey_predicate),
        cmocka_unit_test(test_ratio_mean_is_transmittance),
        cmocka_unit_test(test_flight_distribution),
        cmocka_unit_test(test_march),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
