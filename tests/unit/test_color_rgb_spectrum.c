/* color/rgb_spectrum: RGB -> spectrum -> XYZ -> RGB round trips, integrated
 * here independently of the generator (Simpson's rule at 0.25 nm against the
 * CIE 1931 observer, with this file's own white and matrices), for every
 * colour of a dense grid and random colours in each colour space; the
 * illuminant spectra; the unbounded scale; continuity of the table lookup
 * across cell and component boundaries. */
#include "assert_util.h"

#include <stdbool.h>
#include <stdio.h>

#include "color/illuminant.h"
#include "color/rgb2spec_module.h"
#include "color/rgb_spectrum.h"
#include "scene/spectrum.h"

enum { MAX_NODES = 1881 }; /* 360..830 nm at 0.25 nm */

/* Per colour space: quadrature weight times the normalised illuminant times
 * the matching functions, over the integral of y-bar; the white and the
 * matrices made from it here. */
typedef struct {
    int n;
    double lambda[MAX_NODES];
    vec3 w[MAX_NODES];
    vec3 white;
    double rgb_from_xyz[9];
} quad;

/* Simpson's rule at 0.25 nm, and at 1 nm for the scan of every cell. */
static quad quads[COLOR_SPACE_COUNT], coarse_srgb;
/* The module's tables, loaded once by setup. */
static const rgb2spec_table *tables;

static const rgb2spec_table *table(color_space cs) { return &tables[cs]; }
static const rgb2spec_table *srgb(void) { return table(COLOR_SPACE_SRGB); }

static void quad_init(color_space cs, double step, quad *q)
{
    double y_bar = 0.0;
    q->n = (int)((830.0 - 360.0) / step + 0.5) + 1;
    assert_true(q->n <= MAX_NODES && q->n % 2 == 1);
    q->white = v3(0, 0, 0);
    for (int n = 0; n < q->n; ++n) {
        double l = 360.0 + n * step;
        double qw = (n == 0 || n == q->n - 1 ? 1.0 : n % 2 ? 4.0 : 2.0) * step / 3.0;
        vec3 cmf = spectrum_cie_xyz(l);
        q->lambda[n] = l;
        q->w[n] = v3_scale(cmf, qw * rgb_spectrum_illuminant(table(cs), l));
        y_bar += qw * cmf.y;
    }
    for (int n = 0; n < q->n; ++n) {
        q->w[n] = v3_scale(q->w[n], 1.0 / y_bar);
        q->white = v3_add(q->white, q->w[n]);
    }
    double w[3] = {q->white.x, q->white.y, q->white.z};
    color_space_rgb_from_xyz_white(cs, w, q->rgb_from_xyz);
}

static int setup(void **state)
{
    (void)state;
    hz_error err;
    if (rgb2spec_tables_load(&tables, &err) != HZ_OK) {
        print_error("%s\n", err.message);
        return -1;
    }
    for (int cs = 0; cs < COLOR_SPACE_COUNT; ++cs)
        quad_init((color_space)cs, 0.25, &quads[cs]);
    quad_init(COLOR_SPACE_SRGB, 1.0, &coarse_srgb);
    return 0;
}

static rgb rgb_of_xyz(const quad *q, vec3 v)
{
    const double *m = q->rgb_from_xyz;
    return rgb_make(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
                    m[6] * v.x + m[7] * v.y + m[8] * v.z);
}

/* The RGB of the reflectance p under the illuminant of q's space. */
static rgb reflectance_rgb_q(const quad *q, sigmoid_poly p)
{
    vec3 xyz = v3(0, 0, 0);
    for (int n = 0; n < q->n; ++n)
        xyz = v3_add(xyz, v3_scale(q->w[n], sigmoid_poly_eval(p, q->lambda[n])));
    return rgb_of_xyz(q, xyz);
}

static rgb reflectance_rgb(color_space cs, sigmoid_poly p)
{
    return reflectance_rgb_q(&quads[cs], p);
}

static double rgb_error(rgb a, rgb b)
{
    return hz_fmax(fabs(a.r - b.r), hz_fmax(fabs(a.g - b.g), fabs(a.b - b.b)));
}

static double round_trip_error(color_space cs, rgb c)
{
    return rgb_error(reflectance_rgb(cs, sigmoid_poly_from_rgb(table(cs), c)), c);
}

/* Whether the sRGB of c (in cs) has every component in [lo, 1 - lo]. */
static bool inside_srgb(color_space cs, rgb c, double lo)
{
    double m[9];
    color_space_convert_matrix(cs, COLOR_SPACE_SRGB, m);
    double s[3] = {m[0] * c.r + m[1] * c.g + m[2] * c.b, m[3] * c.r + m[4] * c.g + m[5] * c.b,
                   m[6] * c.r + m[7] * c.g + m[8] * c.b};
    for (int k = 0; k < 3; ++k)
        if (s[k] < lo - 1e-9 || s[k] > 1.0 - lo + 1e-9)
            return false;
    return true;
}

/* Which colours of a space are checked, and to what tolerance: those whose
 * sRGB lies in [srgb_margin, 1 - srgb_margin] and whose own components lie in
 * [lo, hi]; `tol` for those whose largest component is at most `ceiling`,
 * `tol_top` above it. */
typedef struct {
    color_space cs;
    double srgb_margin, lo, hi, ceiling, tol, tol_top;
} domain;

typedef struct {
    double worst;
    rgb at;
    int count;
} error_stats;

static void check_colour(const domain *d, rgb c, error_stats *st)
{
    if (!inside_srgb(d->cs, c, d->srgb_margin))
        return;
    double e = round_trip_error(d->cs, c), tol = rgb_max(c) <= d->ceiling ? d->tol : d->tol_top;
    st->count++;
    if (e / tol > st->worst) {
        st->worst = e / tol;
        st->at = c;
    }
}

/* A grid^3 grid and `randoms` random colours over the domain's cube. */
static void check_domain(const domain *d, int grid, int randoms)
{
    error_stats st = {0};
    double span = d->hi - d->lo;
    for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j)
            for (int k = 0; k < grid; ++k)
                check_colour(d, rgb_make(d->lo + span * i / (grid - 1.0),
                                         d->lo + span * j / (grid - 1.0),
                                         d->lo + span * k / (grid - 1.0)), &st);
    uint64_t seed = 0x5eed0000u + (uint64_t)d->cs;
    for (int n = 0; n < randoms; ++n) {
        double r = rng_next(&seed), g = rng_next(&seed), b = rng_next(&seed);
        check_colour(d, rgb_make(d->lo + span * r, d->lo + span * g, d->lo + span * b), &st);
    }
    double e = round_trip_error(d->cs, st.at);
    print_message("%s: %d colours, largest error/tolerance %.3f: %.3g at (%.4f, %.4f, %.4f)\n",
                  color_space_name(d->cs), st.count, st.worst, e, st.at.r, st.at.g, st.at.b);
    assert_true(st.count > grid * grid); /* the domain left colours to check */
    if (!(st.worst <= 1.0))
        fail_msg("%s: round trip off by %g at (%g, %g, %g)", color_space_name(d->cs), e,
                 st.at.r, st.at.g, st.at.b);
}

static void test_round_trip_srgb(void **state)
{
    (void)state;
    /* Every colour: 1e-3 up to a largest component of 0.985; within 1.5e-3 to
     * the top, where the spectra saturate at 1 (docs/spectral.md). */
    domain d = {COLOR_SPACE_SRGB, 0.0, 0.0, 1.0, 0.985, 1e-3, 1.5e-3};
    check_domain(&d, 33, 20000);
}

static void test_round_trip_other_spaces(void **state)
{
    (void)state;
    /* Colours well inside the sRGB gamut (components in [0.05, 0.95]) round
     * trip within 1e-3 in Rec. 2020 and DCI-P3; the whole sRGB gamut within
     * what docs/spectral.md lists, where neighbouring nodes are colours no
     * reflectance (or no sigmoid) has. */
    const domain ds[] = {
        {COLOR_SPACE_REC2020, 0.05, 0.0, 1.0, 1.0, 1e-3, 1e-3},
        {COLOR_SPACE_DCI_P3, 0.05, 0.0, 1.0, 1.0, 1e-3, 1e-3},
        {COLOR_SPACE_REC2020, 0.0, 0.0, 1.0, 1.0, 4e-3, 4e-3},
        {COLOR_SPACE_DCI_P3, 0.0, 0.0, 1.0, 1.0, 2e-3, 2e-3},
        /* ACES2065-1's cube is mostly outside the spectral locus: pbrt-v4's
         * own check uses [0.3, 0.7]^3. */
        {COLOR_SPACE_ACES2065_1, 0.0, 0.3, 0.7, 1.0, 1.5e-3, 1.5e-3},
        {COLOR_SPACE_ACES2065_1, 0.05, 0.0, 1.0, 1.0, 1e-2, 1e-2},
    };
    for (size_t i = 0; i < sizeof ds / sizeof ds[0]; ++i)
        check_domain(&ds[i], 33, 20000);
}

/* Every cell of the sRGB table at its centre, where a lookup is furthest
 * from the solved nodes; 1 nm steps are enough here. */
static void test_round_trip_srgb_every_cell(void **state)
{
    (void)state;
    const rgb2spec_solution *t = table(COLOR_SPACE_SRGB)->solution;
    int res = t->res;
    double worst = 0.0, worst_top = 0.0;
    rgb at = {0}, at_top = {0};
    for (int m = 0; m < 3; ++m)
        for (int k = 0; k < res - 1; ++k)
            for (int j = 0; j < res - 1; ++j)
                for (int i = 0; i < res - 1; ++i) {
                    double z = 0.5 * (t->z_nodes[k] + t->z_nodes[k + 1]), v[3];
                    v[m] = z;
                    v[(m + 1) % 3] = z * 0.5 * (t->xy_nodes[i] + t->xy_nodes[i + 1]);
                    v[(m + 2) % 3] = z * 0.5 * (t->xy_nodes[j] + t->xy_nodes[j + 1]);
                    rgb c = rgb_make(v[0], v[1], v[2]);
                    sigmoid_poly p = sigmoid_poly_from_rgb(srgb(), c);
                    double e = rgb_error(reflectance_rgb_q(&coarse_srgb, p), c);
                    double *w = z <= 0.985 ? &worst : &worst_top;
                    if (e > *w) {
                        *w = e;
                        *(z <= 0.985 ? &at : &at_top) = c;
                    }
                }
    print_message("srgb, 3 x %d^3 cell centres: largest error %.3g at (%.5f, %.5f, %.5f), "
                  "%.3g at (%.5f, %.5f, %.5f) above 0.985\n", res - 1, worst, at.r, at.g, at.b,
                  worst_top, at_top.r, at_top.g, at_top.b);
    assert_true(worst <= 1e-3);
    assert_true(worst_top <= 1.5e-3);
}

/* The XYZ of an emission spectrum f (no illuminant): integral(f xyz-bar) /
 * integral(y-bar), from the 0.25 nm weights of space cs divided by its
 * illuminant. */
static vec3 emission_xyz(color_space cs, rgb_illuminant_spectrum s)
{
    const quad *q = &quads[cs];
    vec3 xyz = v3(0, 0, 0);
    for (int n = 0; n < q->n; ++n) {
        double il = rgb_spectrum_illuminant(table(cs), q->lambda[n]);
        xyz = v3_add(xyz, v3_scale(q->w[n], rgb_illuminant_spectrum_eval(s, q->lambda[n]) / il));
    }
    return xyz;
}

/* pbrt-v4 normalises the colour spaces' illuminants to luminance 1; their
 * chromaticities are D65's and the ACES white point. RGB (1,1,1) as an
 * emitter is that illuminant exactly. */
static void test_illuminants(void **state)
{
    (void)state;
    assert_near(illuminant_raw(ILLUMINANT_D65, 560.0), 100.0, 0.0);
    assert_near(illuminant_raw(ILLUMINANT_D65, 555.0), 102.023, 1e-9); /* CIE table */
    assert_near(illuminant_raw(ILLUMINANT_D65, 557.5), 0.5 * (102.023 + 100.0), 1e-9);
    assert_near(illuminant_raw(ILLUMINANT_ACES_D60, 560.0), 100.0, 1e-9);
    const double want_xy[COLOR_SPACE_COUNT][2] = {[COLOR_SPACE_SRGB] = {0.3127, 0.3290},
                                                  [COLOR_SPACE_REC2020] = {0.3127, 0.3290},
                                                  [COLOR_SPACE_DCI_P3] = {0.3127, 0.3290},
                                                  [COLOR_SPACE_ACES2065_1] = {0.32168, 0.33767}};
    for (int cs = 0; cs < COLOR_SPACE_COUNT; ++cs) {
        const rgb2spec_table *t = table((color_space)cs);
        vec3 w = quads[cs].white, tw = rgb_spectrum_white_xyz(t);
        assert_near(w.y, 1.0, 1e-6); /* luminance 1 */
        assert_v3_near(tw, w, 1e-5); /* the generator's white, integrated apart */
        assert_near(w.x / (w.x + w.y + w.z), want_xy[cs][0], 2e-4);
        assert_near(w.y / (w.x + w.y + w.z), want_xy[cs][1], 2e-4);
        rgb_illuminant_spectrum s = rgb_illuminant_spectrum_from_rgb(t, rgb_grey(1));
        for (double l = 360.0; l <= 830.0; l += 3.7)
            assert_near(rgb_illuminant_spectrum_eval(s, l), rgb_spectrum_illuminant(t, l),
                        1e-12 * rgb_spectrum_illuminant(t, l));
        rgb back = rgb_spectrum_rgb_from_xyz(t, emission_xyz(cs, s));
        assert_true(rgb_error(back, rgb_grey(1)) < 1e-5);
    }
}

/* An unbounded RGB is 2 max times the reflectance of RGB / (2 max): the
 * spectrum scales with the RGB and round-trips as an emitter and under the
 * illuminant. */
static void test_unbounded_and_emitters(void **state)
{
    (void)state;
    const rgb cs_in[] = {{3.0, 1.5, 0.3, 1.5}, {0.2, 7.0, 0.01, 7.0}, {0.05, 0.1, 40.0, 0.1}, {0.6, 0.6, 0.6, 0.6}};
    for (size_t i = 0; i < sizeof cs_in / sizeof cs_in[0]; ++i) {
        rgb c = cs_in[i];
        double m = rgb_max(c);
        rgb_unbounded_spectrum u = rgb_unbounded_spectrum_from_rgb(srgb(), c);
        rgb_albedo_spectrum half =
            rgb_albedo_spectrum_from_rgb(srgb(), rgb_scale(c, 0.5 / m));
        assert_near(u.scale, 2.0 * m, 1e-15 * m);
        rgb_unbounded_spectrum u2 =
            rgb_unbounded_spectrum_from_rgb(srgb(), rgb_scale(c, 10.0));
        for (double l = 360.0; l <= 830.0; l += 5.3) {
            double v = rgb_unbounded_spectrum_eval(u, l);
            assert_near(v, 2.0 * m * rgb_albedo_spectrum_eval(half, l), 1e-12 * m);
            assert_near(rgb_unbounded_spectrum_eval(u2, l), 10.0 * v, 1e-9 * m);
        }
        /* Under the illuminant it is the RGB again, to the albedo's error
         * times 2 max; as an emitter (times the illuminant) too. */
        rgb back = rgb_scale(reflectance_rgb(COLOR_SPACE_SRGB, u.poly), u.scale);
        assert_true(rgb_error(back, c) <= 2.0 * m * 1e-3);
        rgb_illuminant_spectrum e = rgb_illuminant_spectrum_from_rgb(srgb(), c);
        rgb lit = rgb_spectrum_rgb_from_xyz(srgb(), emission_xyz(COLOR_SPACE_SRGB, e));
        assert_true(rgb_error(lit, c) <= 2.0 * m * 1e-3);
    }
    rgb_unbounded_spectrum zero = rgb_unbounded_spectrum_from_rgb(srgb(), rgb_grey(0));
    rgb_illuminant_spectrum dark =
        rgb_illuminant_spectrum_from_rgb(srgb(), rgb_make(-1.0, 0.0, NAN));
    assert_near(rgb_unbounded_spectrum_eval(zero, 500.0), 0.0, 0.0);
    assert_near(rgb_illuminant_spectrum_eval(dark, 500.0), 0.0, 0.0);
}

/* Greys are exact; out-of-range albedos are clamped; the maximum bounds the
 * spectrum. */
static void test_greys_clamping_and_max(void **state)
{
    (void)state;
    const double greys[] = {0.0, 1e-6, 0.18, 0.5, 0.9, 1.0};
    for (size_t i = 0; i < sizeof greys / sizeof greys[0]; ++i) {
        rgb_albedo_spectrum s = rgb_albedo_spectrum_from_rgb(srgb(), rgb_grey(greys[i]));
        for (double l = 360.0; l <= 830.0; l += 47.0)
            assert_near(rgb_albedo_spectrum_eval(s, l), greys[i], 1e-15);
    }
    rgb_albedo_spectrum hi = rgb_albedo_spectrum_from_rgb(srgb(), rgb_make(2, 1, 0.5));
    rgb_albedo_spectrum in = rgb_albedo_spectrum_from_rgb(srgb(), rgb_make(1, 1, 0.5));
    rgb_albedo_spectrum bad = rgb_albedo_spectrum_from_rgb(srgb(), rgb_make(NAN, -1, 0.3));
    for (double l = 360.0; l <= 830.0; l += 10.0) {
        assert_near(rgb_albedo_spectrum_eval(hi, l), rgb_albedo_spectrum_eval(in, l), 0.0);
        double v = rgb_albedo_spectrum_eval(bad, l);
        assert_true(v >= 0.0 && v <= 1.0);
    }
    uint64_t seed = 7;
    for (int n = 0; n < 2000; ++n) {
        rgb c = rgb_make(rng_next(&seed), rng_next(&seed), rng_next(&seed));
        sigmoid_poly p = sigmoid_poly_from_rgb(srgb(), c);
        double m = sigmoid_poly_max(p), seen = 0.0;
        for (double l = 360.0; l <= 830.0; l += 0.5)
            seen = hz_fmax(seen, sigmoid_poly_eval(p, l));
        assert_true(seen <= m + 1e-12 && seen >= m - 1e-4);
    }
}

static double spectrum_distance(sigmoid_poly a, sigmoid_poly b)
{
    double d = 0.0;
    for (double l = 360.0; l <= 830.0; l += 2.0)
        d = hz_fmax(d, fabs(sigmoid_poly_eval(a, l) - sigmoid_poly_eval(b, l)));
    return d;
}

/* The spectra of z (x, 0.5, y) - h and + h (largest component z), when
 * `along_x` of (z, z (x -/+ h), 0.3 z). */
static double change_across(double z, double x, double y, double h, bool along_x)
{
    rgb a = along_x ? rgb_make(z, z * (x - h), 0.3 * z) : rgb_scale(rgb_make(1, 0.5, y), z - h);
    rgb b = along_x ? rgb_make(z, z * (x + h), 0.3 * z) : rgb_scale(rgb_make(1, 0.5, y), z + h);
    return spectrum_distance(sigmoid_poly_from_rgb(srgb(), a),
                             sigmoid_poly_from_rgb(srgb(), b));
}

/* The lookup is continuous across the nodes of the largest component and of
 * the others: shrinking the step across a node by 100 shrinks the change of
 * the spectrum by about as much (a jump would stay), and it is small; and
 * where the largest component changes tables (r = g > b read as red's or as
 * green's). */
static void test_lookup_continuity(void **state)
{
    (void)state;
    const rgb2spec_solution *t = table(COLOR_SPACE_SRGB)->solution;
    uint64_t seed = 11;
    double worst = 0.0, worst_ratio = 0.0;
    for (int n = 0; n < 3000; ++n) {
        int k = 1 + (int)(rng_next(&seed) * (t->res - 2));
        int i = 1 + (int)(rng_next(&seed) * (t->res - 2));
        double y = rng_next(&seed), zz = 0.02 + 0.95 * rng_next(&seed);
        for (int axis = 0; axis < 2; ++axis) {
            double z = axis ? zz : t->z_nodes[k], x = t->xy_nodes[i];
            double big = change_across(z, x, y, 1e-6 * z, axis);
            double small = change_across(z, x, y, 1e-8 * z, axis);
            if (big > 1e-9) /* above rounding */
                worst_ratio = hz_fmax(worst_ratio, small / big);
            if (z > 0.01)
                worst = hz_fmax(worst, big);
        }
    }
    print_message("across nodes: largest change %.3g (step 1e-6 z, z > 0.01); "
                  "largest ratio at 100x smaller steps %.3g\n", worst, worst_ratio);
    assert_true(worst < 1e-3);
    assert_true(worst_ratio < 0.02);
    double across = 0.0;
    for (int n = 0; n < 500; ++n) {
        double a = 0.05 + 0.9 * rng_next(&seed), b = a * rng_next(&seed);
        rgb c = rgb_make(a * (1 + 1e-9), a, b), d = rgb_make(a, a * (1 + 1e-9), b);
        across = hz_fmax(across, spectrum_distance(sigmoid_poly_from_rgb(srgb(), c),
                                                   sigmoid_poly_from_rgb(srgb(), d)));
    }
    /* The two tables were solved apart: they agree to the solver's precision
     * at their shared nodes and to the interpolation error between them. */
    print_message("between tables: largest change %.3g\n", across);
    assert_true(across < 5e-3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_srgb),
        cmocka_unit_test(test_round_trip_srgb_every_cell),
        cmocka_unit_test(test_round_trip_other_spaces),
        cmocka_unit_test(test_illuminants),
        cmocka_unit_test(test_unbounded_and_emitters),
        cmocka_unit_test(test_greys_clamping_and_max),
        cmocka_unit_test(test_lookup_continuity),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
