#define _POSIX_C_SOURCE 200809L
/* Spectral rendering (--color spectral, docs/spectral.md) against closed
 * forms: the wavelength density, a coloured reflectance under a white sky,
 * a grey scene equal to its RGB image, a conductor of constant eta and k, a
 * dielectric slab, and a chromatic absorbing medium's transmittance per
 * wavelength integrated against the observer. */
#include "render_test_util.h"

#include "color/rgb2spec_module.h"
#include "color/rgb_spectrum.h"
#include "color/spectral.h"
#include "color/wavelengths.h"
#include "scene/named_spectra.h"
#include "scene/spectrum.h"

/* The sRGB table of the module (loaded once; the same pointer after). */
static const rgb2spec_table *srgb_table(void)
{
    const rgb2spec_table *t = NULL;
    hz_error err = {0};
    if (rgb2spec_tables_load(&t, &err) != HZ_OK)
        fail_msg("%s", err.message);
    return &t[COLOR_SPACE_SRGB];
}

static const render_options spectral_opt = {.seed = 0, .color = RENDER_COLOR_SPECTRAL};

/* The density integrates to 1, and sampling inverts its CDF. */
static void test_wavelength_density(void **state)
{
    (void)state;
    double sum = 0.0, h = 0.01;
    for (double l = WAVELENGTH_MIN + h / 2; l < WAVELENGTH_MAX; l += h)
        sum += wavelength_visible_pdf(l) * h;
    expect_close(sum, 1.0, 1e-9, 0.0, "integral of the pdf", 0, 0);
    assert_true(wavelength_visible_pdf(359.0) == 0.0 && wavelength_visible_pdf(831.0) == 0.0);
    for (double u = 0.05; u < 1.0; u += 0.1) {
        double lambda = wavelength_visible_sample(u), cdf = 0.0;
        for (double l = WAVELENGTH_MIN + h / 2; l < lambda; l += h)
            cdf += wavelength_visible_pdf(l) * h;
        expect_close(cdf, u, 0.0, 1e-4, "CDF at the sample", u, 0);
    }
    /* Four lanes, as pbrt-v4's: companions a quarter of the sample apart,
     * at the same density. */
    assert_int_equal(WAVELENGTH_LANES, 4);
    wavelengths w = wavelengths_sample_visible(0.9);
    expect_close(w.lambda[0], wavelength_visible_sample(0.9), 1e-15, 0.0, "hero", 0, 0);
    for (int i = 1; i < WAVELENGTH_LANES; ++i) {
        double ui = 0.9 + i / 4.0;
        expect_close(w.lambda[i], wavelength_visible_sample(ui - floor(ui)), 1e-12, 0.0,
                     "companion", i, 0);
        expect_close(w.pdf[i], wavelength_visible_pdf(w.lambda[i]), 1e-9, 0.0, "its density",
                     i, 0);
    }
    /* A constant spectrum 1, its lanes averaged over stratified samples,
     * is equal-energy white: X = Y = Z = 1 within the CIE tables' sums. */
    enum { N = 30000 };
    vec3 xyz = v3(0, 0, 0);
    for (int i = 0; i < N; ++i) {
        wavelengths wi = wavelengths_sample_visible((i + 0.5) / N);
        xyz = v3_add(xyz, wavelengths_xyz(&wi, rgb_grey(1.0)));
    }
    xyz = v3_scale(xyz, 1.0 / N);
    expect_close(xyz.y, 1.0, 1e-4, 0.0, "Y of a constant 1", 0, 0);
    expect_close(xyz.x, 1.0, 2e-3, 0.0, "X of a constant 1", 0, 0);
    expect_close(xyz.z, 1.0, 2e-3, 0.0, "Z of a constant 1", 0, 0);
}

/* An orthographic camera looking down -z at the plane z = 0 under a white
 * sky: the centre pixel's radiance, `spp` samples (zsobol). */
/* The scene of plane_radiance: 8x8 pixels of `spp` samples. */
static char *plane_scene(const char *material, int spp)
{
    char head[512];
    snprintf(head, sizeof head,
             "LookAt 0 0 5  0 0 0  0 1 0\n"
             "Camera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"
             "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" %d\n"
             "Integrator \"volpath\" \"integer maxdepth\" 1\n"
             "WorldBegin\n"
             "LightSource \"infinite\" \"rgb L\" [1 1 1]\n",
             spp);
    return cat(head, material,
               "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
               "  \"point3 P\" [-2 -2 0 2 -2 0 2 2 0 -2 2 0]\n");
}

static rgb plane_radiance(const char *material, const render_options *opt, int spp)
{
    char *text = plane_scene(material, 16);
    render_options o = *opt;
    render_scene *rs = build_scene_or_fail(text, &o);
    free(text);
    assert_true(render_scene_spectral(rs) == (opt->color == RENDER_COLOR_SPECTRAL));
    rgb L = eval_pixel(rs, 4.5, 4.5, spp).L;
    render_scene_destroy(rs);
    return L;
}

/* A diffuse reflectance under a white (D65, luminance 1) sky reflects its
 * own RGB: the albedo spectrum of the RGB integrates back to it within the
 * tables' 1e-3. A Lambertian plane under a constant sky gets radiance
 * R * L exactly, so only the table and the wavelength noise remain. */
static void test_coloured_reflectance(void **state)
{
    (void)state;
    rgb L = plane_radiance("Material \"diffuse\" \"rgb reflectance\" [0.8 0.2 0.1]\n",
                           &spectral_opt, 1024);
    expect_rgb_close(L, rgb_make(0.8, 0.2, 0.1), 0.0, 3e-3, "coloured reflectance", 4.5, 4.5);
}

/* A grey scene: every lane carries the same value, so spectral rendering
 * gives RGB rendering's radiance (the sky's D65 white through the film's
 * matrix is 1, 1, 1). */
static void test_grey_matches_rgb(void **state)
{
    (void)state;
    const char *mat = "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n";
    render_options rgb_opt = {.seed = 0, .color = RENDER_COLOR_RGB};
    rgb a = plane_radiance(mat, &rgb_opt, 64), b = plane_radiance(mat, &spectral_opt, 1024);
    expect_rgb_close(a, rgb_grey(0.5), 1e-12, 0.0, "RGB", 4.5, 4.5);
    expect_rgb_close(b, a, 0.0, 2e-3, "spectral against RGB", 4.5, 4.5);
}

/* A smooth conductor of constant eta and k seen straight on under a white
 * sky reflects the normal-incidence Fresnel reflectance
 * ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2) at every wavelength. */
static void test_conductor_constant(void **state)
{
    (void)state;
    double n = 0.2, k = 3.0, R = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
    rgb L = plane_radiance("Material \"conductor\" \"spectrum eta\" [0.2] \"spectrum k\" [3]\n"
                           "  \"float roughness\" 0\n",
                           &spectral_opt, 256);
    expect_rgb_close(L, rgb_grey(R), 0.0, 2e-3, "conductor", 4.5, 4.5);
}

enum { SLAB_RES = 32 };

static double gold_head_on(double lambda, const void *ctx)
{
    (void)ctx;
    const named_spectrum_samples *e = named_spectrum_find("metal-Au-eta"),
                                 *k = named_spectrum_find("metal-Au-k");
    spectrum_value se = {.kind = SPECTRUM_VALUE_SAMPLED, .scale = 1.0, .lambda = e->lambda,
                         .value = e->value, .n = e->n};
    spectrum_value sk = {.kind = SPECTRUM_VALUE_SAMPLED, .scale = 1.0, .lambda = k->lambda,
                         .value = k->value, .n = k->n};
    double n = spectrum_value_eval(&se, lambda), kk = spectrum_value_eval(&sk, lambda);
    return ((n - 1) * (n - 1) + kk * kk) / ((n + 1) * (n + 1) + kk * kk);
}

typedef double (*spectrum_fn)(double lambda, const void *ctx);
static rgb rgb_of_illuminated(spectrum_fn s, const void *ctx);

/* Gold by pbrt-v4's named spectra, smooth, head on under a white sky: the
 * Fresnel reflectance of eta(lambda), k(lambda) per wavelength integrated
 * against the observer (RGB rendering reduces eta and k to RGB first). */
static void test_gold_named_spectra(void **state)
{
    (void)state;
    rgb L = plane_radiance("Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\"\n"
                           "  \"spectrum k\" \"metal-Au-k\" \"float roughness\" 0\n",
                           &spectral_opt, 1024);
    rgb want = rgb_of_illuminated(gold_head_on, NULL);
    expect_rgb_close(L, want, 0.0, 3e-3, "gold head on", 4.5, 4.5);
}

/* A camera looking through a slab (thickness 1: an interface box or glass)
 * toward a black area light of radiance 1: the mean of a SLAB_RES^2 image
 * of `spp` samples a pixel (tracking through an absorber is a 0-or-1
 * estimate per sample: many are needed). */
static rgb through_slab_with(const char *integrator, const char *slab_material, const char *medium,
                             const render_options *opt, int spp, int maxdepth)
{
    char head[1024];
    snprintf(head, sizeof head,
             "LookAt 0 0 5  0 0 0  0 1 0\n"
             "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
             "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" %d\n"
             "Integrator \"%s\" %s %d\n"
             "WorldBegin\n",
             SLAB_RES, SLAB_RES, spp, integrator,
             strcmp(integrator, "volpath") == 0 ? "\"integer maxdepth\"" : "\"integer lightsamples\"",
             maxdepth);
    char body[2048];
    snprintf(body, sizeof body,
             "%s"
             "AttributeBegin\n"
             "  %s\n"
             "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3 4 6 5 4 7 6]\n"
             "    \"point3 P\" [-2 -2 0.5 2 -2 0.5 2 2 0.5 -2 2 0.5\n"
             "                 -2 -2 -0.5 2 -2 -0.5 2 2 -0.5 -2 2 -0.5]\n"
             "AttributeEnd\n"
             "AttributeBegin\n"
             "  Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
             "  AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
             "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "    \"point3 P\" [-3 -3 -2 3 -3 -2 3 3 -2 -3 3 -2]\n"
             "AttributeEnd\n",
             medium, slab_material);
    char *text = cat(head, body, "");
    render_options o = *opt;
    render_scene *rs = build_scene_or_fail(text, &o);
    free(text);
    render_expect_finite(rs);
    rgb sum = rgb_grey(0.0);
    for (int y = 0; y < SLAB_RES; ++y)
        for (int x = 0; x < SLAB_RES; ++x)
            sum = rgb_add(sum, film_get_pixel(render_scene_film(rs), x, y, 1.0));
    render_scene_destroy(rs);
    return rgb_scale(sum, 1.0 / (SLAB_RES * SLAB_RES));
}

static rgb through_slab(const char *slab_material, const char *medium, const render_options *opt,
                        int spp, int maxdepth)
{
    return through_slab_with("volpath", slab_material, medium, opt, spp, maxdepth);
}

/* The RGB (sRGB) of spectrum s(lambda) times the sRGB illuminant (D65 at
 * luminance 1), integrated against the observer at 0.1 nm. */
static rgb rgb_of_illuminated(spectrum_fn s, const void *ctx)
{
    vec3 xyz = v3(0, 0, 0);
    double h = 0.1;
    for (double l = WAVELENGTH_MIN + h / 2; l < WAVELENGTH_MAX; l += h) {
        double v = s(l, ctx) * rgb_spectrum_illuminant(srgb_table(), l) * h;
        xyz = v3_add(xyz, v3_scale(spectrum_cie_xyz(l), v));
    }
    return rgb_spectrum_rgb_from_xyz(srgb_table(), v3_scale(xyz, 1.0 / SPECTRUM_CIE_Y_INTEGRAL));
}

static double beer_lambert(double lambda, const void *ctx)
{
    const rgb_unbounded_spectrum *sigma = ctx;
    return exp(-rgb_unbounded_spectrum_eval(*sigma, lambda) * 1.0);
}

/* A chromatic absorbing medium: per wavelength exp(-sigma_a(lambda) d),
 * sigma_a the unbounded spectrum of its RGB. RGB rendering gives
 * exp(-sigma_rgb d) per channel instead, which differs by far more than
 * the noise. */
static void test_chromatic_beer_lambert(void **state)
{
    (void)state;
    const char *medium = "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\"\n"
                         "  \"rgb sigma_a\" [2 0.5 0.1] \"rgb sigma_s\" [0 0 0]\n";
    const char *slab = "MediumInterface \"ink\" \"\"\n  Material \"interface\"";
    rgb got = through_slab(slab, medium, &spectral_opt, 256, 5);
    rgb_unbounded_spectrum sigma =
        rgb_unbounded_spectrum_from_rgb(srgb_table(), rgb_make(2.0, 0.5, 0.1));
    rgb want = rgb_of_illuminated(beer_lambert, &sigma);
    expect_rgb_close(got, want, 0.0, 2e-3, "spectral transmittance", 2.5, 2.5);
    /* 1024 spp: the hero's pass or stop is the noise (0.0015 to 0.0026 at
     * 64 spp across seeds, about 4x less here) */
    render_options rgb_opt = {.seed = 0, .color = RENDER_COLOR_RGB};
    rgb in_rgb = through_slab(slab, medium, &rgb_opt, 1024, 5);
    expect_rgb_close(in_rgb, rgb_make(exp(-2.0), exp(-0.5), exp(-0.1)), 0.0, 2e-3,
                     "RGB transmittance", 2.5, 2.5);
    assert_true(fabs(want.r - in_rgb.r) > 0.02); /* the two modes differ here */
    /* singlescatter's transmittance through a homogeneous medium is exact:
     * only the wavelengths' noise is left. */
    rgb ss = through_slab_with("singlescatter", slab, medium, &spectral_opt, 64, 1);
    expect_rgb_close(ss, want, 0.0, 1e-3, "singlescatter spectral transmittance", 2.5, 2.5);
}

static double sampled_beer_lambert(double lambda, const void *ctx)
{
    (void)ctx; /* sigma_a 2 at 400 nm falling linearly to 0.1 at 700 nm, 0 outside */
    double sigma = lambda < 400.0 || lambda > 700.0 ? 0.0 : 2.0 + (lambda - 400.0) * (-1.9 / 300.0);
    return exp(-sigma);
}

/* The same with sigma_a given as a sampled spectrum: the medium's own
 * spectrum per wavelength, not the RGB spectrum of its RGB. */
static void test_sampled_medium(void **state)
{
    (void)state;
    const char *medium = "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\"\n"
                         "  \"spectrum sigma_a\" [400 2 700 0.1] \"rgb sigma_s\" [0 0 0]\n";
    const char *slab = "MediumInterface \"ink\" \"\"\n  Material \"interface\"";
    rgb got = through_slab(slab, medium, &spectral_opt, 256, 5);
    rgb want = rgb_of_illuminated(sampled_beer_lambert, NULL);
    expect_rgb_close(got, want, 0.0, 2.5e-3, "sampled sigma_a", 2.5, 2.5);
    /* The detour through the spectrum's RGB would be told apart. */
    const double lambda[2] = {400.0, 700.0}, value[2] = {2.0, 0.1};
    rgb_unbounded_spectrum detour = rgb_unbounded_spectrum_from_rgb(
        srgb_table(), spectrum_sampled_to_rgb(lambda, value, 2));
    rgb other = rgb_of_illuminated(beer_lambert, &detour);
    /* (0.604 0.332 0.172 as given, 0.577 0.335 0.167 by the detour) */
    assert_true(fabs(other.r - want.r) > 0.01 || fabs(other.g - want.g) > 0.01 ||
                fabs(other.b - want.b) > 0.01);
}

/* The mean of a render of a coloured fog sphere (volumes/fog_sphere.vdb)
 * under a distant light, spectrally, with `integrator`. */
static rgb coloured_fog_mean(const char *integrator, int spp)
{
    char text[4096];
    snprintf(text, sizeof text,
             "LookAt 0 0.3 -4  0 0 0  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 35\n"
             "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 24\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" %d\n"
             "Integrator %s\n"
             "WorldBegin\n"
             "LightSource \"distant\" \"point3 from\" [1 3 -2] \"point3 to\" [0 0 0]"
             " \"blackbody L\" [4000] \"float scale\" 3\n"
             "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"%s\"\n"
             "    \"rgb sigma_a\" [0.5 1 1.5] \"rgb sigma_s\" [8 5 3]\n"
             "AttributeBegin\n  Material \"interface\"\n  MediumInterface \"m\" \"\"\n"
             "  Shape \"sphere\" \"float radius\" 1.1\nAttributeEnd\n",
             spp, integrator, HAZE_SCENES "/../volumes/fog_sphere.vdb");
    render_options opt = spectral_opt;
    render_scene *rs = build_scene_or_fail(text, &opt);
    render_expect_finite(rs);
    rgb sum = rgb_grey(0.0);
    for (int i = 0; i < 24 * 24; ++i)
        sum = rgb_add(sum, film_get_pixel(render_scene_film(rs), i % 24, i / 24, 1.0));
    render_scene_destroy(rs);
    return rgb_scale(sum, 1.0 / (24 * 24));
}

/* A coloured grid medium lit by a blackbody sun: singlescatter's marching
 * (with shadow rays, and with the shadow cache, whose optical depths become
 * spectra) and volpath's single scattering (maxdepth 1, the same
 * expectation) agree per channel within their step bias and noise. */
static void test_singlescatter_grid(void **state)
{
    (void)state;
    rgb vp = coloured_fog_mean("\"volpath\" \"integer maxdepth\" 1", 256);
    rgb rays = coloured_fog_mean("\"singlescatter\" \"float stepsize\" 0.5", 16);
    rgb cache = coloured_fog_mean("\"singlescatter\" \"float stepsize\" 0.5 "
                                  "\"float shadowcache\" 1",
                                  16);
    assert_true(vp.r > 0.01 && vp.b > 0.003);
    expect_rgb_close(rays, vp, 0.03, 0.0, "singlescatter (shadow rays) vs volpath", 0, 0);
    expect_rgb_close(cache, rays, 0.01, 0.0, "singlescatter: shadow cache vs shadow rays", 0, 0);
}

/* A smooth glass slab seen straight on, every interreflection followed:
 * transmittance (1 - R) / (1 + R), R the normal-incidence reflectance. */
static void test_dielectric_slab(void **state)
{
    (void)state;
    double R = (0.5 / 2.5) * (0.5 / 2.5);
    rgb got = through_slab("Material \"dielectric\" \"float eta\" 1.5", "", &spectral_opt, 16,
                           100);
    expect_rgb_close(got, rgb_grey((1 - R) / (1 + R)), 0.0, 3e-3, "glass slab", 2.5, 2.5);
}

/* A glass slab seen straight on whose index falls from 3 at 360 nm to 1.2
 * at 830 nm: each wavelength passes (1 - R(lambda)) / (1 + R(lambda)) of
 * the light behind it, so the slab tints it red; a path keeps one
 * wavelength past a dispersive surface (pbrt-v4's TerminateSecondary). A
 * constant index (RGB rendering's, at 550 nm) would pass grey. */
static double dispersed_slab(double lambda, const void *ctx)
{
    (void)ctx;
    double eta = 3.0 + (1.2 - 3.0) * (lambda - 360.0) / (830.0 - 360.0);
    double r = (eta - 1.0) / (eta + 1.0);
    r *= r;
    return (1.0 - r) / (1.0 + r);
}

/* The normal-incidence reflectance of a smooth coating whose index falls
 * from 3 to 1.2 over 360-830 nm, on a black base. */
static double dispersed_coating(double lambda, const void *ctx)
{
    (void)ctx;
    double eta = 3.0 + (1.2 - 3.0) * (lambda - 360.0) / (830.0 - 360.0);
    double r = (eta - 1.0) / (eta + 1.0);
    return r * r;
}

/* A coated diffuse's coating disperses as a dielectric does (pbrt-v4's
 * coated materials take their interface index at the hero wavelength and
 * terminate the others): head on under a white sky, a smooth coating over
 * a black base reflects R(lambda) per wavelength. At 550 nm alone (no
 * dispersion) it would be grey, 0.0713 in every channel. */
static void test_dispersive_coating(void **state)
{
    (void)state;
    /* Rendered (not eval_pixel's one fixed ray), as dispersion asks. */
    char *text = plane_scene("Material \"coateddiffuse\" \"rgb reflectance\" [0 0 0]\n"
                             "  \"float roughness\" 0 \"spectrum eta\" [360 3  830 1.2]\n",
                             8192);
    render_options opt = {.seed = 0}; /* --color auto: spectral for the dispersive coating */
    render_scene *rs = build_scene_or_fail(text, &opt);
    free(text);
    assert_true(render_scene_spectral(rs));
    render_expect_finite(rs);
    rgb got = rgb_grey(0.0);
    for (int i = 0; i < 64; ++i)
        got = rgb_add(got, film_get_pixel(render_scene_film(rs), i % 8, i / 8, 1.0));
    got = rgb_scale(got, 1.0 / 64);
    render_scene_destroy(rs);
    rgb want = rgb_of_illuminated(dispersed_coating, NULL);
    print_message("dispersive coating: %.4f %.4f %.4f, want %.4f %.4f %.4f\n", got.r, got.g,
                  got.b, want.r, want.g, want.b);
    /* One wavelength a sample: about 1.1% noise in red (seeds 0-3). */
    expect_rgb_close(got, want, 0.04, 0.0, "dispersive coating", 0, 0);
    assert_true(want.b - want.r > 0.03);
}

static void test_dispersive_slab(void **state)
{
    (void)state;
    rgb got = through_slab("Material \"dielectric\" \"spectrum eta\" [360 3  830 1.2]", "",
                           &spectral_opt, 1024, 100);
    rgb want = rgb_of_illuminated(dispersed_slab, NULL);
    print_message("dispersive slab: %.4f %.4f %.4f, want %.4f %.4f %.4f\n", got.r, got.g, got.b,
                  want.r, want.g, want.b);
    expect_rgb_close(got, want, 0.0, 4e-3, "dispersive slab", 2.5, 2.5);
    assert_true(want.r - want.b > 0.1);
}

static double furnace(double lambda, const void *ctx)
{
    const rgb_albedo_spectrum *rho = ctx;
    return 1.0 / (1.0 - rgb_albedo_spectrum_eval(*rho, lambda));
}

/* The white furnace: inside a sphere whose every point emits radiance 1
 * (white, D65) and reflects diffusely with albedo rho, radiance is
 * 1 / (1 - rho(lambda)) at every wavelength: every bounce multiplies
 * spectra. RGB rendering's 1 / (1 - rho_rgb) per channel differs. */
static void test_white_furnace(void **state)
{
    (void)state;
    const char *text = "LookAt 0 0 0  0 0 1  0 1 0\n"
                       "Camera \"perspective\" \"float fov\" 60\n"
                       "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                       "Sampler \"zsobol\" \"integer pixelsamples\" 256\n"
                       "Integrator \"volpath\" \"integer maxdepth\" 200\n"
                       "WorldBegin\n"
                       "Material \"diffuse\" \"rgb reflectance\" [0.8 0.5 0.2]\n"
                       "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n"
                       "Shape \"sphere\" \"float radius\" 1\n";
    rgb got[2];
    for (int mode = 0; mode < 2; ++mode) {
        render_options opt = {.seed = 0,
                              .color = mode ? RENDER_COLOR_SPECTRAL : RENDER_COLOR_RGB};
        render_scene *rs = build_scene_or_fail(text, &opt);
        render_expect_finite(rs);
        rgb sum = rgb_grey(0.0);
        for (int i = 0; i < 256; ++i)
            sum = rgb_add(sum, film_get_pixel(render_scene_film(rs), i % 16, i / 16, 1.0));
        got[mode] = rgb_scale(sum, 1.0 / 256);
        render_scene_destroy(rs);
    }
    rgb_albedo_spectrum rho = rgb_albedo_spectrum_from_rgb(srgb_table(), rgb_make(0.8, 0.5, 0.2));
    rgb want = rgb_of_illuminated(furnace, &rho);
    expect_rgb_close(got[1], want, 5e-3, 0.0, "spectral furnace", 0, 0);
    expect_rgb_close(got[0], rgb_make(5.0, 2.0, 1.25), 5e-3, 0.0, "RGB furnace", 0, 0);
    assert_true(fabs(want.r - 5.0) > 0.1); /* the modes differ by far more than the noise */
}

/* A blackbody emitter of 2856 K seen directly: the chromaticity of CIE
 * illuminant A (x 0.44757, y 0.40745), from the wavelengths themselves;
 * its luminance 1 as an RGB light's (pbrt-v4's normalisation). */
static void test_blackbody_chromaticity(void **state)
{
    (void)state;
    const char *text = "LookAt 0 0 5  0 0 0  0 1 0\n"
                       "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
                       "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                       "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
                       "Integrator \"volpath\"\n"
                       "WorldBegin\n"
                       "AreaLightSource \"diffuse\" \"blackbody L\" [2856]\n"
                       "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
                       "  \"point3 P\" [-2 -2 0 2 -2 0 2 2 0 -2 2 0]\n";
    render_options opt = spectral_opt;
    render_scene *rs = build_scene_or_fail(text, &opt);
    rgb L = eval_pixel(rs, 2.5, 2.5, 4096).L;
    render_scene_destroy(rs);
    vec3 xyz = rgb_spectrum_xyz_from_rgb(srgb_table(), L);
    double sum = xyz.x + xyz.y + xyz.z;
    expect_close(xyz.x / sum, 0.44757, 0.0, 1e-3, "x of 2856 K", 2.5, 2.5);
    expect_close(xyz.y / sum, 0.40745, 0.0, 1e-3, "y of 2856 K", 2.5, 2.5);
    expect_close(xyz.y, 1.0, 0.0, 3e-3, "luminance", 2.5, 2.5);
}

/* The film's mean of a quad emitting `colour`, filling a 16x16 image taken
 * with Film "sensor" "nikon_d850", in colour mode `color`. */
static rgb sensor_image_mean(const char *colour, render_color color)
{
    char text[1024];
    snprintf(text, sizeof text,
             "LookAt 0 0 0  0 0 1  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 30\n"
             "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
             "  \"string sensor\" \"nikon_d850\"\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 256\n"
             "Integrator \"volpath\" \"integer maxdepth\" 1\n"
             "WorldBegin\n"
             "AreaLightSource \"diffuse\" \"rgb L\" [%s]\n"
             "Shape \"trianglemesh\" \"point3 P\" [-10 -10 5  10 -10 5  10 10 5  -10 10 5]\n"
             "  \"integer indices\" [0 2 1 0 3 2]\n",
             colour);
    render_options opt = {.seed = 0, .color = color};
    render_scene *rs = build_scene_or_fail(text, &opt);
    render_expect_finite(rs);
    rgb sum = rgb_grey(0.0);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            sum = rgb_add(sum, film_get_pixel(render_scene_film(rs), x, y, 1.0));
    render_scene_destroy(rs);
    return rgb_scale(sum, 1.0 / 256.0);
}

/* A camera sensor under spectral rendering: each sample's wavelengths on the
 * camera's response curves, as pbrt-v4's PixelSensor. pbrt-v4's image means
 * of the same scene (4096 spp: `pbrt --spp 4096`) are the reference; the RGB
 * fit of the sensor (film/sensor.h) is exact for greys only. And --color
 * auto renders spectrally when the Film has a camera sensor. */
static void test_camera_sensor(void **state)
{
    (void)state;
    rgb red = sensor_image_mean("0.8 0.1 0.1", RENDER_COLOR_SPECTRAL);
    expect_rgb_close(red, rgb_make(0.84399, 0.11490, 0.11847), 0.015, 0.0, "red emitter", 0, 0);
    rgb grey = sensor_image_mean("0.5 0.5 0.5", RENDER_COLOR_SPECTRAL);
    expect_rgb_close(grey, rgb_make(0.49224, 0.49756, 0.49145), 0.005, 0.0, "grey emitter", 0, 0);
    rgb grey_rgb = sensor_image_mean("0.5 0.5 0.5", RENDER_COLOR_RGB);
    expect_rgb_close(grey_rgb, grey, 0.005, 0.0, "grey emitter, RGB", 0, 0);
    /* The RGB fit's blue of the red emitter: 0.73 of pbrt-v4's. */
    rgb red_rgb = sensor_image_mean("0.8 0.1 0.1", RENDER_COLOR_RGB);
    print_message("red emitter: spectral %.5f %.5f %.5f, RGB %.5f %.5f %.5f\n", red.r, red.g,
                  red.b, red_rgb.r, red_rgb.g, red_rgb.b);
    assert_true(red_rgb.b < 0.9 * red.b);

    const char *scene = "Camera \"orthographic\"\n"
                        "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                        "  \"string sensor\" \"%s\"\n"
                        "WorldBegin\n"
                        "Shape \"sphere\"\n";
    const char *sensors[2] = {"canon_eos_5d_mkiv", "cie1931"};
    for (int k = 0; k < 2; ++k) {
        char text[512];
        snprintf(text, sizeof text, scene, sensors[k]);
        render_options opt = {.seed = 0};
        render_scene *rs = build_scene_or_fail(text, &opt);
        assert_true(render_scene_spectral(rs) == (k == 0));
        render_scene_destroy(rs);
    }
}

/* A scene of `material` under a white sky with `integrator`, built with
 * the default colour mode: whether it renders spectrally. */
static bool auto_spectral_film(const char *integrator, const char *film, const char *material)
{
    char text[2048];
    snprintf(text, sizeof text,
             "LookAt 0 0 5  0 0 0  0 1 0\n"
             "Camera \"orthographic\"\n"
             "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4 %s\n"
             "Integrator \"%s\"\n"
             "WorldBegin\n"
             "LightSource \"infinite\" \"rgb L\" [1 0.5 0.2]\n"
             "%s\n"
             "Shape \"sphere\"\n",
             film, integrator, material);
    render_options opt = {.seed = 0}; /* RENDER_COLOR_AUTO */
    render_scene *rs = build_scene_or_fail(text, &opt);
    bool spectral = render_scene_spectral(rs);
    render_scene_destroy(rs);
    return spectral;
}
static bool auto_spectral(const char *integrator, const char *material)
{
    return auto_spectral_film(integrator, "", material);
}

/* --color auto: spectral where a scene has a coloured medium or a coloured
 * metal, coating, hair or measured material; RGB for diffuse colours and
 * coloured lights, under either integrator. */
static void test_auto_choice(void **state)
{
    (void)state;
    /* Diffuse colours (under a coloured sky) only scale each wavelength. */
    assert_false(auto_spectral("volpath", "Material \"diffuse\" \"rgb reflectance\" [0.6 0.12 0.1]"));
    assert_false(auto_spectral("volpath", "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]"));
    assert_true(auto_spectral("volpath", "Material \"conductor\""));  /* copper */
    assert_false(auto_spectral("volpath", "Material \"conductor\" \"spectrum eta\" [1.5]\n"
                                          "  \"spectrum k\" [2]"));
    assert_false(auto_spectral("volpath", "Material \"dielectric\""));
    assert_true(auto_spectral("volpath", "Material \"coateddiffuse\" \"rgb reflectance\" [0.7 0.1 0.1]"));
    assert_false(auto_spectral("volpath", "Material \"coateddiffuse\" \"rgb reflectance\" [0.4 0.4 0.4]"));
    assert_true(auto_spectral("volpath", "Texture \"c\" \"spectrum\" \"checkerboard\"\n"
                                         "  \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1]\n"
                                         "Material \"coateddiffuse\" \"texture reflectance\" \"c\""));
    assert_false(auto_spectral("volpath", "Texture \"c\" \"spectrum\" \"checkerboard\"\n"
                                          "  \"rgb tex1\" [1 1 1] \"rgb tex2\" [0 0 0]\n"
                                          "Material \"coateddiffuse\" \"texture reflectance\" \"c\""));
    assert_true(auto_spectral("volpath", "MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
                                         "  \"rgb sigma_a\" [1 0.5 0.2]\n"
                                         "MediumInterface \"m\" \"\"\nMaterial \"interface\""));
    assert_false(auto_spectral("volpath", "MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
                                          "  \"rgb sigma_a\" [1 1 1]\n"
                                          "MediumInterface \"m\" \"\"\nMaterial \"interface\""));
    assert_true(auto_spectral("singlescatter", "Material \"conductor\""));
    assert_false(auto_spectral("singlescatter", "Material \"diffuse\""));
    /* A named glass disperses, in volpath only; a constant spectrum does not. */
    assert_true(auto_spectral("volpath", "Material \"dielectric\" \"spectrum eta\" \"glass-BK7\""));
    assert_false(auto_spectral("volpath", "Material \"dielectric\" \"spectrum eta\" [1.5]"));
    assert_false(
        auto_spectral("singlescatter", "Material \"dielectric\" \"spectrum eta\" \"glass-BK7\""));
    /* A clamp acts on each sample's four wavelengths, as pbrt-v4's. */
    assert_true(auto_spectral_film("volpath", "\"float maxcomponentvalue\" 10", "Material \"diffuse\""));
    assert_true(
        auto_spectral_film("singlescatter", "\"float maxcomponentvalue\" 10", "Material \"diffuse\""));
}

/* Without the tables' module, --color spectral is an error naming what to
 * set, and auto renders in RGB with a warning. */
static void test_missing_module(void **state)
{
    (void)state;
    const char *text = "Camera \"orthographic\"\n"
                       "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                       "Integrator \"volpath\"\n"
                       "WorldBegin\n"
                       "Material \"conductor\"\n"
                       "Shape \"sphere\"\n";
    setenv("HAZE_RGB2SPEC_MODULE", "/nonexistent/libhaze_rgb2spec.so", 1);
    for (int mode = 0; mode < 2; ++mode) {
        scene_desc sd;
        hz_error err = {0};
        assert_int_equal(scene_parse_string(text, "m.pbrt", &sd, &err), HZ_OK);
        render_options opt = {.seed = 0,
                              .color = mode ? RENDER_COLOR_SPECTRAL : RENDER_COLOR_AUTO};
        char warned[2048] = "";
        FILE *warn = fmemopen(warned, sizeof warned - 1, "w");
        assert_non_null(warn);
        render_scene *rs = NULL;
        hz_status st = render_scene_create(&sd, &opt, warn, &rs, &err);
        fclose(warn);
        scene_desc_free(&sd);
        if (mode) {
            assert_int_equal(st, HZ_ERROR);
            assert_non_null(strstr(err.message, "HAZE_RGB2SPEC_MODULE"));
        } else {
            assert_int_equal(st, HZ_OK);
            assert_false(render_scene_spectral(rs));
            assert_non_null(strstr(warned, "rendering in RGB"));
            render_scene_destroy(rs);
        }
    }
    unsetenv("HAZE_RGB2SPEC_MODULE");
}

/* The same scene and seed give the same image on 1 and 2 threads. */
static void test_thread_count_invariance(void **state)
{
    (void)state;
    const char *text = "LookAt 0 0 5  0 0 0  0 1 0\n"
                       "Camera \"perspective\" \"float fov\" 30\n"
                       "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
                       "Sampler \"zsobol\" \"integer pixelsamples\" 8\n"
                       "Integrator \"volpath\"\n"
                       "WorldBegin\n"
                       "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                       "Material \"diffuse\" \"rgb reflectance\" [0.7 0.2 0.1]\n"
                       "Shape \"sphere\"\n";
    rgb px[2][24 * 16];
    for (int t = 0; t < 2; ++t) {
        render_options opt = spectral_opt;
        render_scene *rs = build_scene_or_fail(text, &opt);
        renderer_options ro = {.threads = t + 1, .progress = NULL};
        render_stats stats;
        hz_error err = {0};
        assert_int_equal(renderer_run(rs, &ro, &stats, &err), HZ_OK);
        for (int i = 0; i < 24 * 16; ++i)
            px[t][i] = film_get_pixel(render_scene_film(rs), i % 24, i / 24, 1.0);
        render_scene_destroy(rs);
    }
    assert_memory_equal(px[0], px[1], sizeof px[0]);
    bool coloured = false;
    for (int i = 0; i < 24 * 16; ++i)
        coloured |= px[0][i].r > 2.0 * px[0][i].b && px[0][i].b > 0.0;
    assert_true(coloured);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wavelength_density),
        cmocka_unit_test(test_coloured_reflectance),
        cmocka_unit_test(test_grey_matches_rgb),
        cmocka_unit_test(test_conductor_constant),
        cmocka_unit_test(test_gold_named_spectra),
        cmocka_unit_test(test_chromatic_beer_lambert),
        cmocka_unit_test(test_sampled_medium),
        cmocka_unit_test(test_singlescatter_grid),
        cmocka_unit_test(test_dielectric_slab),
        cmocka_unit_test(test_dispersive_slab),
        cmocka_unit_test(test_dispersive_coating),
        cmocka_unit_test(test_blackbody_chromaticity),
        cmocka_unit_test(test_white_furnace),
        cmocka_unit_test(test_auto_choice),
        cmocka_unit_test(test_camera_sensor),
        cmocka_unit_test(test_missing_module),
        cmocka_unit_test(test_thread_count_invariance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
