/* Progressive passes (`haze render --time-limit`, src/render/progressive.h):
 * the pass schedule; passes that add up to S samples give the render of S
 * samples bit for bit (every AOV); a pass cut short is undone; the command
 * line writes the complete passes and names them in the header. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sampler/sampler_math.h"
#include "cli_util.h"
#include "core/clock.h"
#include "film/exr.h"
#include "render/progressive.h"
#include "render/progressive_error.h"
#include "render/step_pilot.h"
#include "render_test_util.h"

static bool verbose_on(void)
{
    const char *v = getenv("HAZE_MEDIA_VERBOSE");
    return v && v[0] && v[0] != '0';
}

/* A medium over a floor under a sky and a distant light: surfaces, media,
 * shadow rays; every AOV; an independent sampler (sample i of a pixel does
 * not depend on the count). */
static char *scene_text(int spp)
{
    char *s = malloc(4096);
    assert_non_null(s);
    snprintf(s, 4096,
             "LookAt 0 1 -4  0 0.6 0  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 40\n"
             "Film \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 36\n"
             "    \"bool writedepth\" true \"bool writevariance\" true\n"
             "    \"bool writesamplecount\" true\n"
             "Sampler \"independent\" \"integer pixelsamples\" %d\n"
             "WorldBegin\n"
             "LightSource \"distant\" \"point3 from\" [1 3 -2] \"point3 to\" [0 0 0]"
             " \"rgb L\" [3 3 3]\n"
             "LightSource \"infinite\" \"rgb L\" [0.1 0.12 0.15]\n"
             "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
             "    \"rgb sigma_a\" [0.2 0.2 0.2] \"rgb sigma_s\" [1 1 1]\n"
             "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "    \"point3 P\" [-5 0 -5  5 0 -5  5 0 5  -5 0 5]\n"
             "AttributeBegin\n"
             "  Material \"interface\"\n"
             "  MediumInterface \"fog\" \"\"\n"
             "  Translate 0 0.7 0\n"
             "  Shape \"sphere\" \"float radius\" 0.7\n"
             "AttributeEnd\n",
             spp);
    return s;
}

/* Every accumulator of the film, as one buffer (free it). */
static unsigned char *film_bytes(film *f, size_t *n)
{
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    size_t total = acc.count_count * sizeof(uint32_t);
    for (int i = 0; i < 3; ++i)
        total += acc.double_count[i] * sizeof(double);
    unsigned char *b = malloc(total), *p = b;
    assert_non_null(b);
    for (int i = 0; i < 3; ++i) {
        if (acc.doubles[i])
            memcpy(p, acc.doubles[i], acc.double_count[i] * sizeof(double));
        p += acc.double_count[i] * sizeof(double);
    }
    if (acc.counts)
        memcpy(p, acc.counts, acc.count_count * sizeof(uint32_t));
    *n = total;
    return b;
}

/* One render of `spp` samples; its accumulators. */
static unsigned char *render_once(int spp, size_t *n)
{
    char *text = scene_text(spp);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    renderer_options opt = {.threads = 2};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run(rs, &opt, &st, &err), HZ_OK);
    assert_int_equal(st.spp, spp);
    unsigned char *b = film_bytes(render_scene_film(rs), n);
    render_scene_destroy(rs);
    return b;
}

static void test_pass_schedule(void **state)
{
    (void)state;
    const int spp16[] = {1, 2, 4, 8, 16}, spp12[] = {1, 2, 4, 8, 12};
    int b = 0;
    for (int i = 0; i < 5; ++i)
        assert_int_equal(b = progressive_pass_end(b, 16), spp16[i]);
    b = 0;
    for (int i = 0; i < 5; ++i)
        assert_int_equal(b = progressive_pass_end(b, 12), spp12[i]);
    assert_int_equal(progressive_pass_end(0, 1), 1);
    assert_int_equal(progressive_pass_end(1 << 23, 1 << 24), 1 << 24);
    /* 1 s for 2 samples: 4 more need 2 s */
    assert_true(progressive_pass_fits(10.0, 12.0, 1.0, 2, 4));
    assert_false(progressive_pass_fits(10.0, 11.9, 1.0, 2, 4));
}

/* No deadline in reach: every pass runs and the film is the one-render film. */
static void test_all_passes_bit_identical(void **state)
{
    (void)state;
    size_t n1 = 0, n2 = 0;
    unsigned char *once = render_once(12, &n1);
    char *text = scene_text(12);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    for (int threads = 1; threads <= 2; ++threads) {
        if (threads == 2) {
            render_scene_destroy(rs);
            text = scene_text(12);
            rs = build_scene_or_fail(text, NULL);
            free(text);
        }
        renderer_options opt = {.threads = threads};
        render_stats st;
        hz_error err = {0};
        assert_int_equal(
            renderer_run_progressive(rs, &opt, &(progressive_goal){hz_clock_seconds() + 1e6, 0, 0}, &st, &err), HZ_OK);
        assert_int_equal(st.spp, 12);
        assert_int_equal(st.passes, 5);
        assert_false(st.interrupted);
        assert_true(st.camera_rays >= 12u * 40 * 36);
        unsigned char *prog = film_bytes(render_scene_film(rs), &n2);
        assert_int_equal(n1, n2);
        assert_memory_equal(once, prog, n1);
        free(prog);
    }
    render_scene_destroy(rs);
    free(once);
}

/* A deadline already passed: the first pass still runs, no other. */
static void test_first_pass_always_completes(void **state)
{
    (void)state;
    size_t n1 = 0, n2 = 0;
    unsigned char *one = render_once(1, &n1);
    char *text = scene_text(64);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    renderer_options opt = {.threads = 2};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run_progressive(rs, &opt, &(progressive_goal){hz_clock_seconds() - 1.0, 0, 0}, &st, &err),
                     HZ_OK);
    assert_int_equal(st.spp, 1);
    assert_int_equal(st.passes, 1);
    assert_int_equal(st.tiles_done, st.tile_count);
    unsigned char *prog = film_bytes(render_scene_film(rs), &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(one, prog, n1);
    free(prog);
    free(one);
    render_scene_destroy(rs);
}

/* One thread claims tiles 0..T-1 and then gets -1, pass after pass; in the
 * third pass it asks for a cancel after `cut` tiles, as a signal would. */
typedef struct {
    int tile_count, cut;
    atomic_int calls;
    volatile sig_atomic_t cancel;
} cutter;

static int cutter_next(void *p)
{
    cutter *c = p;
    int n = atomic_fetch_add(&c->calls, 1);
    int pass = n / (c->tile_count + 1), t = n % (c->tile_count + 1);
    if (pass == 2 && t == c->cut) {
        c->cancel = 1;
        return -1;
    }
    return t < c->tile_count ? t : -1;
}

/* Passes [0,1) and [1,2) complete, [2,4) is cut after 3 tiles: the film is
 * the 2-sample film, not one with 4 samples in 3 tiles. */
static void test_cut_pass_undone(void **state)
{
    (void)state;
    size_t n1 = 0, n2 = 0;
    unsigned char *two = render_once(2, &n1);
    char *text = scene_text(16);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    cutter c = {.tile_count = 3 * 3, .cut = 3};
    atomic_init(&c.calls, 0);
    renderer_options opt = {.threads = 1, .next_tile = cutter_next, .tile_ctx = &c,
                            .cancel = &c.cancel};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run_progressive(rs, &opt, &(progressive_goal){hz_clock_seconds() + 1e6, 0, 0}, &st, &err),
                     HZ_OK);
    assert_int_equal(st.tile_count, c.tile_count);
    assert_int_equal(st.spp, 2);
    assert_int_equal(st.passes, 2);
    assert_false(st.interrupted);
    unsigned char *prog = film_bytes(render_scene_film(rs), &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(two, prog, n1);
    free(prog);
    free(two);
    render_scene_destroy(rs);
}

/* ---- --target-error ------------------------------------------------------ */

/* A deterministic standard normal (Box-Muller over a hash). */
static double normal(uint64_t *state)
{
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    double u1 = ((*state >> 11) + 0.5) * 0x1p-53;
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    double u2 = ((*state >> 11) + 0.5) * 0x1p-53;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* A 64x32 film whose pixels take iid samples of mean 0.5 and standard
 * deviation 0.1 (left half) or 0.4 (right half), grey. */
static film *noise_film(void)
{
    film_params p;
    film_params_default(&p);
    p.xres = 64;
    p.yres = 32;
    p.bounds = (pixel_bounds){.x0 = 0, .x1 = 64, .y0 = 0, .y1 = 32};
    p.write_variance = p.write_sample_count = true;
    hz_error err = {0};
    film *f = film_create(&p, &err);
    if (!f)
        fail_msg("film: %s", err.message);
    return f;
}

static void add_noise(film *f, int samples, uint64_t *state)
{
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int i = 0; i < samples; ++i) {
                double v = 0.5 + (x < 32 ? 0.1 : 0.4) * normal(state);
                film_add_sample(f, x, y, rgb_grey(v), 1.0, INFINITY);
            }
}

/* A noise film with `samples` per pixel, a copy of it, then `samples` more. */
static film *noise_film_and_copy(uint64_t seed, int samples, film_snapshot **copy)
{
    film *f = noise_film();
    uint64_t rng = seed;
    add_noise(f, samples, &rng);
    hz_error err = {0};
    *copy = film_snapshot_create(f, &err);
    assert_non_null(*copy);
    add_noise(f, samples, &rng);
    return f;
}

/* The estimates against the closed form: Var[mean] = sigma^2 / n, relative
 * (0.5 + 0.01)^2; the allocation gives the noisier half 4x the samples. */
static void test_error_estimate(void **state)
{
    (void)state;
    film_snapshot *before;
    film *f = noise_film_and_copy(12345, 8, &before);
    hz_error err = {0};
    progressive_error pe;
    assert_int_equal(progressive_error_init(&pe, f, &err), HZ_OK);
    unsigned char active[64 * 32];
    memset(active, 1, sizeof active);
    progressive_error_measure(&pe, f, before, active, 8, 16, 1.0, 2);
    double d = 0.51 * 0.51, want = (0.01 + 0.16) / 2.0 / 16.0 / d;
    /* e_i (allocation) of pixels away from the halves' border and the tile
     * edges: the larger of own and neighbours' mean, a little above sigma^2/n */
    double left = 0.0, right = 0.0;
    int nl = 0, nr = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) {
            if (x % 16 == 0 || x % 16 == 15 || y % 16 == 0 || y % 16 == 15)
                continue;
            if (x < 32) {
                left += pe.e[y * 64 + x];
                ++nl;
            } else {
                right += pe.e[y * 64 + x];
                ++nr;
            }
        }
    left /= nl;
    right /= nr;
    if (verbose_on())
        print_message("e left %.4g (%.4g), right %.4g (%.4g)\n", left, 0.01 / 16 / d, right,
                      0.16 / 16 / d);
    /* Conservative: the larger of own and neighbours' mean, over the lower
     * bound of the value (at a noise of the mean 0.05 of it, about +25%; at
     * 0.2, about +110%) */
    assert_true(left >= 0.01 / 16 / d && left <= 1.3 * 0.01 / 16 / d);
    assert_true(right >= 0.16 / 16 / d && right <= 2.4 * 0.16 / 16 / d);

    /* The image's (halves) estimate. */
    double estimate = 0.0;
    long on = progressive_error_select(&pe, f, &(progressive_goal){0.0, 1e-9, 0.0}, active, &estimate);
    if (verbose_on())
        print_message("halves %.4g (%.4g)\n", estimate, want);
    /* unbiased over the value; over its lower bound (the right half's mean
     * noise is 0.2 of it): up to 1.8x */
    assert_true(estimate >= want && estimate <= 1.8 * want);
    assert_int_equal(on, 64 * 32); /* far from 1e-9: every pixel goes on */

    /* A target between the halves' shares: n*_left = 0.096 / E, n*_right =
     * 0.384 / E; at E = 0.012, 8 and 32: the left half (16 samples) stops, the
     * right goes on (the estimate, 0.02, is above 0.7 E). */
    memset(active, 1, sizeof active);
    on = progressive_error_select(&pe, f, &(progressive_goal){0.0, 0.012, 0.0}, active, NULL);
    int left_on = 0, right_on = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            if (x < 16) /* whole tiles on either side */
                left_on += active[y * 64 + x];
            else if (x >= 48)
                right_on += active[y * 64 + x];
    assert_true(left_on < 16 * 32 / 20);
    assert_true(right_on > 16 * 32 * 19 / 20);
    assert_true(on > 0);

    /* A target the estimate meets: every pixel stops. */
    memset(active, 1, sizeof active);
    progressive_goal met = {0.0, 2.0 * want, 0.0};
    assert_int_equal(progressive_error_select(&pe, f, &met, active, NULL), 0);
    assert_int_equal(progressive_error_next_end(&pe, 16, 1024, &met), 20);
    /* The same target after a marching bias of half of it: the noise's share,
     * want, is below the estimate, and pixels go on. */
    memset(active, 1, sizeof active);
    progressive_goal spent = {0.0, 2.0 * want, want};
    assert_true(progressive_noise_target(&spent) == want);
    assert_true(progressive_error_select(&pe, f, &spent, active, NULL) > 0);
    /* A target 10x below: the next pass doubles (1/n: 14x the samples). */
    assert_int_equal(progressive_error_next_end(&pe, 16, 1024, &(progressive_goal){0.0, want / 10, 0.0}), 32);
    progressive_error_free(&pe);
    film_snapshot_destroy(before);
    film_destroy(f);
}

/* Base-2 radical inverse of i (van der Corput): its first 2^m points are
 * the 2^m strata of [0, 1), each half of them the strata of the other's
 * size. */
static double van_der_corput(uint32_t i) { return smp_reverse_bits32(i) * 0x1p-32; }

/* Samples [n0, n) of every pixel of a noise film: a line 0.5 + A (u - 0.5)
 * over a van der Corput sequence shifted by the pixel's own random offset.
 * The mean of the first n = 2^m samples is 0.5 + A (d - 1 / (2n)), d
 * uniform in [0, 1/n): Var = A^2 / (12 n^2), falling as n^-2, and the
 * halves estimate H(n) = V(n/2) - V(n) = 3 V(n). */
static void add_stratified(film *f, int n0, int n, const double *shift, double amplitude)
{
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int i = n0; i < n; ++i) {
                double u = van_der_corput((uint32_t)i) + shift[y * 64 + x];
                u -= floor(u);
                film_add_sample(f, x, y, rgb_grey(0.5 + amplitude * (u - 0.5)), 1.0, INFINITY);
            }
}

/* Passes of 2, 2, 4 and 8 samples measured as a render measures them; the
 * image's estimate after each. */
static void measured_passes(film *f, void (*add)(film *, int, int, void *), void *ctx,
                            progressive_error *pe, double estimates[4])
{
    hz_error err = {0};
    assert_int_equal(progressive_error_init(pe, f, &err), HZ_OK);
    film_snapshot *before = film_snapshot_alloc(f, &err);
    assert_non_null(before);
    unsigned char active[64 * 32];
    progressive_goal far = {0.0, 1e-9, 0.0}; /* every pixel goes on */
    int ends[4] = {2, 4, 8, 16};
    for (int p = 0, done = 0; p < 4; done = ends[p++]) {
        memset(active, 1, sizeof active);
        if (done > 0)
            film_snapshot_save(before, f);
        add(f, done, ends[p], ctx);
        progressive_error_measure(pe, f, before, active, done, ends[p], 1.0, 2);
        assert_int_equal(progressive_error_select(pe, f, &far, active, &estimates[p]), 64 * 32);
    }
    film_snapshot_destroy(before);
}

typedef struct {
    double shift[64 * 32];
    double amplitude;
    uint64_t rng;
} sample_source;

static void add_stratified_pass(film *f, int n0, int n, void *ctx)
{
    sample_source *src = ctx;
    add_stratified(f, n0, n, src->shift, src->amplitude);
}

static void add_noise_pass(film *f, int n0, int n, void *ctx)
{
    add_noise(f, n - n0, &((sample_source *)ctx)->rng);
}

/* Both: each sample the stratified line plus independent noise of 0.1. */
static void add_mixed_pass(film *f, int n0, int n, void *ctx)
{
    sample_source *src = ctx;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int i = n0; i < n; ++i) {
                double u = van_der_corput((uint32_t)i) + src->shift[y * 64 + x];
                u -= floor(u);
                double v = 0.5 + src->amplitude * (u - 0.5) + 0.1 * normal(&src->rng);
                film_add_sample(f, x, y, rgb_grey(v), 1.0, INFINITY);
            }
}

/* A pixel whose mean is one bright sample's (a firefly: the others near 0)
 * says nothing of its value without it: from PROGRESSIVE_SINGLE_SAMPLE_SPP
 * samples on its relative error is taken over the least denominator,
 * Var / 0.01^2, not over m - 0.7 sd (fog-dof at E = 2e-3, seed 3, missed E
 * by 6% through one such pixel, docs/progressive.md). With fewer samples the
 * lower bound stays. */
static void test_single_bright_sample(void **state)
{
    (void)state;
    for (int samples = 8; samples <= 32; samples *= 4) {
        film *f = noise_film();
        uint64_t rng = 5;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 64; ++x)
                for (int i = 0; i < samples; ++i) {
                    double v = 0.02 + 0.002 * normal(&rng);
                    if (x == 40 && y == 20 && i == samples / 2)
                        v = 10.0; /* the firefly */
                    film_add_sample(f, x, y, rgb_grey(v), 1.0, INFINITY);
                }
        hz_error err = {0};
        progressive_error pe;
        assert_int_equal(progressive_error_init(&pe, f, &err), HZ_OK);
        unsigned char active[64 * 32];
        memset(active, 1, sizeof active);
        progressive_error_measure(&pe, f, NULL, active, 0, samples, 1.0, 2);
        rgb m = film_get_pixel(f, 40, 20, 1.0), var = film_get_variance(f, 40, 20, 1.0);
        double sd = sqrt(var.r), lo = m.r - PROGRESSIVE_LOWER_BOUND_K * sd;
        double over_least = var.r / (0.01 * 0.01), over_bound = var.r / ((lo + 0.01) * (lo + 0.01));
        double e = pe.halves[20 * 64 + 40]; /* the first measure's: Var / d^2 */
        if (verbose_on())
            print_message("firefly at %d spp: sd/m %.3f, halves %.4g (over 0.01^2 %.4g, over the bound %.4g)\n",
                          samples, sd / m.r, e, over_least, over_bound);
        assert_true(sd / m.r > 0.9);
        assert_true(pe.e[20 * 64 + 40] >= e); /* the allocation sees it too */
        if (samples >= PROGRESSIVE_SINGLE_SAMPLE_SPP)
            assert_true(fabs(e - over_least) <= 1e-9 * over_least);
        else
            assert_true(fabs(e - over_bound) <= 1e-9 * over_bound);
        progressive_error_free(&pe);
        film_destroy(f);
    }
}

/* The halves estimate corrected by the convergence of the passes: samples
 * whose mean's variance falls as n^-2 read a factor x = 4 per doubling and
 * the estimate falls from H(n) = 3 V(n) to about V(n); independent samples
 * read about 2 and keep it; a mixture of both, V(n) = A / n^2 + B / n, whose
 * convergence slows down as n grows, is not taken for faster than it is
 * (all against the closed forms). */
static void test_convergence_correction(void **state)
{
    (void)state;
    static sample_source src = {.amplitude = 0.4, .rng = 777};
    for (int i = 0; i < 64 * 32; ++i) { /* uniform offsets */
        src.rng = src.rng * 6364136223846793005ull + 1442695040888963407ull;
        src.shift[i] = ((src.rng >> 11) + 0.5) * 0x1p-53;
    }
    film *f = noise_film();
    progressive_error pe;
    double est[4];
    measured_passes(f, add_stratified_pass, &src, &pe, est);
    double d = 0.51 * 0.51, v16 = 0.16 / 12.0 / (16.0 * 16.0) / d;
    if (verbose_on())
        print_message("stratified: x %.3f, estimates %.4g %.4g %.4g %.4g, V(16) %.4g\n",
                      pe.convergence, est[0], est[1], est[2], est[3], v16);
    assert_true(pe.convergence > 3.6 && pe.convergence <= 4.0);
    assert_true(est[3] >= 0.95 * v16 && est[3] <= 1.25 * v16); /* uncorrected: 3 V(16) */
    progressive_error_free(&pe);
    film_destroy(f);

    f = noise_film();
    src.rng = 4242;
    measured_passes(f, add_noise_pass, &src, &pe, est);
    /* sigma^2 / n over (0.5 + 0.01)^2, the image's mean of both halves */
    double iid = (0.01 + 0.16) / 2.0 / 16.0 / d;
    if (verbose_on())
        print_message("independent: x %.3f, estimate %.4g (%.4g)\n", pe.convergence, est[3], iid);
    assert_true(pe.convergence >= 2.0 && pe.convergence < 2.3);
    assert_true(est[3] >= 0.85 * iid && est[3] <= 1.8 * iid);
    progressive_error_free(&pe);
    film_destroy(f);

    /* A = 0.4^2 / 12, B = 0.1^2: at 16 samples the stratified part is a
     * fifth of V, at 4 half of it. */
    f = noise_film();
    src.rng = 99;
    measured_passes(f, add_mixed_pass, &src, &pe, est);
    double mixed = (0.16 / 12.0 / (16.0 * 16.0) + 0.01 / 16.0) / d;
    if (verbose_on())
        print_message("mixed: x %.3f, estimate %.4g (%.4g)\n", pe.convergence, est[3], mixed);
    assert_true(est[3] >= mixed && est[3] <= 1.5 * mixed);
    progressive_error_free(&pe);
    film_destroy(f);
}

/* The convergence read from three passes' squared changes, on sources each
 * model is exact for: c_k = H(n / 2^k) = V(n / 2^(k+1)) - V(n / 2^k). */
static void test_read_convergence(void **state)
{
    (void)state;
    assert_true(progressive_read_convergence(1.0, 2.0, 4.0) == 2.0); /* V ~ 1/n */
    assert_true(fabs(progressive_read_convergence(1.0, 4.0, 16.0) - 4.0) < 1e-12); /* 1/n^2 */
    assert_true(progressive_read_convergence(1.0, 2.0, 0.0) == 2.0); /* no third pass */
    /* Alternating, a slow pass (2.3x) between fast ones (3.2x), as fog-dof's
     * noise from 1 to 8 samples: exact for the alternating model, outside
     * the mixed one (c1 / c0 = 1.89 < 2), which does not vote; before, the
     * mixed model read 1.96 there, the estimate was taken as if x were 2. */
    double v[4] = {1.0, 1.0 / 3.2, 1.0 / (3.2 * 2.3), 1.0 / (3.2 * 2.3 * 3.2)}; /* 1..8 */
    double x = progressive_read_convergence(v[2] - v[3], v[1] - v[2], v[0] - v[1]);
    assert_true(fabs(x - 3.2) < 1e-9);
    /* V(n) = A / n^2 + B / n with A = B = 1, at n = 16: the slower model
     * never reads faster than the truth, V(8) / V(16) = 2.118. */
    double V[4];
    for (int k = 0; k < 4; ++k) {
        double n = 16.0 / (double)(1 << k);
        V[k] = 1.0 / (n * n) + 1.0 / n;
    }
    x = progressive_read_convergence(V[1] - V[0], V[2] - V[1], V[3] - V[2]);
    assert_true(x >= 2.0 && x <= V[1] / V[0] + 1e-12);
    assert_true(x > 2.1); /* the mixed model is exact here */
}

/* Bit-for-bit copies of every accumulator array of f. */
static double *copy_accumulators(film *f, size_t *count)
{
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    size_t n = 0;
    for (int i = 0; i < FILM_DOUBLE_ARRAYS; ++i)
        n += acc.double_count[i];
    n += acc.count_count; /* counts stored as doubles: exact below 2^53 */
    double *out = malloc(n * sizeof *out), *p = out;
    assert_non_null(out);
    for (int i = 0; i < FILM_DOUBLE_ARRAYS; ++i)
        for (size_t k = 0; k < acc.double_count[i]; ++k)
            *p++ = acc.doubles[i][k];
    for (size_t k = 0; k < acc.count_count; ++k)
        *p++ = (double)acc.counts[k];
    *count = n;
    return out;
}

/* A pass of --target-error saves and restores only the pixels it renders,
 * and measures only the tiles it rendered: a masked snapshot undoes samples
 * added to its pixels exactly, and a measure whose active tiles did not
 * change gives the figures of a full one, also when the tile sums were
 * summed across ranks in between. */
static void test_masked_snapshot_and_measure(void **state)
{
    (void)state;
    film_snapshot *snap;
    film *f = noise_film_and_copy(777, 4, &snap);
    uint64_t rng = 778;
    hz_error err = {0};
    unsigned char mask[64 * 32], all[64 * 32];
    memset(all, 1, sizeof all);
    for (int i = 0; i < 64 * 32; ++i) /* runs of 1-3 pixels, across rows */
        mask[i] = (i / 3 + i % 7) % 3 == 0;
    size_t n0, n1, n2;
    double *before = copy_accumulators(f, &n0);
    rgb *value = malloc(64 * 32 * sizeof *value);
    assert_non_null(value);
    for (int i = 0; i < 64 * 32; ++i)
        value[i] = film_get_pixel(f, i % 64, i / 64, 1.0);
    film_snapshot_save_pixels(snap, f, mask);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            if (mask[y * 64 + x])
                film_add_sample(f, x, y, rgb_grey(0.25 + 0.01 * x), 0.5, INFINITY);
    /* The copy is packed (the masked pixels in mask order): each pixel is
     * found in its place. */
    for (int i = 0; i < 64 * 32; ++i)
        if (mask[i]) {
            rgb was = film_snapshot_pixel(snap, f, i % 64, i / 64, 1.0);
            assert_memory_equal(&was, &value[i], sizeof was);
        }
    free(value);
    double *during = copy_accumulators(f, &n1);
    assert_true(n1 == n0 && memcmp(before, during, n0 * sizeof *before) != 0);
    film_snapshot_restore_pixels(snap, f, mask);
    double *after = copy_accumulators(f, &n2);
    assert_true(n2 == n0 && memcmp(before, after, n0 * sizeof *before) == 0);
    free(before);
    free(during);
    free(after);

    /* The halves against the last full save, then the left tiles again. */
    film_snapshot_save(snap, f);
    add_noise(f, 4, &rng);
    progressive_error pe;
    assert_int_equal(progressive_error_init(&pe, f, &err), HZ_OK);
    progressive_error_measure(&pe, f, snap, all, 12, 16, 1.0, 2);
    size_t sums = PROGRESSIVE_TILE_SUMS * (size_t)pe.tile_count;
    double *full = malloc(sums * sizeof *full), *e = malloc(64 * 32 * sizeof *e);
    assert_non_null(full);
    assert_non_null(e);
    memcpy(full, pe.tile_sums, sums * sizeof *full);
    memcpy(e, pe.e, 64 * 32 * sizeof *e);
    for (size_t i = 0; i < sums; ++i) /* as summed over two ranks */
        pe.tile_sums[i] *= 2.0;
    unsigned char left[64 * 32];
    for (int i = 0; i < 64 * 32; ++i)
        left[i] = i % 64 < 16 && i % 5 == 0; /* some pixels of the left tiles */
    progressive_error_measure(&pe, f, snap, left, 12, 16, 1.0, 2);
    assert_true(full[0] > 0.0 && full[sums - PROGRESSIVE_TILE_SUMS] > 0.0);
    /* Every tile's figures of its pixels (halves, roots, pixels) are those of
     * the full measure; the sums over the last pass's pixels only the left
     * tiles have. */
    for (int t = 0; t < pe.tile_count; ++t) {
        const double *got = pe.tile_sums + PROGRESSIVE_TILE_SUMS * (size_t)t,
                     *want = full + PROGRESSIVE_TILE_SUMS * (size_t)t;
        assert_memory_equal(got, want, 3 * sizeof *got);
        if (t % pe.tiles_x == 0)
            assert_true(got[3] > 0.0 && got[3] < want[3] && got[4] > 0.0 && got[5] > 0.0);
        else
            assert_true(got[3] == 0.0 && got[4] == 0.0 && got[5] == 0.0);
    }
    assert_memory_equal(pe.e, e, 64 * 32 * sizeof *e);
    free(full);
    free(e);
    progressive_error_free(&pe);
    film_snapshot_destroy(snap);
    film_destroy(f);
}

/* A fog sphere (noisy) in front of a plain sky (exact from one sample). */
static const char *const FOG_SPHERE_SCENE =
    "LookAt 0 1 -4  0 0.7 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 40\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 1024\n"
    "WorldBegin\n"
    "LightSource \"distant\" \"point3 from\" [1 3 -2] \"point3 to\" [0 0 0]"
    " \"rgb L\" [3 3 3]\n"
    "LightSource \"infinite\" \"rgb L\" [0.3 0.35 0.4]\n"
    "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
    "    \"rgb sigma_a\" [0.2 0.2 0.2] \"rgb sigma_s\" [2 2 2]\n"
    "AttributeBegin\n"
    "  Material \"interface\"\n"
    "  MediumInterface \"fog\" \"\"\n"
    "  Translate 0 0.7 0\n"
    "  Shape \"sphere\" \"float radius\" 0.8\n"
    "AttributeEnd\n";

/* The estimate of pass N's progress line, parsed. */
static double reported_estimate(const char *log, int pass)
{
    char key[32];
    snprintf(key, sizeof key, "pass %d: ", pass);
    const char *line = strstr(log, key);
    assert_non_null(line);
    const char *at = strstr(line, "estimated relMSE ");
    assert_non_null(at);
    double reported = 0.0;
    assert_int_equal(sscanf(at, "estimated relMSE %lf", &reported), 1);
    return reported;
}

/* The image's estimates after the first two passes of a --target-error
 * render (their progress lines) are the ones measured by hand: two samples
 * in one pass, whose halves estimate is the film's variance (no copy: the
 * first pass is never undone); then a copy of the film, two more samples,
 * the halves of every pixel against the copy. A copy missed before the
 * second pass would leave its halves against an empty film. */
static void test_pass_estimates(void **state)
{
    (void)state;
    const double target = 1e-4; /* far: every pixel goes on to 20 samples */
    render_options ro = {.statistics = true, .spp = 1024};
    render_scene *rs = build_scene_or_fail(FOG_SPHERE_SCENE, &ro);
    char *log = NULL;
    size_t log_size = 0;
    FILE *progress = open_memstream(&log, &log_size);
    assert_non_null(progress);
    renderer_options opt = {.threads = 2, .progress = progress};
    render_stats st;
    hz_error err = {0};
    progressive_goal goal = {0.0, target, 0.0};
    assert_int_equal(renderer_run_progressive(rs, &opt, &goal, &st, &err), HZ_OK);
    fclose(progress);
    assert_non_null(strstr(log, "pass 1: 2 of 1024 spp"));
    assert_non_null(strstr(log, "pass 2: 4 of 1024 spp"));
    double reported[2] = {reported_estimate(log, 1), reported_estimate(log, 2)};
    free(log);
    render_scene_destroy(rs);

    rs = build_scene_or_fail(FOG_SPHERE_SCENE, &ro);
    film *f = render_scene_film(rs);
    renderer_options two = {.threads = 2, .sample_begin = 0, .sample_end = 2};
    assert_int_equal(renderer_run(rs, &two, &st, &err), HZ_OK);
    progressive_error pe;
    assert_int_equal(progressive_error_init(&pe, f, &err), HZ_OK);
    unsigned char active[32 * 24];
    memset(active, 1, sizeof active);
    double ratio = camera_imaging_ratio(render_scene_camera(rs), film_get_params(f));
    double expected[2] = {0.0, 0.0};
    progressive_error_measure(&pe, f, NULL, active, 0, 2, ratio, 2);
    assert_int_equal(progressive_error_select(&pe, f, &goal, active, &expected[0]),
                     (long)sizeof active);
    film_snapshot *copy = film_snapshot_create(f, &err);
    assert_non_null(copy);
    two.sample_begin = 2;
    two.sample_end = 4;
    assert_int_equal(renderer_run(rs, &two, &st, &err), HZ_OK);
    progressive_error_measure(&pe, f, copy, active, 2, 4, ratio, 2);
    progressive_error_select(&pe, f, &goal, active, &expected[1]);
    for (int p = 0; p < 2; ++p) {
        if (verbose_on())
            print_message("pass %d estimate %.6g, by hand %.6g\n", p + 1, reported[p],
                          expected[p]);
        assert_true(expected[p] > 0.0);
        assert_true(fabs(reported[p] - expected[p]) <= 1e-2 * expected[p]); /* 3 digits */
    }
    film_snapshot_destroy(copy);
    render_scene_destroy(rs);

    /* The first estimate, the film's s^2 / n, is the halves estimate of two
     * one-sample passes: at equal weights (this scene's samples have them)
     * both are (a - b)^2 / 4 per pixel, equal to rounding (3e-16 relative
     * when written). */
    progressive_error_free(&pe); /* a new render: no passes before */
    rs = build_scene_or_fail(FOG_SPHERE_SCENE, &ro);
    f = render_scene_film(rs);
    assert_int_equal(progressive_error_init(&pe, f, &err), HZ_OK);
    renderer_options one = {.threads = 2, .sample_begin = 0, .sample_end = 1};
    assert_int_equal(renderer_run(rs, &one, &st, &err), HZ_OK);
    copy = film_snapshot_create(f, &err);
    assert_non_null(copy);
    one.sample_begin = 1;
    one.sample_end = 2;
    assert_int_equal(renderer_run(rs, &one, &st, &err), HZ_OK);
    memset(active, 1, sizeof active);
    double halves = 0.0;
    progressive_error_measure(&pe, f, copy, active, 1, 2, ratio, 2);
    progressive_error_select(&pe, f, &goal, active, &halves);
    if (verbose_on())
        print_message("two passes of one sample: %.6g\n", halves);
    assert_true(fabs(halves - expected[0]) <= 1e-9 * expected[0]);
    film_snapshot_destroy(copy);
    progressive_error_free(&pe);
    render_scene_destroy(rs);
}

static void render_adaptive(const char *text, int threads, double target, film_snapshot **out,
                            render_stats *st, render_scene **keep)
{
    render_options ro = {.statistics = true, .spp = 1024};
    render_scene *rs = build_scene_or_fail(text, &ro);
    renderer_options opt = {.threads = threads};
    hz_error err = {0};
    assert_int_equal(
        renderer_run_progressive(rs, &opt, &(progressive_goal){0.0, target, 0.0}, st, &err), HZ_OK);
    *out = film_snapshot_create(render_scene_film(rs), &err);
    assert_non_null(*out);
    *keep = rs;
}

/* A fog sphere (noisy) in front of a plain sky (exact from one sample):
 * the same image for 1 and 2 threads; sky pixels stop at the least count;
 * the measured relMSE against a 1024-sample render meets the target. */
static void test_target_error_render(void **state)
{
    (void)state;
    const char *text = FOG_SPHERE_SCENE;
    const double target = 1e-3;
    film_snapshot *a, *b;
    render_stats sa, sb;
    render_scene *ra, *rb;
    render_adaptive(text, 1, target, &a, &sa, &ra);
    render_adaptive(text, 2, target, &b, &sb, &rb);
    film *fa = render_scene_film(ra), *fb = render_scene_film(rb);
    size_t n1 = 0, n2 = 0;
    unsigned char *ba = film_bytes(fa, &n1), *bb = film_bytes(fb, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(ba, bb, n1);
    free(ba);
    free(bb);
    assert_true(sa.passes >= 3 && sa.passes == sb.passes);
    assert_true(sa.samples < 0.5 * 1024 * 32 * 24); /* adaptive: far fewer than the cap */

    /* The reference: 1024 samples everywhere. */
    render_scene *ref = build_scene_or_fail(text, NULL);
    renderer_options opt = {.threads = 2};
    render_stats sr;
    hz_error err = {0};
    assert_int_equal(renderer_run(ref, &opt, &sr, &err), HZ_OK);
    film *fr = render_scene_film(ref);
    double rel = 0.0;
    /* every pixel's least: 0.2 / sqrt(E) = 6.3, the pass that reaches it: 8 */
    long sky = 0, sky_least = 0, most = 0, least = 8;
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 32; ++x) {
            rgb p = film_get_pixel(fa, x, y, 1.0), r = film_get_pixel(fr, x, y, 1.0);
            double c[3] = {p.r - r.r, p.g - r.g, p.b - r.b}, q[3] = {r.r, r.g, r.b};
            for (int k = 0; k < 3; ++k)
                rel += c[k] * c[k] / ((q[k] + 0.01) * (q[k] + 0.01)) / 3.0;
            long count = film_get_sample_count(fa, x, y);
            most = count > most ? count : most;
            if (film_get_variance(fa, x, y, 1.0).r == 0.0 && fabs(r.g - 0.35) < 1e-9) {
                ++sky;
                sky_least += count == least;
            }
        }
    rel /= 32 * 24;
    if (verbose_on())
        print_message("relMSE %.3g (target %.3g), %.2f spp mean, %ld max, %ld sky pixels\n",
                      rel, target, sa.samples / (32.0 * 24), most, sky);
    assert_true(rel <= target);
    /* The sky stops at the least (but next to the fog: its neighbours' error) */
    assert_true(sky > 50 && sky_least > 0.8 * sky);
    assert_true(most > least); /* the fog did not */
    render_scene_destroy(ref);
    film_snapshot_destroy(a);
    film_snapshot_destroy(b);
    render_scene_destroy(ra);
    render_scene_destroy(rb);
}

/* The relMSE of film f against ref's film (haze diff's). */
static double film_rel_mse(film *f, film *ref, int w, int h)
{
    double rel = 0.0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            rgb p = film_get_pixel(f, x, y, 1.0), r = film_get_pixel(ref, x, y, 1.0);
            double c[3] = {p.r - r.r, p.g - r.g, p.b - r.b}, q[3] = {r.r, r.g, r.b};
            for (int k = 0; k < 3; ++k)
                rel += c[k] * c[k] / ((q[k] + 0.01) * (q[k] + 0.01)) / 3.0;
        }
    return rel / (w * h);
}

/* Multiple scattering in a dense, bright sphere of fog over black (volpath,
 * albedo 0.97): path contributions come in a few discrete levels, so a
 * pixel's first samples often agree: on the silhouette, two samples that
 * both miss a partly covering sphere, inside, two equal paths. With only
 * their own variance such pixels stopped at the least count, and the image
 * missed E = 1e-2 (relMSE 0.012-0.018 for seeds 1-3); the spread of the
 * neighbours' means is a floor under it. Three seeds meet E against a
 * 4096-sample render. */
static void test_target_error_heavy_tails(void **state)
{
    (void)state;
    const char *text =
        "LookAt 0 1 -4  0 0.7 0  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 30\n"
        "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 24\n"
        "Sampler \"zsobol\" \"integer pixelsamples\" 4096\n"
        "Integrator \"volpath\" \"integer maxdepth\" 64\n"
        "WorldBegin\n"
        "LightSource \"distant\" \"point3 from\" [1 3 -2] \"point3 to\" [0 0 0]"
        " \"rgb L\" [3 3 3]\n"
        "MakeNamedMedium \"cloud\" \"string type\" \"homogeneous\"\n"
        "    \"rgb sigma_a\" [0.25 0.25 0.25] \"rgb sigma_s\" [8 8 8]\n"
        "AttributeBegin\n"
        "  Material \"interface\"\n"
        "  MediumInterface \"cloud\" \"\"\n"
        "  Translate 0 0.7 0\n"
        "  Shape \"sphere\" \"float radius\" 0.8\n"
        "AttributeEnd\n";
    const double target = 1e-2;
    render_scene *ref = build_scene_or_fail(text, NULL);
    renderer_options opt = {.threads = 2};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run(ref, &opt, &st, &err), HZ_OK);
    for (uint64_t seed = 1; seed <= 3; ++seed) {
        render_options ro = {.statistics = true, .spp = 4096, .seed = seed};
        render_scene *rs = build_scene_or_fail(text, &ro);
        assert_int_equal(renderer_run_progressive(rs, &opt, &(progressive_goal){0.0, target, 0.0},
                                                  &st, &err),
                         HZ_OK);
        double rel = film_rel_mse(render_scene_film(rs), render_scene_film(ref), 24, 24);
        if (verbose_on())
            print_message("heavy tails, seed %d: relMSE %.4g (target %.3g), %.2f spp mean\n",
                          (int)seed, rel, target, st.samples / (24.0 * 24));
        assert_true(rel <= target);
        render_scene_destroy(rs);
    }
    render_scene_destroy(ref);
}

/* The fog sphere marched with `estimator` at `step` voxels (shadow step twice it). */
static char *pilot_scene(const char *estimator, double step)
{
    return fog_sphere_scene(estimator, step, 2.0 * step, 0.0);
}

/* The pilot from `step` with `estimator` for target E: its choice, and the
 * chosen step's whole-image relMSE (spp samples a pixel) against a raymarch
 * 16 times finer with exact shadow rays. */
static double pilot_bias(const char *estimator, double step, double E, int spp, step_choice *ch)
{
    char *text = pilot_scene(estimator, step);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    step_pilot_choose(rs, E, 2, NULL, ch);
    assert_true(ch->applies);
    text = pilot_scene("raymarch", ch->step / 16.0);
    render_scene *fine = build_scene_or_fail(text, NULL);
    free(text);
    double e = centre_rel_mse(rs, fine, 32, 32, spp, NULL);
    print_message("pilot (%s from step %g, E = %g): step %g, estimated bias %.3g, %d renders; "
                  "%d spp against step %g: %.3g (share %.3g)\n",
                  estimator, step, E, ch->step, ch->bias, ch->renders, spp, ch->step / 16.0, e,
                  STEP_PILOT_SHARE * E);
    render_scene_destroy(rs);
    render_scene_destroy(fine);
    return e;
}

/* --target-error's step pilot: from a coarse step (8 voxels, relMSE far
 * above the target) it halves down to a step whose bias, measured over the
 * whole image against a step 16 times finer with exact shadow rays, is within
 * its share of E; it does not go needlessly fine (twice its step misses the
 * share); a tracking estimator is left alone. */
static void test_step_pilot(void **state)
{
    (void)state;
    const double E = 1e-3;
    char *text = pilot_scene("raymarch", 8.0);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    step_choice ch;
    step_pilot_choose(rs, E, 2, NULL, &ch);
    print_message("pilot: step %g (shadow %g, cache %g), bias %.3g, %d pixels, %d renders\n",
                  ch.step, ch.shadow_step, ch.shadow_cache, ch.bias, ch.pixels, ch.renders);
    assert_true(ch.applies);
    assert_true(ch.step < 8.0 && ch.shadow_step == 2.0 * ch.step);
    /* A static grid under a distant light: the pilot uses a shadow cache at
     * the step (its bias measured with the step's, against exact shadow
     * rays below). */
    assert_true(ch.shadow_cache == ch.step);
    assert_non_null(render_scene_shadow_caches(rs));
    assert_true(ch.bias <= STEP_PILOT_SHARE * E);
    double fine_step = ch.step / 16.0;
    text = pilot_scene("raymarch", fine_step);
    render_scene *fine = build_scene_or_fail(text, NULL);
    free(text);
    text = pilot_scene("raymarch", 2.0 * ch.step);
    render_scene *coarse = build_scene_or_fail(text, NULL);
    free(text);
    double chosen = centre_rel_mse(rs, fine, 32, 32, 1, NULL),
           twice = centre_rel_mse(coarse, fine, 32, 32, 1, NULL);
    print_message("whole image against step %g: chosen %.3g, twice the step %.3g (share %.3g)\n",
                  fine_step, chosen, twice, STEP_PILOT_SHARE * E);
    assert_true(chosen <= STEP_PILOT_SHARE * E);
    assert_true(twice > 0.25 * STEP_PILOT_SHARE * E);
    render_scene_destroy(rs);
    render_scene_destroy(fine);
    render_scene_destroy(coarse);

    /* From a fine step and a loose target it goes coarser and stays within
     * the share; coming down from the coarsest step, it renders nothing
     * finer than half the step it chooses (not the scene's own step). */
    chosen = pilot_bias("raymarch", 0.25, 1e-2, 1, &ch);
    assert_true(ch.step > 0.25 && chosen <= STEP_PILOT_SHARE * 1e-2);
    assert_true(ch.finest == 0.5 * ch.step);
    /* Jittered marching: its noise is told from its bias (8 paired samples
     * per pilot pixel); measured with 64 samples per pixel. */
    chosen = pilot_bias("jittered", 8.0, E, 64, &ch);
    assert_true(ch.step < 8.0 && chosen <= STEP_PILOT_SHARE * E);
    /* The same choice and estimate on one thread as on two. */
    text = pilot_scene("jittered", 8.0);
    rs = build_scene_or_fail(text, NULL);
    free(text);
    step_choice one;
    step_pilot_choose(rs, E, 1, NULL, &one);
    render_scene_destroy(rs);
    assert_true(one.step == ch.step && one.bias == ch.bias && one.renders == ch.renders);
    /* On this 32x32 image the render's first pass is 2048 samples: a tenth
     * of that (at any step's cost a sample) is less than one comparison's
     * first 64 pixels of 8 samples, so no comparison grows past them. */
    assert_int_equal(ch.pixels, STEP_PILOT_START_PIXELS);
    /* The same with the render capped at 2 samples a pixel (--spp 2): the
     * pilot's 8 samples are its own, not the render's 2. */
    text = pilot_scene("jittered", 8.0);
    rs = build_scene_or_fail(text, &(render_options){.spp = 2});
    free(text);
    step_choice capped;
    step_pilot_choose(rs, E, 2, NULL, &capped);
    render_scene_destroy(rs);
    assert_true(capped.step == ch.step && capped.bias == ch.bias && capped.renders == ch.renders);

    text = pilot_scene("residual", 8.0);
    rs = build_scene_or_fail(text, NULL);
    free(text);
    step_pilot_choose(rs, E, 2, NULL, &ch);
    assert_false(ch.applies);
    render_scene_destroy(rs);
}

/* The step pilot where the medium covers a small part of the image: the
 * bench cloud (volumes/plume.vdb, a sixth of a 320x240 image) at E = 1e-2.
 * Of a comparison's first 64 pixels about ten see the cloud; on those the
 * comparison of steps 32 and 16 read as a clear pass and the pilot chose
 * step 32. Comparisons now take pixels until 32 of them tell the steps
 * apart: steps 8 and 4 then differ by an estimated 1.9e-2 (four times the
 * goal), so the step chosen is finer than 8. */
static void test_step_pilot_small_medium(void **state)
{
    (void)state;
    char text[4096];
    snprintf(text, sizeof text,
             "LookAt 1.2 1.1 -3.0  -0.05 0.95 -0.05  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 40\n"
             "Film \"rgb\" \"integer xresolution\" 320 \"integer yresolution\" 240\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
             "WorldBegin\n"
             "LightSource \"distant\" \"point3 from\" [-2 1.2 -1] \"point3 to\" [0 0 0]"
             " \"rgb L\" [9 8.5 8]\n"
             "LightSource \"infinite\" \"rgb L\" [0.08 0.1 0.14]\n"
             "MakeNamedMedium \"cloud\" \"string type\" \"nanovdb\" \"string filename\" \"%s\"\n"
             "    \"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [60 60 60] \"float g\" 0.6\n"
             "AttributeBegin\n  Material \"interface\"\n  MediumInterface \"cloud\" \"\"\n"
             "  Shape \"trianglemesh\" \"integer indices\" [0 6 2  0 4 6  1 3 7  1 7 5  0 1 5"
             "  0 5 4  2 7 3  2 6 7  0 3 1  0 2 3  4 5 7  4 7 6]\n"
             "    \"point3 P\" [-0.42 -0.05 -0.42  0.31 -0.05 -0.42  -0.42 1.96 -0.42"
             "  0.31 1.96 -0.42  -0.42 -0.05 0.31  0.31 -0.05 0.31  -0.42 1.96 0.31"
             "  0.31 1.96 0.31]\n"
             "AttributeEnd\n",
             HAZE_SCENES "/../volumes/plume.vdb");
    render_scene *rs = build_scene_or_fail(text, NULL);
    step_choice ch;
    /* Loading built no majorant cells; the pilot's fine walks bound those
     * of the bricks they reached, and the media report it. */
    medium_work w0 = render_scene_media_work(rs);
    step_pilot_choose(rs, 1e-2, 2, NULL, &ch);
    medium_work w = render_scene_media_work(rs);
    print_message("pilot on the cloud: step %g, bias %.3g, %d pixels, %d renders, "
                  "%zu majorant bricks built (%.4f s)\n",
                  ch.step, ch.bias, ch.pixels, ch.renders, w.majorant_bricks, w.majorant_seconds);
    render_scene_destroy(rs);
    assert_int_equal(w0.majorant_bricks, 0);
    assert_true(w0.majorant_seconds == 0.0);
    assert_true(w.majorant_bricks > 0 && w.majorant_seconds > 0.0);
    assert_true(ch.applies);
    assert_true(ch.step < 8.0 && ch.bias <= STEP_PILOT_SHARE * 1e-2);
    assert_true(ch.pixels > STEP_PILOT_START_PIXELS);
}

static char dir[1024];

/* The command line: a limit no render reaches gives the full render's pixels
 * and says so in the header; a short one still writes a whole image (the
 * first pass at least) within about the limit; bad values are usage errors. */
static void test_command_line(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "%s/progressive-%ld", HAZE_TMP, (long)getpid());
    mkdir(dir, 0755);
    char scene[1200], full[1200], prog[1200], quick[1200], args[4096], out[8192];
    snprintf(scene, sizeof scene, "%s/s.pbrt", dir);
    snprintf(full, sizeof full, "%s/full.exr", dir);
    snprintf(prog, sizeof prog, "%s/prog.exr", dir);
    snprintf(quick, sizeof quick, "%s/quick.exr", dir);
    char *text = scene_text(8);
    write_text_file(scene, text);
    free(text);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet", scene, full);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "render '%s' -o '%s' --time-limit 1e6", scene, prog);
    if (run_haze(args, out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_non_null(strstr(out, "8 spp in 4 passes"));
    assert_true(exr_pixels_equal(full, prog));
    exr_image img;
    hz_error err = {0};
    assert_int_equal(exr_read(prog, &img, &err), HZ_OK);
    const char *passes = exr_attribute(&img, "haze:passes"), *spp = exr_attribute(&img, "haze:spp");
    assert_non_null(passes);
    assert_non_null(spp);
    assert_string_equal(passes, "4");
    assert_string_equal(spp, "8");
    exr_image_free(&img);

    double t0 = hz_clock_seconds();
    snprintf(args, sizeof args, "render '%s' -o '%s' --spp 1048576 --time-limit 0.5 --quiet",
             scene, quick);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    double took = hz_clock_seconds() - t0;
    assert_true(took < (UNDER_ASAN ? 30.0 : 5.0));
    assert_int_equal(exr_read(quick, &img, &err), HZ_OK);
    spp = exr_attribute(&img, "haze:spp");
    assert_non_null(spp);
    assert_true(atol(spp) >= 1 && atol(spp) < 1048576);
    exr_image_free(&img);

    const char *bad[] = {"0", "-1", "abc", "nan", "inf", "1e10"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(args, sizeof args, "render '%s' -o '%s' --time-limit %s", scene, quick, bad[i]);
        assert_int_equal(run_haze(args, out, sizeof out), 2);
        assert_non_null(strstr(out, "--time-limit"));
        snprintf(args, sizeof args, "render '%s' -o '%s' --target-error %s", scene, quick,
                 bad[i]);
        assert_int_equal(run_haze(args, out, sizeof out), 2);
        assert_non_null(strstr(out, "--target-error"));
    }

    /* --target-error: the film records each pixel's samples and variance */
    snprintf(args, sizeof args, "render '%s' -o '%s' --target-error 1e-2 --spp 64", scene, quick);
    if (run_haze(args, out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_non_null(strstr(out, "spp at most ("));
    assert_int_equal(exr_read(quick, &img, &err), HZ_OK);
    assert_non_null(exr_attribute(&img, "haze:target_error"));
    assert_non_null(exr_attribute(&img, "haze:spp_mean"));
    const char *estimated = exr_attribute(&img, "haze:estimated_error");
    assert_non_null(estimated);
    assert_true(atof(estimated) > 0.0 && atof(estimated) <= 1e-2);
    assert_null(strstr(out, "not reached"));
    bool has_count = false;
    for (int c = 0; c < img.channel_count; ++c)
        has_count |= !strcmp(img.channels[c].name, "SampleCount.Y");
    assert_true(has_count);
    exr_image_free(&img);
    /* A target the --spp cap keeps the passes from: the render says so, and
     * the header has the estimate it stopped at; one sample a pixel gives
     * no estimate, and says that. */
    snprintf(args, sizeof args, "render '%s' -o '%s' --target-error 1e-8 --spp 4 --quiet", scene,
             quick);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "--target-error 1e-08 not reached: estimated relMSE "));
    assert_non_null(strstr(out, "(the --spp cap stopped the passes)"));
    assert_int_equal(exr_read(quick, &img, &err), HZ_OK);
    estimated = exr_attribute(&img, "haze:estimated_error");
    assert_non_null(estimated);
    assert_true(atof(estimated) > 1e-8);
    exr_image_free(&img);
    snprintf(args, sizeof args, "render '%s' -o '%s' --target-error 1e-2 --spp 1 --quiet", scene,
             quick);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "no error estimate, which needs two samples a pixel"));
    assert_int_equal(exr_read(quick, &img, &err), HZ_OK);
    assert_null(exr_attribute(&img, "haze:estimated_error"));
    exr_image_free(&img);
    unlink(scene);
    unlink(full);
    unlink(prog);
    unlink(quick);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pass_schedule),
        cmocka_unit_test(test_all_passes_bit_identical),
        cmocka_unit_test(test_first_pass_always_completes),
        cmocka_unit_test(test_cut_pass_undone),
        cmocka_unit_test(test_command_line),
        cmocka_unit_test(test_error_estimate),
        cmocka_unit_test(test_convergence_correction),
        cmocka_unit_test(test_read_convergence),
        cmocka_unit_test(test_single_bright_sample),
        cmocka_unit_test(test_masked_snapshot_and_measure),
        cmocka_unit_test(test_target_error_render),
        cmocka_unit_test(test_pass_estimates),
        cmocka_unit_test(test_target_error_heavy_tails),
        cmocka_unit_test(test_step_pilot),
        cmocka_unit_test(test_step_pilot_small_medium),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
