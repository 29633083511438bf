/* Emitting media: closed forms of absorbing emission (the source term is
 * sigma_a Le, as pbrt-v4) under both integrators, and what does not glow. */
#include "media_test_util.h"
#include "scene/spectrum.h"

/* An orthographic camera looks head-on (+z) through a slab of medium
 * z in [0, d] (a box much wider than the view), with no light at all. */
static char *slab_scene(const char *integrator, const char *medium, double d)
{
    char *box = box_mesh(v3(-50, -50, 0), v3(50, 50, d));
    char *s = sfmt("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\"\n"
                   "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                   "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n"
                   "MakeNamedMedium \"m\" %s\n"
                   "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n%s"
                   "AttributeEnd\n",
                   integrator, medium, box);
    free(box);
    return s;
}

/* L = Le sigma_a / sigma_t (1 - e^{-sigma_t d}) per channel. */
static rgb slab_closed_form(rgb Le, rgb sigma_a, rgb sigma_t, double d)
{
    double v[3];
    for (int c = 0; c < 3; ++c)
        v[c] = ch(sigma_t, c) > 0.0
                   ? ch(Le, c) * ch(sigma_a, c) / ch(sigma_t, c) * -expm1(-ch(sigma_t, c) * d)
                   : 0.0;
    return rgb_make(v[0], v[1], v[2]);
}

/* Mean and standard error over the 4 x 4 image's pixels. */
static void image_mean(render_scene *rs, int spp, rgb *mean, rgb *se)
{
    image_mean_se(rs, 4, 4, spp, mean, se);
}

/* Homogeneous: exact under singlescatter (closed form, with or without
 * scattering: singlescatter does not scatter emitted light), within noise
 * under volpath without scattering. Lescale multiplies; "rgb Le" is that RGB. */
static void test_homogeneous_slab(void **state)
{
    (void)state;
    const double d = 1.5;
    const rgb Le = rgb_make(1.0 * 2, 2.0 * 2, 3.0 * 2); /* Lescale 2 */
    const rgb sa = rgb_make(0.5, 1.0, 2.0);
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0.5 1 2] \"rgb sigma_s\" [0 0 0] "
        "\"rgb Le\" [1 2 3] \"float Lescale\" 2",
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0.5 1 2] \"rgb sigma_s\" [0.3 0.2 0.1] "
        "\"rgb Le\" [1 2 3] \"float Lescale\" 2",
    };
    const rgb st[] = {sa, rgb_add(sa, rgb_make(0.3, 0.2, 0.1))};
    for (int k = 0; k < 2; ++k) {
        char *text = slab_scene("Integrator \"singlescatter\"", media[k], d);
        render_scene *rs = build(text);
        rgb want = slab_closed_form(Le, sa, st[k], d);
        pstat p = pixel_stats_raw(rs, 1, 2, 4);
        expect_rgb_close(p.mean, want, 1e-9, 1e-12, "singlescatter slab", k, 0);
        render_scene_destroy(rs);
        free(text);
    }
    char *text = slab_scene("Integrator \"volpath\"", media[0], d);
    render_scene *rs = build(text);
    rgb mean, se, want = slab_closed_form(Le, sa, sa, d);
    image_mean(rs, 4096, &mean, &se);
    expect_within_noise(mean, se, want, 0.0, "volpath slab");
    render_scene_destroy(rs);
    free(text);
}

/* The camera inside emitting fog that fills all space: L = Le sigma_a /
 * sigma_t; a medium that does not absorb does not glow; maxdepth 0 gathers
 * no medium emission (pbrt-v4: emission only while depth < maxdepth). */
static void test_unbounded_and_dark(void **state)
{
    (void)state;
    const char *fmt = "MediumInterface \"\" \"m\"\nLookAt 0 0 0  0 0 1  0 1 0\n"
                      "Camera \"perspective\"\n"
                      "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                      "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\n"
                      "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" %s\nWorldBegin\n";
    const char *glowing = "\"rgb sigma_a\" [0.2 0.4 0.8] \"rgb sigma_s\" [0 0 0] "
                          "\"rgb Le\" [3 2 1]";
    const char *dark = "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [1 1 1] \"rgb Le\" [3 2 1]";
    const char *integ[] = {"Integrator \"singlescatter\"", "Integrator \"volpath\""};
    for (int k = 0; k < 2; ++k) {
        char *text = sfmt(fmt, integ[k], glowing);
        render_scene *rs = build(text);
        /* singlescatter: exact; volpath: within its noise (one-sample MIS
         * over the hero channels: single samples range over 0 .. 9) */
        pstat p = pixel_stats_raw(rs, 1, 1, k == 0 ? 64 : 16384);
        if (k == 0)
            expect_rgb_close(p.mean, rgb_make(3, 2, 1), 1e-9, 1e-9, "unbounded", k, 0);
        else
            expect_within_noise(p.mean, p.se, rgb_make(3, 2, 1), 0.0, "unbounded");
        render_scene_destroy(rs);
        free(text);
        text = sfmt(fmt, integ[k], dark);
        rs = build(text);
        p = pixel_stats_raw(rs, 1, 1, 16);
        assert_true(p.mean.r == 0.0 && p.mean.g == 0.0 && p.mean.b == 0.0);
        render_scene_destroy(rs);
        free(text);
    }
    char *text = sfmt(fmt, "Integrator \"volpath\" \"integer maxdepth\" 0", glowing);
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 1, 16);
    assert_true(p.mean.r == 0.0 && p.mean.g == 0.0 && p.mean.b == 0.0);
    render_scene_destroy(rs);
    free(text);
}

/* "blackbody Le" has luminance 1 (as a light's); negative Le or Lescale and
 * Le on a grid medium (pbrt-v4 has none) are refused at their place. */
static void test_parameters(void **state)
{
    (void)state;
    const char *fmt = "MediumInterface \"\" \"m\"\nLookAt 0 0 0  0 0 1  0 1 0\n"
                      "Camera \"perspective\"\n"
                      "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                      "Integrator \"singlescatter\"\n"
                      "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" "
                      "\"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [0 0 0] %s\nWorldBegin\n";
    char *text = sfmt(fmt, "\"blackbody Le\" 2500");
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 1, 1);
    expect_close(rgb_luminance(p.mean), 1.0, 1e-3, 0.0, "blackbody Le luminance", 0, 0);
    assert_true(p.mean.r > p.mean.g && p.mean.g > p.mean.b); /* 2500 K is orange */
    render_scene_destroy(rs);
    free(text);
    char msg[4096];
    text = sfmt(fmt, "\"float Lescale\" -1 \"rgb Le\" [1 1 1]");
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:6:"));
    assert_non_null(strstr(msg, "\"Lescale\" must be finite and non-negative"));
    free(text);
    text = sfmt(fmt, "\"rgb Le\" [1 -1 1]");
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "\"Le\" times \"Lescale\" must be finite and non-negative"));
    free(text);
    text = sfmt("LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES
                "/fog_sphere.vdb\" \"rgb Le\" [1 1 1]\n");
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "unused parameter \"rgb Le\""));
    free(text);
}

/* ---- temperature grids (volumes/box_fire.vdb) ---- */

/* An orthographic camera looks along +z through the middle of box_fire's
 * density (1 on voxels [0,31]^3 of size 1/32, trilinear, so 1/64 of a ramp
 * beyond each face: the density integrates to exactly 1 along z). */
static char *fire_scene(const char *integrator, const char *file, const char *extra)
{
    return sfmt("LookAt 0.5 0.5 -1  0.5 0.5 0  0 1 0\n"
                "Camera \"orthographic\" \"float screenwindow\" [-0.2 0.2 -0.2 0.2]\n"
                "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n"
                "MakeNamedMedium \"fire\" \"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES
                "/%s\" \"rgb sigma_a\" [0.5 1 2] \"rgb sigma_s\" [0 0 0] %s\n"
                "AttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\n"
                "Shape \"sphere\" \"float radius\" 0.2\nTranslate 0.5 0.5 0.5\n"
                "Shape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n",
                integrator, file, extra);
}

/* With a constant temperature the source is constant: L = Le sigma_a /
 * sigma_t (1 - e^{-sigma_t D}) whatever the density profile, D = 1. */
static rgb fire_closed_form(double kelvin, double Le_scale)
{
    rgb Le = rgb_scale(spectrum_blackbody_peak_to_rgb(kelvin), Le_scale);
    rgb sa = rgb_make(0.5, 1, 2);
    return slab_closed_form(Le, sa, sa, 1.0);
}

/* temperature_coarse (its own transform) is 2500 K wherever the density is
 * not 0: the closed form, through .vdb and .nvdb, with pbrt-v4's offset,
 * scale and Lescale; at or below 100 K nothing glows. */
static void test_temperature_closed_form(void **state)
{
    (void)state;
    const char *march = "Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" "
                        "\"float stepsize\" 0.125";
    struct {
        const char *file, *extra;
        double kelvin, Le_scale;
    } cases[] = {
        {"box_fire.vdb", "\"string temperaturename\" \"temperature_coarse\"", 2500, 1},
        {"box_fire.nvdb", "\"string temperaturename\" \"temperature_coarse\"", 2500, 1},
        {"box_fire.vdb",
         "\"string temperaturename\" \"temperature_coarse\" \"float temperatureoffset\" -500 "
         "\"float temperaturescale\" 0.5 \"float Lescale\" 3",
         1500, 3},
        {"box_fire.vdb",
         "\"string temperaturename\" \"temperature_coarse\" \"float temperaturecutoff\" 2450",
         0, 0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char *text = fire_scene(march, cases[k].file, cases[k].extra);
        render_scene *rs = build(text);
        rgb want = cases[k].kelvin > 0 ? fire_closed_form(cases[k].kelvin, cases[k].Le_scale)
                                       : rgb_grey(0.0);
        pstat p = pixel_stats_raw(rs, 1, 2, 1);
        if (verbose())
            print_message("case %zu: %.6f %.6f %.6f want %.6f %.6f %.6f\n", k, p.mean.r,
                          p.mean.g, p.mean.b, want.r, want.g, want.b);
        expect_rgb_close(p.mean, want, 1e-3, 1e-12, "temperature closed form", (int)k, 0);
        render_scene_destroy(rs);
        free(text);
    }
    /* volpath, and singlescatter with ratio tracking: unbiased, within noise. */
    const char *integ[] = {"Integrator \"volpath\"",
                           "Integrator \"singlescatter\" \"string transmittance\" \"ratio\""};
    for (int k = 0; k < 2; ++k) {
        char *text = fire_scene(integ[k], "box_fire.vdb",
                                "\"string temperaturename\" \"temperature_coarse\"");
        render_scene *rs = build(text);
        rgb mean, se, want = fire_closed_form(2500, 1);
        image_mean(rs, 1024, &mean, &se);
        expect_within_noise(mean, se, want, 0.0, integ[k]);
        render_scene_destroy(rs);
        free(text);
    }
}

/* The aligned "temperature" grid ramps with the density at the faces (and
 * falls below 100 K on the last 4% of the ramp): against a fine numerical
 * integral of the same trilinear fields with the exact spectral blackbody. */
static void test_temperature_ramp(void **state)
{
    (void)state;
    const double sa[3] = {0.5, 1, 2};
    double want[3] = {0, 0, 0}, tau = 0.0;
    const int n = 20000; /* over index z in [-1, 33] */
    double dz = 34.0 / n;
    for (int i = 0; i < n; ++i) {
        double z = -1.0 + (i + 0.5) * dz;
        double ramp = z < 0 ? 1 + z : z > 31 ? fmax(0.0, 32 - z) : 1.0;
        if (ramp <= 0.0)
            continue;
        double ds = dz / 32.0, kelvin = 2500.0 * ramp;
        rgb Le = kelvin > 100.0 ? spectrum_blackbody_peak_to_rgb(kelvin) : rgb_grey(0.0);
        for (int c = 0; c < 3; ++c)
            want[c] += exp(-sa[c] * tau) * sa[c] * ramp * ch(Le, c) * ds;
        tau += ramp * ds;
    }
    assert_true(fabs(tau - 1.0) < 1e-6);
    char *text = fire_scene("Integrator \"singlescatter\" \"string transmittance\" "
                            "\"raymarch\" \"float stepsize\" 0.0625",
                            "box_fire.vdb", "");
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 2, 1, 1);
    expect_rgb_close(p.mean, rgb_make(want[0], want[1], want[2]), 2e-3, 1e-12, "temperature ramp",
                     0, 0);
    render_scene_destroy(rs);
    free(text);
}

/* pbrt-v4's temperature blackbody reaches its film without the division by
 * the CIE Y integral that a light's spectrum gets: at 2500 K, ~20x a
 * "blackbody Le" of luminance 1 (the integral of ybar is 106.9 nm). */
static void test_temperature_brightness(void **state)
{
    (void)state;
    rgb peak = spectrum_blackbody_peak_to_rgb(2500), unit = spectrum_blackbody_to_rgb(2500);
    double ratio = rgb_luminance(peak) / rgb_luminance(unit);
    if (verbose())
        print_message("2500 K: peak-normalised luminance %.4f (x %.2f)\n", rgb_luminance(peak),
                      ratio);
    /* Same chromaticity, a brightness factor: the peak-normalised spectrum's
     * Y integral in nm. */
    expect_close(peak.g / peak.r, unit.g / unit.r, 1e-9, 0.0, "chromaticity", 0, 0);
    assert_true(ratio > 15.0 && ratio < 25.0);
}

/* ---- uniformgrid (pbrt-v4's dense grid) ---- */

/* Orthographic rays along +z through a 4 x 4 x nz uniformgrid of constant
 * density over the box [0, 1]^2 x [0, 1], seen in the middle (x, y in 0.4 ..
 * 0.6: interior cells). pbrt-v4's samples sit at cell centres and fall to 0
 * one cell beyond, and the box clips: along z the density is 1 except the
 * outer half cells, where it falls linearly to 1/2 at the faces. */
static char *ugrid_scene(const char *integrator, int nz, const char *density,
                         const char *extra)
{
    return sfmt("LookAt 0.5 0.5 -1  0.5 0.5 0  0 1 0\n"
                "Camera \"orthographic\" \"float screenwindow\" [-0.1 0.1 -0.1 0.1]\n"
                "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n"
                "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                "MakeNamedMedium \"u\" \"string type\" \"uniformgrid\" \"integer nx\" 4 "
                "\"integer ny\" 4 \"integer nz\" %d \"float density\" [%s] %s\n"
                "AttributeBegin\nMediumInterface \"u\" \"\"\nMaterial \"interface\"\n"
                "Translate 0.5 0.5 0.5\nShape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n",
                integrator, nz, density, extra);
}

static char *repeat_value(const char *v, int n)
{
    char *s = calloc((size_t)n * (strlen(v) + 1) + 1, 1);
    assert_non_null(s);
    for (int i = 0; i < n; ++i) {
        strcat(s, v);
        strcat(s, " ");
    }
    return s;
}

/* Transmittance exp(-sigma_t h (nz - 1/4)) (the two half cells at the faces
 * hold 3/4 of a cell each); and emission with a constant Lescale grid, whose
 * source sigma_a d Le ls has d = ls on the ramps: against the 1D integral. */
static void test_uniformgrid_closed_forms(void **state)
{
    (void)state;
    const int nz = 5;
    const double h = 1.0 / nz, st = 2.0;
    char *ones = repeat_value("1", 16 * nz);
    char *text = ugrid_scene("Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" "
                             "\"float stepsize\" 0.05",
                             nz, ones, "\"rgb sigma_a\" [2 2 2] \"rgb sigma_s\" [0 0 0]");
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 2, 1);
    double want = exp(-st * h * (nz - 0.25));
    expect_rgb_close(p.mean, rgb_grey(want), 1e-4, 1e-12, "uniformgrid transmittance", 0, 0);
    render_scene_destroy(rs);
    free(text);

    char extra[4096];
    snprintf(extra, sizeof extra,
             "\"rgb sigma_a\" [2 2 2] \"rgb sigma_s\" [0 0 0] \"rgb Le\" [1 2 3] "
             "\"float Lescale\" [%s]",
             ones);
    text = ugrid_scene("Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" "
                       "\"float stepsize\" 0.05",
                       nz, ones, extra);
    /* No sky for the emission: replace the light with nothing. */
    char *sky = strstr(text, "LightSource");
    memset(sky, ' ', strchr(sky, '\n') - sky);
    rs = build(text);
    p = pixel_stats_raw(rs, 1, 2, 1);
    /* Along z (world units): r(z) = 1 in [h/2, 1 - h/2], linear to 1/2 at 0 and 1. */
    double tau = 0.0, e = 0.0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
        double z = (i + 0.5) / n, dz = 1.0 / n;
        double r = z < h / 2 ? 0.5 + z / h : z > 1 - h / 2 ? 0.5 + (1 - z) / h : 1.0;
        e += exp(-st * tau) * st * r * r * dz;
        tau += r * dz;
    }
    expect_rgb_close(p.mean, rgb_make(e, 2 * e, 3 * e), 1e-4, 1e-12, "uniformgrid emission", 0, 0);
    render_scene_destroy(rs);
    free(text);
    free(ones);
}

/* What pbrt-v4 refuses or requires, at its place: counts, both Le and
 * temperature, no density. */
static void test_uniformgrid_errors(void **state)
{
    (void)state;
    char msg[4096];
    char *text = ugrid_scene("", 2, "1 2 3", "");
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "\"density\" has 3 values; expected nx*ny*nz = 4*4*2 = 32"));
    free(text);
    char *d = repeat_value("1", 32);
    char extra[4096];
    snprintf(extra, sizeof extra, "\"rgb Le\" [1 1 1] \"float temperature\" [%s]", d);
    text = ugrid_scene("", 2, d, extra);
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "give \"Le\" or \"temperature\", not both"));
    free(text);
    char *neg = repeat_value("-1", 32);
    text = ugrid_scene("", 2, neg, "");
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "values must be finite and >= 0"));
    assert_non_null(strstr(msg, "test.pbrt:8:1:"));
    free(text);
    free(neg);
    free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_homogeneous_slab),
        cmocka_unit_test(test_unbounded_and_dark),
        cmocka_unit_test(test_parameters),
        cmocka_unit_test(test_temperature_closed_form),
        cmocka_unit_test(test_temperature_ramp),
        cmocka_unit_test(test_temperature_brightness),
        cmocka_unit_test(test_uniformgrid_closed_forms),
        cmocka_unit_test(test_uniformgrid_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
