/* haze's own grids on nanovdb media, as simulation tools write them: a free
 * emission grid ("emissionname": radiance per unit length, whatever the
 * density, coloured by "Le" or by a temperature grid's blackbody) and a
 * colour grid ("colorname": the scattering albedo per channel). Closed forms
 * and numerical integrals of the same trilinear fields, under both
 * integrators. */
#include "media_test_util.h"
#include "scene/spectrum.h"

/* An orthographic camera looks along +z through the middle (x, y in 0.3 ..
 * 0.7, interior voxels of every grid below) of volumes/`file`, inside a
 * sphere that holds the medium; `light` may add a light. */
static char *grid_scene(const char *integrator, const char *file, const char *params,
                        const char *light)
{
    return sfmt("LookAt 0.5 0.5 -1  0.5 0.5 0  0 1 0\n"
                "Camera \"orthographic\" \"float screenwindow\" [-0.2 0.2 -0.2 0.2]\n"
                "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n%s\n"
                "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES
                "/%s\" %s\n"
                "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
                "Translate 0.5 0.5 0.5\nShape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n",
                integrator, light, file, params);
}

static const char *const march = "Integrator \"singlescatter\" \"string transmittance\" "
                                 "\"raymarch\" \"float stepsize\" 0.0625";

/* box_fire's "density": 1 on voxels [0,31] of size 1/32, trilinear. */
static double box_density(double z)
{
    double v = 32.0 * z;
    return v < 0.0 ? fmax(0.0, 1.0 + v) : v > 31.0 ? fmax(0.0, 32.0 - v) : 1.0;
}

/* box_fire's "temperature_coarse" / 2500: 1 on voxels [-2,17] of size 1/16. */
static double coarse(double z)
{
    double v = 16.0 * z;
    return v < -2.0 ? fmax(0.0, v + 3.0) : v > 17.0 ? fmax(0.0, 18.0 - v) : 1.0;
}

/* L = integral of tint coarse(z) e^{-sigma_a tau(z)} dz along the ray. */
static rgb emission_integral(rgb tint, rgb sigma_a)
{
    double L[3] = {0, 0, 0}, tau = 0.0;
    const int n = 400000;
    const double z0 = -0.25, dz = 1.5 / n;
    for (int i = 0; i < n; ++i) {
        double z = z0 + (i + 0.5) * dz, d = box_density(z);
        for (int c = 0; c < 3; ++c)
            L[c] += ch(tint, c) * coarse(z) * exp(-ch(sigma_a, c) * (tau + 0.5 * d * dz)) * dz;
        tau += d * dz;
    }
    return rgb_make(L[0], L[1], L[2]);
}

/* The 4 x 4 image of `text` at `spp`, within noise of `want`. */
static void expect_image_within_noise(const char *text, int spp, rgb want, const char *what)
{
    render_scene *rs = build(text);
    rgb mean, se;
    image_mean_se(rs, 4, 4, spp, &mean, &se);
    expect_within_noise(mean, se, want, 1e-9, what);
    render_scene_destroy(rs);
}

/* A grid that glows where there is no density at all (sigma 0): L is the
 * tint times the emission's integral, 20 voxels of 1/16 = 1.25, also in the
 * voxels beyond the density's support (the clipping and the majorant grid
 * must keep them). "rgb Le" is the tint as given; Lescale scales. */
static void test_emission_without_density(void **state)
{
    (void)state;
    const char *params = "\"string emissionname\" \"temperature_coarse\" \"rgb Le\" [1 2 3] "
                         "\"float Lescale\" 0.0004 \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0 0 0]";
    const rgb want = rgb_make(1.25, 2.5, 3.75);
    char *text = grid_scene(march, "box_fire.vdb", params, "");
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 2, 1);
    expect_rgb_close(p.mean, want, 1e-6, 1e-12, "emission without density", 0, 0);
    render_scene_destroy(rs);
    free(text);
    /* Jittered strata (ratio tracking's, jittered marching's) and volpath's
     * tentative collisions: unbiased, within noise. */
    const char *integ[] = {"Integrator \"singlescatter\" \"string transmittance\" \"ratio\"",
                           "Integrator \"singlescatter\"", "Integrator \"volpath\""};
    for (int k = 0; k < 3; ++k) {
        text = grid_scene(integ[k], "box_fire.vdb", params, "");
        expect_image_within_noise(text, 512, want, integ[k]);
        free(text);
    }
}

/* The emission seen through absorbing density (box_fire's box, sigma_a
 * 0.5, 1, 2): against the numerical integral of the same trilinear fields;
 * marching to 2e-3, volpath and ratio tracking within noise. */
static void test_emission_through_density(void **state)
{
    (void)state;
    const char *params = "\"string emissionname\" \"temperature_coarse\" \"float Lescale\" 0.0004 "
                         "\"rgb sigma_a\" [0.5 1 2] \"rgb sigma_s\" [0 0 0]";
    rgb want = emission_integral(rgb_grey(1.0), rgb_make(0.5, 1, 2));
    char *text = grid_scene(march, "box_fire.vdb", params, "");
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 2, 1, 1);
    expect_rgb_close(p.mean, want, 2e-3, 1e-12, "emission through density", 0, 0);
    render_scene_destroy(rs);
    free(text);
    const char *integ[] = {"Integrator \"volpath\"",
                           "Integrator \"singlescatter\" \"string transmittance\" \"ratio\""};
    for (int k = 0; k < 2; ++k) {
        text = grid_scene(integ[k], "box_fire.vdb", params, "");
        expect_image_within_noise(text, 1024, want, integ[k]);
        free(text);
    }
}

/* Coloured by a temperature grid: each point's blackbody colour at
 * luminance 1 (none at or below 100 K). Against the integral of coarse(z)
 * times pbrt-v4's blackbody of 2500 coarse(z) kelvin, normalised: the ramps
 * at the grid's faces are redder than 2500 K. */
static rgb coloured_integral(void)
{
    double L[3] = {0, 0, 0};
    const int n = 6000;
    const double z0 = -0.25, dz = 1.5 / n;
    for (int i = 0; i < n; ++i) {
        double f = coarse(z0 + (i + 0.5) * dz), kelvin = 2500.0 * f;
        if (kelvin <= 100.0)
            continue;
        rgb c = f == 1.0 ? spectrum_blackbody_to_rgb(2500) : spectrum_blackbody_to_rgb(kelvin);
        for (int k = 0; k < 3; ++k)
            L[k] += f * ch(c, k) / rgb_luminance(c) * dz;
    }
    return rgb_make(L[0], L[1], L[2]);
}

static void test_emission_coloured_by_temperature(void **state)
{
    (void)state;
    char *text = grid_scene(march, "box_fire.vdb",
                            "\"string emissionname\" \"temperature_coarse\" \"string "
                            "temperaturename\" \"temperature_coarse\" \"float Lescale\" 0.0004 "
                            "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0 0 0]",
                            "");
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 1, 1);
    rgb want = coloured_integral();
    expect_close(rgb_luminance(p.mean), 1.25, 2e-3, 0.0, "luminance", 0, 0);
    expect_rgb_close(p.mean, want, 3e-3, 1e-12, "coloured by temperature", 0, 0);
    render_scene_destroy(rs);
    free(text);
}

/* A colour grid scales the scattering albedo and nothing else: box_color's
 * colour is (0.2, 0.5, 1) wherever there is density, so single scattering
 * under a distant light is that times the uncoloured image, sample for
 * sample under marching (the colour draws no random numbers), in
 * expectation under volpath maxdepth 1. */
static void test_color_scales_albedo(void **state)
{
    (void)state;
    const char *light = "LightSource \"distant\" \"point3 from\" [0.3 1 -0.2] \"point3 to\" "
                        "[0 0 0] \"rgb L\" [3 3 3]";
    const char *plain = "\"rgb sigma_a\" [0.2 0.2 0.2] \"rgb sigma_s\" [0.8 0.8 0.8]";
    char coloured[256];
    snprintf(coloured, sizeof coloured, "%s \"string colorname\" \"color\"", plain);
    const rgb C = rgb_make(0.2, 0.5, 1.0);
    const char *integ[] = {march, "Integrator \"singlescatter\""};
    for (int k = 0; k < 2; ++k) {
        char *ta = grid_scene(integ[k], "box_color.vdb", plain, light);
        char *tb = grid_scene(integ[k], "box_color.vdb", coloured, light);
        render_scene *a = build(ta), *b = build(tb);
        for (int px = 0; px < 4; ++px) {
            pstat pa = pixel_stats_raw(a, px, 3 - px, 4), pb = pixel_stats_raw(b, px, 3 - px, 4);
            assert_true(pa.mean.g > 0.01);
            expect_rgb_close(pb.mean, rgb_mul(C, pa.mean), 1e-7, 1e-15, "colour x albedo", px, k);
        }
        render_scene_destroy(a);
        render_scene_destroy(b);
        free(ta);
        free(tb);
    }
    const char *vp = "Integrator \"volpath\" \"integer maxdepth\" 1";
    char *ta = grid_scene(vp, "box_color.vdb", plain, light);
    char *tb = grid_scene(vp, "box_color.vdb", coloured, light);
    render_scene *a = build(ta), *b = build(tb);
    rgb ma, sa, mb, sb;
    image_mean_se(a, 4, 4, 4096, &ma, &sa);
    image_mean_se(b, 4, 4, 4096, &mb, &sb);
    for (int c = 0; c < 3; ++c) {
        double want = ch(C, c) * ch(ma, c), se = hypot(ch(sb, c), ch(C, c) * ch(sa, c));
        if (verbose())
            print_message("volpath colour c%d: %.5f, want %.5f +- %.5f\n", c, ch(mb, c), want, se);
        assert_true(se < 0.02 * want);
        assert_true(fabs(ch(mb, c) - want) < 4.0 * se);
    }
    render_scene_destroy(a);
    render_scene_destroy(b);
    free(ta);
    free(tb);
}

/* Each mistake one line at its place. */
static void test_errors(void **state)
{
    (void)state;
    struct {
        const char *params, *want;
    } cases[] = {
        {"\"string emissionname\" \"fire\"", "emission grid: "},
        {"\"string emissionname\" \"\"", "\"emissionname\" is empty"},
        {"\"string colorname\" \"density\"", "colour grid: "},
        {"\"string colorname\" \"nope\"", "colour grid: "},
        {"\"string emissionname\" \"temperature\" \"string temperaturename\" \"temperature\" "
         "\"rgb Le\" [1 1 1]",
         "give \"Le\" (one colour) or \"temperaturename\""},
        {"\"string emissionname\" \"temperature\" \"float temperaturescale\" 2",
         "\"temperaturescale\" needs a temperature grid (\"string temperaturename\") to colour "
         "the emission"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char *text = grid_scene(march, "box_fire.vdb", cases[k].params, "");
        char msg[1024];
        build_scene_expect_error(text, msg, sizeof msg);
        if (!strstr(msg, cases[k].want) || !strstr(msg, "test.pbrt:") || strchr(msg, '\n'))
            fail_msg("case %zu: got \"%s\", want \"%s\"", k, msg, cases[k].want);
        free(text);
    }
    /* haze's grids belong to nanovdb media only. */
    char msg[1024];
    build_scene_expect_error("WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" "
                             "\"string colorname\" \"color\"\n",
                             msg, sizeof msg);
    assert_non_null(strstr(msg, "unused parameter \"string colorname\""));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_emission_without_density),
        cmocka_unit_test(test_emission_through_density),
        cmocka_unit_test(test_emission_coloured_by_temperature),
        cmocka_unit_test(test_color_scales_albedo),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
