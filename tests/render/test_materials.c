/* pbrt-v4's metals and glass under volpath, against closed forms: a smooth
 * conductor of "reflectance" r seen head-on under a uniform sky returns r; a
 * smooth glass slab (or a thin sheet) in front of an emitter transmits
 * (1 - R) / (1 + R), R the normal-incidence Fresnel reflectance; and how a
 * scene with them picks its integrator. */
#include "media_test_util.h"
#include "materials/microfacet.h"

/* An orthographic camera looks straight down (-y) at a plane of `material`
 * under a uniform sky of radiance 1. */
static char *mirror_scene(const char *material)
{
    return sfmt("LookAt 0 5 0  0 0 0  0 0 1\nCamera \"orthographic\"\n"
                "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                "Integrator \"volpath\" \"integer maxdepth\" 5\nWorldBegin\n"
                "LightSource \"infinite\" \"rgb L\" [1 1 1]\n%s\n"
                "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                "\"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10]\n",
                material);
}

static void test_conductor_head_on(void **state)
{
    (void)state;
    char *text = mirror_scene("Material \"conductor\" \"rgb reflectance\" [0.2 0.5 0.9]");
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 2, 4);
    expect_rgb_close(p.mean, rgb_make(0.2, 0.5, 0.9), 1e-9, 1e-12, "conductor reflectance", 0, 0);
    render_scene_destroy(rs);
    free(text);
    /* pbrt-v4's named metals (here gold) reduced to RGB: the normal-
     * incidence reflectance of the spectral data under D65 (red clamped to
     * 0.99). */
    text = mirror_scene("Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" "
                        "\"spectrum k\" \"metal-Au-k\"");
    rs = build(text);
    p = pixel_stats_raw(rs, 1, 1, 4);
    expect_rgb_close(p.mean, rgb_make(0.990, 0.783, 0.343), 2e-3, 0.0, "gold", 0, 0);
    render_scene_destroy(rs);
    free(text);
    /* pbrt-v4's default conductor is copper: its normal-incidence
     * reflectance under D65, reduced to RGB. */
    text = mirror_scene("Material \"conductor\"");
    rs = build(text);
    p = pixel_stats_raw(rs, 2, 1, 4);
    expect_rgb_close(p.mean, rgb_make(0.9556, 0.6376, 0.5381), 2e-4, 0.0, "copper", 0, 0);
    render_scene_destroy(rs);
    free(text);
}

/* A reflectance that is within [0, 1] but whose RGB is not, by rounding or
 * through a spectrum's reduction to RGB (a flat [400 1 700 1] gives G =
 * 1.0012), is clamped and renders; a value really above 1 is still refused. */
static void test_reflectance_bounds(void **state)
{
    (void)state;
    const char *ok[] = {
        "Material \"diffuse\" \"spectrum reflectance\" [400 1 700 1]",
        "Material \"conductor\" \"spectrum reflectance\" [400 1 700 1]",
        "ColorSpace \"rec2020\" Material \"diffuse\" \"rgb reflectance\" [1 1 1]",
        "ColorSpace \"dci-p3\" Material \"conductor\" \"rgb reflectance\" [1 1 1]",
    };
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; ++i) {
        char *text = mirror_scene(ok[i]);
        render_scene *rs = build(text);
        pstat p = pixel_stats_raw(rs, 1, 2, 4);
        for (int c = 0; c < 3; ++c)
            if (!(ch(p.mean, c) <= 1.0))
                fail_msg("%s: channel %d is %.17g", ok[i], c, ch(p.mean, c));
        render_scene_destroy(rs);
        free(text);
    }
    /* The white spectrum's conductor seen head-on reflects its RGB, G
     * clamped to 1 (then to pbrt-v4's 0.9999 for a conductor's k). */
    char *text = mirror_scene(ok[1]);
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 2, 4);
    expect_rgb_close(p.mean, rgb_make(0.99596872, 0.9999, 0.99434505), 1e-6, 1e-12,
                     "white spectrum", 0, 0);
    render_scene_destroy(rs);
    free(text);
    const char *refused[] = {
        "Material \"diffuse\" \"rgb reflectance\" [1.01 1 1]",
        "Material \"diffuse\" \"spectrum reflectance\" [400 1.01 700 1.01]",
        "Material \"conductor\" \"rgb reflectance\" [0.5 1.01 0.5]",
        "Material \"diffuse\" \"rgb reflectance\" [0.5 -0.001 0.5]",
    };
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; ++i) {
        text = mirror_scene(refused[i]);
        char msg[512];
        build_scene_expect_error(text, msg, sizeof msg);
        if (!strstr(msg, "reflectance must be within [0, 1]") || !strstr(msg, "test.pbrt:8:"))
            fail_msg("%s: %s", refused[i], msg);
        free(text);
    }
}

/* A coating of index 1 and no thickness is invisible: coateddiffuse is its
 * base (reflectance r under a uniform sky returns r), coatedconductor its
 * metal; a real coating (eta 1.5) on a white base loses a little. */
static void test_coated_closed_forms(void **state)
{
    (void)state;
    struct {
        const char *mat;
        rgb want;
    } cases[] = {
        {"Material \"coateddiffuse\" \"float eta\" 1 \"float thickness\" 0 "
         "\"rgb reflectance\" [0.6 0.3 0.1]",
         {0.6, 0.3, 0.1, 0.3}},
        {"Material \"coatedconductor\" \"float interface.eta\" 1 \"float thickness\" 0 "
         "\"rgb reflectance\" [0.2 0.5 0.9]",
         {0.2, 0.5, 0.9, 0.5}},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char *text = mirror_scene(cases[k].mat);
        render_scene *rs = build(text);
        rgb mean, se;
        image_mean_se(rs, 4, 4, 64, &mean, &se);
        expect_rgb_close(mean, cases[k].want, 1e-6, 1e-12, "invisible coating", (int)k, 0);
        render_scene_destroy(rs);
        free(text);
    }
    char *text = mirror_scene("Material \"coateddiffuse\" \"rgb reflectance\" [1 1 1]");
    render_scene *rs = build(text);
    rgb mean, se;
    image_mean_se(rs, 4, 4, 1024, &mean, &se);
    print_message("white coated diffuse: %.5f +- %.5f\n", mean.g, se.g);
    assert_true(mean.g < 1.0 && mean.g > 0.85);
    render_scene_destroy(rs);
    free(text);
}

/* Material "mix": the second material with probability "amount", chosen
 * per hit by a hash of the point and direction: over 200000 hits the share
 * is the amount within binomial noise, the same hit always chooses alike,
 * and amount 1 is all the second material. */
static void test_mix(void **state)
{
    (void)state;
    material a = {.kind = MATERIAL_DIFFUSE, .reflectance = rgb_grey(0.2)};
    material b = {.kind = MATERIAL_DIFFUSE, .reflectance = rgb_grey(0.8)};
    material m = {.kind = MATERIAL_MIX, .amount = 0.25, .mix = {&a, &b}};
    const int n = 200000;
    int second = 0;
    for (int i = 0; i < n; ++i) {
        vec3 p = v3(i * 0.001, 1.0 + (i % 7) * 0.3, -2.0), wo = v3_normalize(v3(1, 2, i % 5));
        const material *c = material_at(&m, p, wo, NULL);
        assert_true(c == material_at(&m, p, wo, NULL));
        second += c == &b;
    }
    double share = (double)second / n, sd = sqrt(0.25 * 0.75 / n);
    print_message("mix: %.5f of hits chose the second material (want 0.25 +- %.5f)\n", share,
                  sd);
    assert_true(fabs(share - 0.25) < 4.0 * sd);
    const char *defs = "MakeNamedMaterial \"dark\" \"string type\" \"diffuse\" "
                       "\"rgb reflectance\" [0.2 0.2 0.2]\n"
                       "MakeNamedMaterial \"light\" \"string type\" \"diffuse\" "
                       "\"rgb reflectance\" [0.8 0.8 0.8]\n";
    rgb mean, se;
    char *mat = sfmt("%sMaterial \"mix\" \"string materials\" [\"dark\" \"light\"] "
               "\"float amount\" 1",
               defs);
    char *text = mirror_scene(mat);
    render_scene *rs = build(text);
    image_mean_se(rs, 4, 4, 64, &mean, &se);
    expect_rgb_close(mean, rgb_grey(0.8), 1e-9, 1e-12, "mix amount 1", 0, 0);
    render_scene_destroy(rs);
    free(text);
    free(mat);
    char msg[1024];
    const char *bad[][2] = {
        {"WorldBegin\nMaterial \"mix\" \"string materials\" [\"a\" \"b\"]\n",
         "no material named \"a\" defined before it"},
        {"WorldBegin\nMaterial \"mix\" \"string materials\" \"a\"\n",
         "needs \"string materials\" naming two materials, got 1"},
        {"WorldBegin\nMakeNamedMaterial \"i\" \"string type\" \"interface\"\n"
         "MakeNamedMaterial \"d\" \"string type\" \"diffuse\"\n"
         "Material \"mix\" \"string materials\" [\"d\" \"i\"]\n",
         "\"i\" is an interface"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        build_scene_expect_error(bad[k][0], msg, sizeof msg);
        if (!strstr(msg, bad[k][1]) || !strstr(msg, "test.pbrt:"))
            fail_msg("case %zu: got \"%s\", want \"%s\"", k, msg, bad[k][1]);
    }
}

/* A diffuse-transmission sheet under a uniform sky lit from both sides
 * returns R + T (pbrt-v4's defaults: 0.25 each, times "scale"). */
static void test_diffuse_transmission(void **state)
{
    (void)state;
    char *text = mirror_scene("Material \"diffusetransmission\" "
                              "\"rgb reflectance\" [0.3 0.3 0.3] "
                              "\"rgb transmittance\" [0.5 0.2 0.1]");
    render_scene *rs = build(text);
    rgb mean, se;
    image_mean_se(rs, 4, 4, 1024, &mean, &se);
    /* The lobe is chosen by the largest channel: noise in the others. */
    expect_within_noise(mean, se, rgb_make(0.8, 0.5, 0.4), 1e-9, "diffuse transmission");
    render_scene_destroy(rs);
    free(text);
    text = mirror_scene("Material \"diffusetransmission\" \"float scale\" 2");
    rs = build(text);
    image_mean_se(rs, 4, 4, 64, &mean, &se);
    expect_rgb_close(mean, rgb_grey(1.0), 1e-9, 1e-12, "diffuse transmission x2", 0, 0);
    render_scene_destroy(rs);
    free(text);
}

/* A spectrum file (.spd, pbrt-v4's "wavelength value" pairs with '#'
 * comments) read relative to the scene: the same as its pairs inline; a
 * file of odd length is refused. */
static void test_spd_file(void **state)
{
    (void)state;
    const char *path = HAZE_TMP "/haze_flat.spd";
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("# a flat reflectance\n400 0.5\n550\t0.5 # mid\n700 0.5\n", f);
    fclose(f);
    char *mat = sfmt("Material \"diffuse\" \"spectrum reflectance\" \"%s\"", path);
    char *text = mirror_scene(mat);
    render_scene *rs = build(text);
    rgb mean, se;
    image_mean_se(rs, 4, 4, 16, &mean, &se);
    render_scene_destroy(rs);
    free(text);
    free(mat);
    /* Exactly as the same pairs inline (grey within the reduction's 1%). */
    text = mirror_scene("Material \"diffuse\" \"spectrum reflectance\" "
                        "[400 0.5 550 0.5 700 0.5]");
    rs = build(text);
    rgb inline_mean;
    image_mean_se(rs, 4, 4, 16, &inline_mean, &se);
    expect_rgb_close(mean, inline_mean, 1e-12, 0.0, "spd as inline", 0, 0);
    expect_rgb_close(mean, rgb_grey(0.5), 1e-2, 0.0, "spd reflectance", 0, 0);
    render_scene_destroy(rs);
    free(text);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs("400 0.5 700\n", f);
    fclose(f);
    mat = sfmt("WorldBegin\nMaterial \"diffuse\" \"spectrum reflectance\" \"%s\"\n", path);
    char msg[1024];
    build_scene_expect_error(mat, msg, sizeof msg);
    assert_non_null(strstr(msg, "needs (wavelength, value) pairs, got 3 values"));
    free(mat);
    remove(path);
}

/* singlescatter shades reflective materials with direct light: under a
 * distant light (a delta light: light samples only, no noise) it gives what
 * volpath maxdepth 1 gives for a rough conductor, exactly; a perfect mirror
 * reflects no light sample. (A coated material's f is itself a random walk
 * seeded by the directions, which the two integrators round differently:
 * only its presence is checked here.) */
static void test_singlescatter_direct(void **state)
{
    (void)state;
    const char *mats[] = {
        "Material \"conductor\" \"float roughness\" 0.3",
        "Material \"coateddiffuse\" \"rgb reflectance\" [0.6 0.3 0.1] \"float roughness\" 0.1",
        "Material \"conductor\" \"rgb reflectance\" [0.9 0.9 0.9]",
    };
    for (int k = 0; k < 3; ++k) {
        rgb L[2];
        const char *integ[2] = {"Integrator \"singlescatter\"",
                                "Integrator \"volpath\" \"integer maxdepth\" 1"};
        for (int i = 0; i < 2; ++i) {
            char *text = sfmt("LookAt 0 5 -3  0 0 0  0 1 0\nCamera \"orthographic\"\n"
                              "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                              "%s\nWorldBegin\n"
                              "LightSource \"distant\" \"point3 from\" [0 5 3] \"point3 to\" "
                              "[0 0 0] \"rgb L\" [2 2 2]\n%s\n"
                              "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                              "\"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10]\n",
                              integ[i], mats[k]);
            render_scene *rs = build(text);
            L[i] = pixel_stats_raw(rs, 1, 2, 8).mean;
            render_scene_destroy(rs);
            free(text);
        }
        print_message("singlescatter %.6f, volpath 1 %.6f\n", L[0].g, L[1].g);
        if (k != 1)
            expect_rgb_close(L[0], L[1], 1e-9, 1e-12, "singlescatter direct", k, 0);
        assert_true(k == 2 ? L[0].g == 0.0 : L[0].g > 0.01);
    }
    /* Through a surface that transmits, the sky is sampled on both sides:
     * a diffuse-transmission sheet under a uniform sky returns R + T. */
    char *text = sfmt("Integrator \"singlescatter\"\n%s",
                      "LookAt 0 5 0  0 0 0  0 0 1\nCamera \"orthographic\"\n"
                      "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                      "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                      "Material \"diffusetransmission\" \"rgb reflectance\" [0.3 0.3 0.3] "
                      "\"rgb transmittance\" [0.5 0.5 0.5]\n"
                      "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                      "\"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10]\n");
    render_scene *rs = build(text);
    rgb mean, se;
    image_mean_se(rs, 4, 4, 1024, &mean, &se);
    print_message("singlescatter diffuse transmission: %.5f +- %.5f, want 0.8\n", mean.g, se.g);
    assert_true(se.g < 0.01 && fabs(mean.g - 0.8) < 4.0 * se.g);
    render_scene_destroy(rs);
    free(text);
}

/* Option "forcediffuse": the smooth conductor becomes a diffuse surface of
 * its albedo r, which under a uniform sky of radiance 1 returns r. */
static void test_force_diffuse(void **state)
{
    (void)state;
    char *mat = mirror_scene("Material \"conductor\" \"rgb reflectance\" [0.2 0.5 0.9]");
    char *text = sfmt("Option \"bool forcediffuse\" true\n%s", mat);
    render_scene *rs = build(text);
    rgb mean, se;
    image_mean_se(rs, 4, 4, 1024, &mean, &se);
    expect_within_noise(mean, se, rgb_make(0.2, 0.5, 0.9), 1e-12, "forcediffuse");
    render_scene_destroy(rs);
    free(text);
    free(mat);
}

/* An orthographic camera looks along +z through a slab (or a sheet) of glass
 * at an emitting quad of radiance 1; nothing else lights the scene. */
static char *slab_scene(const char *glass)
{
    return sfmt("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\"\n"
                "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                "Integrator \"volpath\" \"integer maxdepth\" 100\nWorldBegin\n"
                "AttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
                "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
                "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                "\"point3 P\" [-20 -20 3  -20 20 3  20 20 3  20 -20 3]\nAttributeEnd\n%s\n",
                glass);
}

/* Head-on through a slab of Fresnel reflectance R per face and internal
 * transmittance t per crossing: (1 - R)^2 t / (1 - R^2 t^2) (t = 1: (1 - R) /
 * (1 + R)). */
static void expect_transmission_t(const char *glass, double eta, double t, const char *what)
{
    char *text = slab_scene(glass);
    render_scene *rs = build(text);
    rgb mean, se;
    image_mean_se(rs, 4, 4, 4096, &mean, &se);
    double R = fresnel_dielectric(1.0, eta);
    double want = (1.0 - R) * (1.0 - R) * t / (1.0 - R * R * t * t);
    print_message("%s: %.5f +- %.5f, want %.5f\n", what, mean.g, se.g, want);
    assert_true(se.g < 0.003);
    assert_true(fabs(mean.g - want) < 4.0 * se.g);
    assert_true(fabs(mean.r - mean.g) < 1e-12 && fabs(mean.b - mean.g) < 1e-12);
    render_scene_destroy(rs);
    free(text);
}

static void expect_transmission(const char *glass, double eta, const char *what)
{
    expect_transmission_t(glass, eta, 1.0, what);
}

static void test_glass_slab(void **state)
{
    (void)state;
    char *box = box_mesh(v3(-10, -10, 0), v3(10, 10, 1));
    char *glass = sfmt("Material \"dielectric\" \"float eta\" 1.5\n%s", box);
    expect_transmission(glass, 1.5, "glass slab");
    free(glass);
    glass = sfmt("Material \"dielectric\" \"float eta\" 2.4\n%s", box);
    expect_transmission(glass, 2.4, "diamond slab");
    free(glass);
    /* Glass holding an absorbing medium (a MediumInterface on the
     * dielectric): a refracting medium boundary, e^{-0.5} per crossing. */
    glass = sfmt("MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" "
                 "\"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [0 0 0]\n"
                 "AttributeBegin\nMediumInterface \"ink\" \"\"\n"
                 "Material \"dielectric\" \"float eta\" 1.5\n%sAttributeEnd",
                 box);
    expect_transmission_t(glass, 1.5, exp(-0.5), "glass of ink");
    free(glass);
    /* pbrt-v4's named glass at 550 nm (haze does not disperse). */
    glass = sfmt("Material \"dielectric\" \"spectrum eta\" \"glass-BK7\"\n%s", box);
    expect_transmission(glass, 1.51854, "BK7 slab");
    free(glass);
    free(box);
    /* A thin sheet sums its interreflections: the same (1 - R) / (1 + R). */
    expect_transmission("Material \"thindielectric\" \"float eta\" 1.5\n"
                        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                        "\"point3 P\" [-10 -10 1  -10 10 1  10 10 1  10 -10 1]",
                        1.5, "thin sheet");
}

/* Russian roulette weighs beta times pbrt-v4's etaScale: inside glass of
 * eta 1.5 beta is 1 / 2.25 of what it is outside, a loss the path gets back
 * when it leaves, so it is no reason to end the path (the roulette on beta
 * alone ended up to 56% of the paths inside the glass per bounce). Two glass
 * slabs, smooth, seen head-on, maxdepth 100. */
static void test_glass_roulette(void **state)
{
    (void)state;
    char *a = box_mesh(v3(-10, -10, 0), v3(10, 10, 1));
    char *b = box_mesh(v3(-10, -10, 1.5), v3(10, 10, 2.5));
    /* Under a uniform sky of 1 (white furnace): every sample of every path,
     * reflected or transmitted any number of times, is exactly 1: no path
     * is cut, none is weighted up. */
    char *text = sfmt("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\"\n"
                      "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                      "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                      "Integrator \"volpath\" \"integer maxdepth\" 100\nWorldBegin\n"
                      "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                      "Material \"dielectric\" \"float eta\" 1.5\n%s%s",
                      a, b);
    render_scene *rs = build(text);
    pstat p = pixel_stats_raw(rs, 1, 2, 4096);
    print_message("furnace: samples in [%.17g, %.17g]\n", p.min, p.max);
    assert_true(fabs(p.min - 1.0) < 1e-9 && fabs(p.max - 1.0) < 1e-9);
    render_scene_destroy(rs);
    free(text);
    /* In front of an emitter of 1, nothing else: the mean is the stack's
     * transmission (1 - R) / (1 + 3R) (four faces, their interreflections
     * summed), and each sample is 0 or 1 (a survivor of the roulette on
     * beta alone came back as 1 / (1 - q) > 1). */
    char *glass = sfmt("Material \"dielectric\" \"float eta\" 1.5\n%s%s", a, b);
    text = slab_scene(glass);
    rs = build(text);
    p = pixel_stats_raw(rs, 1, 2, 16384);
    double R = fresnel_dielectric(1.0, 1.5), want = (1.0 - R) / (1.0 + 3.0 * R);
    print_message("emitter: %.5f +- %.5f, want %.5f; samples in [%g, %.17g]\n", p.mean.g,
                  p.se.g, want, p.min, p.max);
    assert_true(p.max <= 1.0 + 1e-9);
    assert_true(p.se.g < 0.004 && fabs(p.mean.g - want) < 4.0 * p.se.g);
    render_scene_destroy(rs);
    free(text);
    free(glass);
    free(a);
    free(b);
}

/* A scene naming no Integrator with metal or glass renders pbrt-v4's
 * default (volpath, maxdepth 5) and says so.
 * Parameters are pbrt-v4's and checked. */
static void test_integrator_and_parameters(void **state)
{
    (void)state;
    char msg[1024];
    const char *world = "WorldBegin\nMaterial \"dielectric\"\nShape \"sphere\"\n";
    char *text = sfmt("%s", world);
    scene_desc sd;
    hz_error err = {0};
    assert_int_equal(scene_parse_string(text, "test.pbrt", &sd, &err), HZ_OK);
    FILE *warn = tmpfile();
    render_options def = {.seed = 0, .color = RENDER_COLOR_RGB};
    render_scene *rs = NULL;
    assert_int_equal(render_scene_create(&sd, &def, warn, &rs, &err), HZ_OK);
    rewind(warn);
    size_t got = fread(msg, 1, sizeof msg - 1, warn);
    msg[got] = '\0';
    assert_non_null(strstr(msg, "has a \"dielectric\" material, which only \"volpath\" renders"));
    fclose(warn);
    render_scene_destroy(rs);
    scene_desc_free(&sd);
    free(text);

    struct {
        const char *scene, *want;
    } cases[] = {
        {"WorldBegin\nMaterial \"conductor\" \"rgb reflectance\" [0.5 0.5 0.5] "
         "\"rgb eta\" [1 1 1]\n",
         "give \"reflectance\" or \"eta\" and \"k\", not both"},
        {"WorldBegin\nMaterial \"conductor\" \"float roughness\" -0.1\n", "\"roughness\" must be"},
        {"WorldBegin\nMaterial \"dielectric\" \"spectrum eta\" [400 -1.5 700 -1.4]\n",
         "\"eta\" must be finite and > 0, got -1.45"},
        {"WorldBegin\nMaterial \"conductor\" \"spectrum eta\" \"metal-Xx-eta\"\n",
         "no named spectrum \"metal-Xx-eta\""},
        {"WorldBegin\nMaterial \"dielectric\" \"float eta\" 0\n", "\"eta\" must be finite and > 0"},
        {"WorldBegin\nMaterial \"thindielectric\" \"float roughness\" 0.1\n",
         "unused parameter \"float roughness\""},
        {"WorldBegin\nMaterial \"conductor\" \"texture roughness\" \"t\"\n",
         "\"texture roughness\": no float texture named \"t\" defined before it"},
        {"WorldBegin\nMaterial \"coateddiffuse\" \"integer nsamples\" 0\n",
         "\"nsamples\" must be within 1 .. 10000"},
        {"WorldBegin\nMaterial \"coatedconductor\" \"rgb reflectance\" [0.5 0.5 0.5] "
         "\"rgb conductor.k\" [1 1 1]\n",
         "give \"reflectance\" or \"conductor.eta\" and \"conductor.k\", not both"},
        {"WorldBegin\nMaterial \"coateddiffuse\" \"float thickness\" -1\n",
         "\"thickness\" must be finite and >= 0"},
        {"WorldBegin\nMaterial \"coatedconductor\" \"float roughness\" 0.1\n",
         "unused parameter \"float roughness\""},
        {"WorldBegin\nMaterial \"subsurface\"\n", "\"subsurface\" is not supported"},
        {"WorldBegin\nMaterial \"diffuse\" \"texture displacement\" \"nope\"\n",
         "test.pbrt:2:20: \"texture displacement\": no float texture named \"nope\""},
        {"WorldBegin\nMaterial \"interface\" \"float displacement\" 0.1\n",
         "unused parameter \"float displacement\""},
        {"WorldBegin\nMaterial \"coateddiffuse\" \"string normalmap\" \"n.png\"\n",
         "test.pbrt:2:26: cannot read PNG \"n.png\""},
        {"WorldBegin\nMaterial \"diffuse\" \"string normalmap\" \"n.tga\"\n",
         "normal map \"n.tga\": haze reads .png and .exr"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        build_scene_expect_error(cases[k].scene, msg, sizeof msg);
        if (!strstr(msg, cases[k].want))
            fail_msg("case %zu: got \"%s\", want \"%s\"", k, msg, cases[k].want);
    }
}

/* "texture displacement" (pbrt-v4's BumpMap) with the closed form of a
 * ramp: displacement a u on the plane [-1, 1]^2 (dp/du of length 2) tilts
 * the normal by atan(a / 2), so a diffuse plane under a distant light from
 * straight above sends rho / pi L cos(atan(a / 2)) to the camera; a constant
 * displacement (gradient 0) changes nothing. */
static void test_bump_ramp(void **state)
{
    (void)state;
    static const char *fmt =
        "LookAt 0 5 0  0 0 0  0 0 1\n"
        "Camera \"orthographic\"\n"
        "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
        "Integrator \"volpath\" \"integer maxdepth\" 1\n"
        "WorldBegin\n"
        "LightSource \"distant\" \"point3 from\" [0 1 0] \"point3 to\" [0 0 0] "
        "\"rgb L\" [3.14159265358979 3.14159265358979 3.14159265358979]\n"
        "Texture \"d\" \"float\" \"bilerp\" \"float v00\" 0 \"float v10\" %g "
        "\"float v01\" 0 \"float v11\" %g\n"
        "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5] %s\n"
        "Shape \"trianglemesh\" \"point3 P\" [-1 0 -1 1 0 -1 1 0 1 -1 0 1]\n"
        "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n";
    const double slopes[] = {0.0, 1.0, -3.0};
    for (size_t i = 0; i < sizeof slopes / sizeof slopes[0]; ++i) {
        char *text = sfmt(fmt, slopes[i], slopes[i], "\"texture displacement\" \"d\"");
        render_scene *rs = build(text);
        pixel_eval e = eval_pixel(rs, 3.5, 4.5, 4);
        render_scene_destroy(rs);
        free(text);
        double want = 0.5 * cos(atan(slopes[i] / 2.0));
        expect_close(e.L.g, want, 1e-6, 0.0, "bumped plane", 3.5, 4.5);
    }
    char *text = sfmt(fmt, 1.0, 1.0, "\"float displacement\" 0.25");
    render_scene *rs = build(text);
    pixel_eval e = eval_pixel(rs, 3.5, 4.5, 4);
    render_scene_destroy(rs);
    free(text);
    expect_close(e.L.g, 0.5, 1e-9, 0.0, "constant displacement", 3.5, 4.5);
}

/* A mix's "texture amount": where a float checkerboard is 0 the first
 * material shows, where it is 1 the second (pbrt-v4's MixMaterial), each
 * exactly: two diffuse materials under a sky of radiance 1 return their
 * reflectances. */
static void test_mix_texture_amount(void **state)
{
    (void)state;
    char *text = sfmt("LookAt 0 5 0  0 0 0  0 0 1\n"
                      "Camera \"orthographic\"\n"
                      "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                      "Integrator \"volpath\" \"integer maxdepth\" 1\n"
                      "WorldBegin\n"
                      "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                      "Texture \"amt\" \"float\" \"checkerboard\" \"float uscale\" 2 "
                      "\"float vscale\" 2 \"float tex1\" 0 \"float tex2\" 1\n"
                      "MakeNamedMaterial \"a\" \"string type\" \"diffuse\" "
                      "\"rgb reflectance\" [0.2 0.2 0.2]\n"
                      "MakeNamedMaterial \"b\" \"string type\" \"diffuse\" "
                      "\"rgb reflectance\" [0.8 0.8 0.8]\n"
                      "MakeNamedMaterial \"m\" \"string type\" \"mix\" "
                      "\"string materials\" [\"a\" \"b\"] \"texture amount\" \"amt\"\n"
                      "NamedMaterial \"m\"\n"
                      "Shape \"trianglemesh\" \"point3 P\" [-1 0 -1 1 0 -1 1 0 1 -1 0 1]\n"
                      "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n");
    render_scene *rs = build(text);
    free(text);
    int seen[2] = {0, 0};
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 64);
            assert_true(e.hit);
            /* (u, v) of the pixel's centre: x and z of the plane over [-1, 1]. */
            double u = (e.p_world.x + 1.0) / 2.0, v = (e.p_world.z + 1.0) / 2.0;
            int second = ((int)floor(2.0 * u) + (int)floor(2.0 * v)) & 1;
            seen[second]++;
            /* The amount is box-filtered over the camera ray's footprint (a
             * quarter of a check), as pbrt-v4's checkerboard: next to an
             * edge (the plane's rim too) it is fractional and the hash
             * decides. */
            double ax = fabs(e.p_world.x), az = fabs(e.p_world.z);
            if (ax < 0.3 || az < 0.3 || ax > 0.7 || az > 0.7)
                continue;
            expect_close(e.L.g, second ? 0.8 : 0.2, 0.03, 0.0, "mixed by texture", x, y);
        }
    assert_true(seen[0] > 0 && seen[1] > 0);
    render_scene_destroy(rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_conductor_head_on),
        cmocka_unit_test(test_glass_slab),
        cmocka_unit_test(test_force_diffuse),
        cmocka_unit_test(test_spd_file),
        cmocka_unit_test(test_singlescatter_direct),
        cmocka_unit_test(test_diffuse_transmission),
        cmocka_unit_test(test_coated_closed_forms),
        cmocka_unit_test(test_mix),
        cmocka_unit_test(test_integrator_and_parameters),
        cmocka_unit_test(test_bump_ramp),
        cmocka_unit_test(test_mix_texture_amount),
        cmocka_unit_test(test_reflectance_bounds),
        cmocka_unit_test(test_glass_roulette),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
