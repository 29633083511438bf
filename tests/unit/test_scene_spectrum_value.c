/* Spectra as the scene gave them (scene/spectrum_value.h, params_spectrum):
 * each kind for each use, their RGB against the RGB getters, their values
 * against closed forms and pbrt-v4's tables, and the named spectra's tables
 * against the RGB reductions haze renders with. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "assert_util.h"
#include "scene/named_spectra.h"
#include "scene/scene_desc.h"
#include "scene/spectrum.h"
#include "scene/spectrum_value.h"

static const spectrum_use uses[3] = {SPECTRUM_USE_ALBEDO, SPECTRUM_USE_UNBOUNDED,
                                     SPECTRUM_USE_ILLUMINANT};

/* Parses one LightSource with the given parameters and hands back its list. */
static param_list *light_params(scene_desc *sd, const char *params)
{
    char src[1024];
    snprintf(src, sizeof src, "WorldBegin\nLightSource \"point\" %s\n", params);
    hz_error err;
    if (scene_parse_string(src, "s.pbrt", sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(sd->light_count, 1);
    return &sd->lights[0].entity.params;
}

/* What the RGB getter of that use returns. */
static rgb old_getter(param_list *pl, const char *name, spectrum_use use, rgb def)
{
    switch (use) {
    case SPECTRUM_USE_ALBEDO: return params_reflectance(pl, name, def);
    case SPECTRUM_USE_UNBOUNDED: return params_rgb(pl, name, def);
    case SPECTRUM_USE_ILLUMINANT: break;
    }
    return params_illuminant(pl, name, def);
}

static void assert_rgb_same(rgb a, rgb b)
{
    if (a.r != b.r || a.g != b.g || a.b != b.b)
        fail_msg("rgb (%.17g %.17g %.17g) != (%.17g %.17g %.17g)", a.r, a.g, a.b, b.r, b.g, b.b);
}

/* params_spectrum for every use: its rgb is the old getter's, bit for bit. */
static void check_rgb_fields(param_list *pl, const char *name, spectrum_value_kind kind)
{
    for (int u = 0; u < 3; ++u) {
        spectrum_value s = params_spectrum(pl, name, uses[u], rgb_grey(-1.0));
        assert_int_equal(s.kind, kind);
        assert_int_equal(s.use, uses[u]);
        assert_rgb_same(s.rgb, old_getter(pl, name, uses[u], rgb_grey(-1.0)));
        if (uses[u] != SPECTRUM_USE_ILLUMINANT)
            assert_true(s.scale == 1.0);
    }
}

/* pbrt-v4's luminance of scale * spectrum: its inner product with the CIE
 * y-bar at 1 nm over 360..830 nm, in units where a constant 1 is about 1. */
static double luminance(const spectrum_value *s)
{
    double y = 0.0;
    for (int l = 360; l <= 830; ++l)
        y += spectrum_cie_xyz(l).y * spectrum_value_eval(s, l);
    return y / SPECTRUM_CIE_Y_INTEGRAL;
}

static void test_rgb_and_absent(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = light_params(&sd, "\"rgb I\" [0.2 0.4 1.5] \"rgb g\" [0.5 0.5 0.5]");
    check_rgb_fields(pl, "I", SPECTRUM_VALUE_RGB);
    spectrum_value s = params_spectrum(pl, "I", SPECTRUM_USE_UNBOUNDED, rgb_grey(0));
    assert_true(s.rgb.r == 0.2 && s.rgb.g == 0.4 && s.rgb.b == 1.5);
    assert_false(spectrum_value_is_constant(&s));
    /* A grey is flat as a reflectance, not as an emitter (times the
     * colour space's illuminant). */
    s = params_spectrum(pl, "g", SPECTRUM_USE_ALBEDO, rgb_grey(0));
    assert_true(spectrum_value_is_constant(&s));
    s = params_spectrum(pl, "g", SPECTRUM_USE_ILLUMINANT, rgb_grey(0));
    assert_false(spectrum_value_is_constant(&s));
    s = params_spectrum(pl, "absent", SPECTRUM_USE_ILLUMINANT, rgb_make(1, 2, 3));
    assert_int_equal(s.kind, SPECTRUM_VALUE_RGB);
    assert_true(s.rgb.r == 1 && s.rgb.g == 2 && s.rgb.b == 3 && s.scale == 1.0);
    hz_error err;
    assert_int_equal(params_finish(pl, "LightSource", &err), HZ_OK);
    scene_desc_free(&sd);

    /* The same errors as params_rgb: the default, and the reason at
     * params_finish. */
    pl = light_params(&sd, "\"float I\" 3");
    s = params_spectrum(pl, "I", SPECTRUM_USE_ILLUMINANT, rgb_grey(7));
    assert_int_equal(s.kind, SPECTRUM_VALUE_RGB);
    assert_true(s.rgb.g == 7.0);
    assert_int_equal(params_finish(pl, "LightSource", &err), HZ_ERROR);
    assert_string_equal(err.message, "s.pbrt:2:21: parameter \"I\" must be rgb, not float");
    scene_desc_free(&sd);
}

/* Planck's law, independently of scene/spectrum.c: B(l1) / B(l2). */
static double planck_ratio(double l1_nm, double l2_nm, double kelvin)
{
    const double c2 = 1.4387770e-2; /* h c / k_B in m K (CODATA 2010, as pbrt-v4's constants) */
    double l1 = l1_nm * 1e-9, l2 = l2_nm * 1e-9;
    return pow(l2 / l1, 5) * expm1(c2 / (l2 * kelvin)) / expm1(c2 / (l1 * kelvin));
}

static void test_blackbody(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = light_params(&sd, "\"blackbody I\" 5000");
    check_rgb_fields(pl, "I", SPECTRUM_VALUE_BLACKBODY);
    double peak = 2.8977721e6 / 5000.0; /* Wien: 579.55 nm */
    for (int u = 0; u < 3; ++u) {
        spectrum_value s = params_spectrum(pl, "I", uses[u], rgb_grey(0));
        assert_true(s.kelvin == 5000.0);
        assert_false(spectrum_value_is_constant(&s));
        assert_near(spectrum_value_eval(&s, peak), s.scale, 1e-12 * s.scale);
        assert_true(spectrum_value_eval(&s, peak - 5) < s.scale);
        assert_true(spectrum_value_eval(&s, peak + 5) < s.scale);
        assert_near(spectrum_value_eval(&s, 450) / spectrum_value_eval(&s, 650),
                            planck_ratio(450, 650, 5000), 1e-6);
    }
    spectrum_value s = params_spectrum(pl, "I", SPECTRUM_USE_ILLUMINANT, rgb_grey(0));
    assert_near(s.scale, 1.0 / params_illuminant_luminance(pl, "I"), 1e-15);
    assert_near(luminance(&s), 1.0, 1e-12);
    /* Its rgb (luminance 1) is the luminance of the spectrum pbrt-v4 holds
     * (peak 1, scale 1) times 1 / that luminance: a 5000 K blackbody
     * peaking at 1 has luminance ~0.9 (Planck's curve is flat near its
     * peak, which lies in the visible here). */
    s.scale = 1.0;
    assert_near(luminance(&s), params_illuminant_luminance(pl, "I"), 1e-12);
    assert_true(luminance(&s) > 0.8 && luminance(&s) < 1.0);
    scene_desc_free(&sd);
}

static void test_inline_sampled(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = light_params(&sd, "\"spectrum I\" [400 0.2 500 0.8 600 0.4]");
    check_rgb_fields(pl, "I", SPECTRUM_VALUE_SAMPLED);
    spectrum_value s = params_spectrum(pl, "I", SPECTRUM_USE_ALBEDO, rgb_grey(0));
    assert_int_equal(s.n, 3);
    assert_true(s.lambda[0] == 400 && s.lambda[2] == 600 && s.value[1] == 0.8);
    assert_near(spectrum_value_eval(&s, 400), 0.2, 1e-15);
    assert_near(spectrum_value_eval(&s, 450), 0.5, 1e-15);
    assert_near(spectrum_value_eval(&s, 550), 0.6, 1e-15);
    assert_near(spectrum_value_eval(&s, 575), 0.5, 1e-15);
    assert_true(spectrum_value_eval(&s, 600) == 0.4);
    assert_true(spectrum_value_eval(&s, 399.99) == 0.0);
    assert_true(spectrum_value_eval(&s, 600.01) == 0.0);
    assert_false(spectrum_value_is_constant(&s));
    s = params_spectrum(pl, "I", SPECTRUM_USE_ILLUMINANT, rgb_grey(0));
    assert_near(s.scale, 1.0 / params_illuminant_luminance(pl, "I"), 1e-15);
    assert_near(spectrum_value_eval(&s, 450), 0.5 * s.scale, 1e-15 * s.scale);
    assert_near(luminance(&s), 1.0, 1e-12);
    scene_desc_free(&sd);

    /* params_spectrum alone marks the parameter used. */
    pl = light_params(&sd, "\"spectrum I\" [400 0.2 500 0.8 600 0.4]");
    params_spectrum(pl, "I", SPECTRUM_USE_ILLUMINANT, rgb_grey(0));
    hz_error err;
    assert_int_equal(params_finish(pl, "LightSource", &err), HZ_OK);
    scene_desc_free(&sd);
}

static void test_constant(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = light_params(&sd, "\"spectrum I\" [0.5]");
    check_rgb_fields(pl, "I", SPECTRUM_VALUE_SAMPLED);
    spectrum_value s = params_spectrum(pl, "I", SPECTRUM_USE_ALBEDO, rgb_grey(0));
    assert_true(s.rgb.r == 0.5 && s.rgb.g == 0.5 && s.rgb.b == 0.5);
    assert_true(spectrum_value_is_constant(&s));
    for (double l = 360; l <= 830; l += 0.5)
        assert_true(spectrum_value_eval(&s, l) == 0.5);
    s = params_spectrum(pl, "I", SPECTRUM_USE_ILLUMINANT, rgb_grey(0));
    assert_true(spectrum_value_is_constant(&s));
    assert_near(luminance(&s), 1.0, 1e-12);
    /* 1 / (0.5 times the y-bar's sum over 360..830 nm in units of
     * SPECTRUM_CIE_Y_INTEGRAL, which haze's 10 nm table reaches within
     * 1e-3). */
    assert_near(s.scale, 2.0, 2e-3);
    scene_desc_free(&sd);
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void test_spd_file(void **state)
{
    (void)state;
    char dir[512], path[700];
    mkdir(HAZE_TMP, 0755); /* ctest's fixture makes it; a bare run may not have it */
    snprintf(dir, sizeof dir, "%s/spectrum_value", HAZE_TMP);
    mkdir(dir, 0755);
    snprintf(path, sizeof path, "%s/red.spd", dir);
    write_file(path, "# a red filter\n380 0.05\n550 0.1 # green\n600 0.9\n780 0.95\n");
    snprintf(path, sizeof path, "%s/s.pbrt", dir);
    write_file(path, "WorldBegin\nMaterial \"diffuse\" \"spectrum reflectance\" \"red.spd\"\n"
                     "Shape \"sphere\"\n");
    scene_desc sd;
    hz_error err;
    if (scene_parse_file(path, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    param_list *pl = &sd.materials[sd.shapes[0].material].entity.params;
    spectrum_value s = params_spectrum(pl, "reflectance", SPECTRUM_USE_ALBEDO, rgb_grey(0));
    assert_int_equal(s.kind, SPECTRUM_VALUE_SAMPLED);
    assert_int_equal(s.n, 4);
    assert_true(s.lambda[1] == 550 && s.value[1] == 0.1 && s.lambda[3] == 780);
    assert_near(spectrum_value_eval(&s, 575), 0.5, 1e-15);
    assert_true(spectrum_value_eval(&s, 379) == 0.0 && spectrum_value_eval(&s, 781) == 0.0);
    assert_rgb_same(s.rgb, params_reflectance(pl, "reflectance", rgb_grey(0)));
    /* A reflectance within [0, 1]: the clamped rgb of params_reflectance. */
    assert_true(s.rgb.r <= 1.0 && s.rgb.g >= 0.0);
    assert_int_equal(params_finish(pl, "Material", &err), HZ_OK);
    scene_desc_free(&sd);
}

static void test_named_metal(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = light_params(&sd, "\"spectrum eta\" \"metal-Au-eta\" "
                                       "\"spectrum k\" \"metal-Au-k\"");
    check_rgb_fields(pl, "eta", SPECTRUM_VALUE_SAMPLED);
    check_rgb_fields(pl, "k", SPECTRUM_VALUE_SAMPLED);
    spectrum_value eta = params_spectrum(pl, "eta", SPECTRUM_USE_UNBOUNDED, rgb_grey(0));
    spectrum_value k = params_spectrum(pl, "k", SPECTRUM_USE_UNBOUNDED, rgb_grey(0));
    /* Gold at 551.04 nm (2.25 eV) in pbrt-v4's table: n 0.3455, k 2.730625. */
    assert_true(spectrum_value_eval(&eta, 551.040771) == 0.3455);
    assert_true(spectrum_value_eval(&k, 551.040771) == 2.730625);
    /* Between 539.061646 (0.402, 2.54) and 551.040771: linear. */
    double t = (545.0 - 539.061646) / (551.040771 - 539.061646);
    assert_near(spectrum_value_eval(&eta, 545.0), 0.402 + t * (0.3455 - 0.402), 1e-12);
    assert_near(spectrum_value_eval(&k, 545.0), 2.54 + t * (2.730625 - 2.54), 1e-12);
    assert_int_equal(eta.n, 56);
    assert_true(eta.lambda[0] < 360 && eta.lambda[eta.n - 1] > 830);
    scene_desc_free(&sd);
}

static void test_named_illuminant(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = light_params(&sd, "\"spectrum I\" \"stdillum-F4\"");
    check_rgb_fields(pl, "I", SPECTRUM_VALUE_SAMPLED);
    spectrum_value s = params_spectrum(pl, "I", SPECTRUM_USE_ILLUMINANT, rgb_grey(0));
    rgb named;
    assert_true(named_spectrum_rgb("stdillum-F4", &named));
    assert_rgb_same(s.rgb, named);
    assert_near(luminance(&s), 1.0, 1e-12);
    /* The table is at luminance 1 already (pbrt-v4 scales it so under its
     * 1 nm CIE table); haze's 10 nm table differs by well under 1%. */
    assert_near(s.scale, 1.0, 5e-3);
    /* F4 (warm white fluorescent) has a mercury line at 435.8 nm: the
     * table's 435 nm sample stands out of its neighbours. */
    assert_true(spectrum_value_eval(&s, 435) > 2 * spectrum_value_eval(&s, 425));
    /* Used as anything but a light it is pbrt-v4's spectrum, unscaled. */
    spectrum_value a = params_spectrum(pl, "I", SPECTRUM_USE_UNBOUNDED, rgb_grey(0));
    assert_true(a.scale == 1.0 && a.value == s.value);
    scene_desc_free(&sd);
}

/* Normal-incidence reflectance of a conductor. */
static double fresnel0(double eta, double k)
{
    return ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
}

/* The linear sRGB of a reflectance under D65 over that of D65 itself (so
 * 1 is white): how named_spectra.c reduced the metals. */
static rgb reflectance_under_d65(const spectrum_value *eta, const spectrum_value *k)
{
    const named_spectrum_samples *t = named_spectrum_find("stdillum-D65");
    spectrum_value d65 = {.kind = SPECTRUM_VALUE_SAMPLED, .scale = 1, .lambda = t->lambda,
                          .value = t->value, .n = t->n};
    vec3 lit = v3(0, 0, 0), white = v3(0, 0, 0);
    for (int l = 360; l <= 830; ++l) {
        vec3 cmf = v3_scale(spectrum_cie_xyz(l), spectrum_value_eval(&d65, l));
        double r = fresnel0(spectrum_value_eval(eta, l), spectrum_value_eval(k, l));
        lit = v3_add(lit, v3_scale(cmf, r));
        white = v3_add(white, cmf);
    }
    rgb a = spectrum_srgb_from_xyz(lit), w = spectrum_srgb_from_xyz(white);
    return rgb_make(a.r / w.r, a.g / w.g, a.b / w.b);
}

static spectrum_value named_value(const char *name)
{
    const named_spectrum_samples *t = named_spectrum_find(name);
    if (!t)
        fail_msg("no samples for %s", name);
    return (spectrum_value){.kind = SPECTRUM_VALUE_SAMPLED, .scale = 1, .lambda = t->lambda,
                            .value = t->value, .n = t->n};
}

/* Each named metal's spectra reproduce the RGB reduction that haze renders
 * with: the normal-incidence reflectance of the reduced eta and k is the
 * RGB of the spectral reflectance under D65 (named_spectra.h), clamped to
 * 0.99, and where k reduced to 0 (MgO's and TiO2's red and green) as near
 * as eta alone reaches. */
static void test_named_metals_reduce_to_rgb(void **state)
{
    (void)state;
    static const char *metals[] = {"Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"};
    for (size_t m = 0; m < sizeof metals / sizeof metals[0]; ++m) {
        char ename[32], kname[32];
        snprintf(ename, sizeof ename, "metal-%s-eta", metals[m]);
        snprintf(kname, sizeof kname, "metal-%s-k", metals[m]);
        rgb eta, k;
        assert_true(named_spectrum_rgb(ename, &eta) && named_spectrum_rgb(kname, &k));
        spectrum_value se = named_value(ename), sk = named_value(kname);
        rgb spectral = reflectance_under_d65(&se, &sk);
        double want[3] = {spectral.r, spectral.g, spectral.b};
        double e3[3] = {eta.r, eta.g, eta.b}, k3[3] = {k.r, k.g, k.b};
        for (int c = 0; c < 3; ++c) {
            double got = fresnel0(e3[c], k3[c]);
            double tol = k3[c] == 0.0 ? 7e-3 : 5e-4;
            if (want[c] > 0.99) /* gold's red: 1.022, clamped */
                assert_near(got, 0.99, 1e-4);
            else if (fabs(got - want[c]) > tol)
                fail_msg("metal-%s channel %d: reduced %.4f, spectral %.4f", metals[m], c, got,
                         want[c]);
        }
        if (strcmp(metals[m], "Au") == 0) /* named_spectra.c's comment */
            assert_true(fabs(want[0] - 1.022) < 1e-3 && fabs(want[1] - 0.783) < 1e-3 &&
                        fabs(want[2] - 0.343) < 1e-3);
    }
}

/* The glasses' RGB is their index at 550 nm; the illuminants' their
 * chromaticity at luminance 1. */
static void test_named_glasses_and_illuminants_reduce_to_rgb(void **state)
{
    (void)state;
    assert_int_equal(named_spectra_table_count, 36); /* as many as named_spectra.c knows */
    for (size_t i = 0; i < named_spectra_table_count; ++i) {
        const named_spectrum_samples *t = &named_spectra_table[i];
        rgb c;
        if (!named_spectrum_rgb(t->name, &c))
            fail_msg("%s: a table without an RGB reduction", t->name);
        assert_ptr_equal(named_spectrum_find(t->name), t);
        for (size_t j = 1; j < t->n; ++j)
            assert_true(t->lambda[j] > t->lambda[j - 1]);
        /* As pbrt-v4 extends them: every table covers 360..830 nm. */
        assert_true(t->lambda[0] <= 360 && t->lambda[t->n - 1] >= 830);
        spectrum_value s = {.kind = SPECTRUM_VALUE_SAMPLED, .scale = 1, .lambda = t->lambda,
                            .value = t->value, .n = t->n};
        if (strncmp(t->name, "glass-", 6) == 0) {
            assert_near(spectrum_value_eval(&s, 550), c.g, 2e-5);
        } else if (strncmp(t->name, "stdillum-", 9) == 0) {
            assert_near(luminance(&s), 1.0, 1e-4);
        }
    }
}

/* The CIE 1931 chromaticity of a spectrum. */
static void chromaticity(const spectrum_value *s, double *x, double *y)
{
    vec3 xyz = v3(0, 0, 0);
    for (int l = 360; l <= 830; ++l)
        xyz = v3_add(xyz, v3_scale(spectrum_cie_xyz(l), spectrum_value_eval(s, l)));
    *x = xyz.x / (xyz.x + xyz.y + xyz.z);
    *y = xyz.y / (xyz.x + xyz.y + xyz.z);
}

/* The illuminants' tables against the chromaticities the CIE publishes
 * for them (CIE 15, 2 degree observer), and against haze's RGB reductions
 * where those agree with the tables. */
static void test_named_illuminants(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        double x, y;
    } cie[] = {
        {"stdillum-A", 0.44757, 0.40745},  {"stdillum-D65", 0.31271, 0.32902},
        {"stdillum-F1", 0.3131, 0.3371},   {"stdillum-F2", 0.3721, 0.3751},
        {"stdillum-F3", 0.4091, 0.3941},   {"stdillum-F4", 0.4402, 0.4031},
        {"stdillum-F5", 0.3138, 0.3452},   {"stdillum-F6", 0.3779, 0.3882},
        {"stdillum-F7", 0.3129, 0.3292},   {"stdillum-F8", 0.3458, 0.3586},
        {"stdillum-F9", 0.3741, 0.3727},   {"stdillum-F10", 0.3458, 0.3588},
        {"stdillum-F11", 0.3805, 0.3769},  {"stdillum-F12", 0.4370, 0.4042},
    };
    for (size_t i = 0; i < sizeof cie / sizeof cie[0]; ++i) {
        spectrum_value s = named_value(cie[i].name);
        double x, y;
        chromaticity(&s, &x, &y);
        if (fabs(x - cie[i].x) > 6e-4 || fabs(y - cie[i].y) > 6e-4)
            fail_msg("%s: xy %.4f %.4f, the CIE's %.4f %.4f", cie[i].name, x, y, cie[i].x,
                     cie[i].y);
    }
    /* haze's RGB of every illuminant (A, D50 — pbrt-v4's "D5000" table, whose
     * chromaticity (0.3369, 0.3581) is not the CIE's D50 — D65 and the F
     * series) is the tables'. */
    static const char *agree[] = {"stdillum-A",   "stdillum-D50", "stdillum-D65", "stdillum-F1",
                                  "stdillum-F2",  "stdillum-F3",  "stdillum-F4",  "stdillum-F5",
                                  "stdillum-F6",  "stdillum-F7",  "stdillum-F8",  "stdillum-F9",
                                  "stdillum-F10", "stdillum-F11", "stdillum-F12"};
    for (size_t i = 0; i < sizeof agree / sizeof agree[0]; ++i) {
        const named_spectrum_samples *t = named_spectrum_find(agree[i]);
        rgb got = spectrum_sampled_to_illuminant(t->lambda, t->value, t->n), c;
        assert_true(named_spectrum_rgb(agree[i], &c));
        if (fabs(got.r - c.r) > 1e-3 || fabs(got.g - c.g) > 1e-3 || fabs(got.b - c.b) > 1e-3)
            fail_msg("%s: spectral (%.5f %.5f %.5f), reduced (%.5f %.5f %.5f)", agree[i], got.r,
                     got.g, got.b, c.r, c.g, c.b);
    }
}

/* Lists copied from the parser's (graphics state, entities) keep their own
 * samples. */
static void test_copy_keeps_samples(void **state)
{
    (void)state;
    scene_desc sd;
    param_list *pl = light_params(&sd, "\"spectrum I\" [400 1 700 3] \"spectrum eta\" "
                                       "\"glass-BK7\" \"blackbody L\" 3000");
    param_list copy;
    assert_true(params_copy(&copy, pl));
    scene_desc_free(&sd);
    spectrum_value s = params_spectrum(&copy, "I", SPECTRUM_USE_UNBOUNDED, rgb_grey(0));
    assert_int_equal(s.n, 2);
    assert_near(spectrum_value_eval(&s, 550), 2.0, 1e-15);
    s = params_spectrum(&copy, "eta", SPECTRUM_USE_UNBOUNDED, rgb_grey(0));
    assert_ptr_equal(s.value, named_spectrum_find("glass-BK7")->value);
    s = params_spectrum(&copy, "L", SPECTRUM_USE_ILLUMINANT, rgb_grey(0));
    assert_true(s.kind == SPECTRUM_VALUE_BLACKBODY && s.kelvin == 3000);
    params_free(&copy);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rgb_and_absent),
        cmocka_unit_test(test_blackbody),
        cmocka_unit_test(test_inline_sampled),
        cmocka_unit_test(test_constant),
        cmocka_unit_test(test_spd_file),
        cmocka_unit_test(test_named_metal),
        cmocka_unit_test(test_named_illuminant),
        cmocka_unit_test(test_named_metals_reduce_to_rgb),
        cmocka_unit_test(test_named_glasses_and_illuminants_reduce_to_rgb),
        cmocka_unit_test(test_named_illuminants),
        cmocka_unit_test(test_copy_keeps_samples),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
