/* Integrator "volpath": closed forms of multiple scattering (furnaces), the
 * selection of the integrator and its parameters. */
#include "media_test_util.h"
#include "integrator/volpath_media.h"

/* A sphere of medium (radius 1 at the origin) under a uniform sky, seen from
 * outside: with albedo 1 and no absorption anywhere, every path leaves with
 * the sky's radiance, so L = sky on every pixel, inside the sphere or not. */
static char *sky_furnace(const char *medium, const char *extra)
{
    return sfmt("LookAt 0 0 4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 35\n"
                "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                "Integrator \"volpath\" \"integer maxdepth\" 100000 %s\n"
                "WorldBegin\n"
                "LightSource \"infinite\" \"rgb L\" [0.5 1 1.5]\n"
                "MakeNamedMedium \"m\" %s\n"
                "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
                "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
                extra, medium);
}

/* Grey media: scattering and null-collision weights are exactly 1, so each
 * path returns the sky exactly (a zero-variance furnace); marched (the
 * grid at "stepsize" 3) too: the strata's field is a medium of albedo 1; and
 * split in three at the first scattering point (their mean). */
static void test_grey_sky_furnace_is_exact(void **state)
{
    (void)state;
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [3 3 3] "
        "\"float g\" 0.6",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [8 8 8] \"float g\" -0.3",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [8 8 8] \"float g\" -0.3",
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [3 3 3] "
        "\"float g\" 0.6",
    };
    const char *extra[] = {"", "", "\"float stepsize\" 3", "\"integer mediumsplits\" 3"};
    for (size_t k = 0; k < 4; ++k) {
        char *text = sky_furnace(media[k], extra[k]);
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 8, 8, 16);
        for (int i = 0; i < 64; ++i)
            for (int c = 0; c < 3; ++c)
                assert_float_equal(ch(px[i].mean, c), 0.5 * (c + 1), 1e-9);
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}

/* Chromatic albedo-1 media: the hero channel's tracking carries the others
 * through r_u; the mean is still the sky, within noise. Marched too (the
 * grid at "stepsize" 3: the other lanes weighted by their transmittance in
 * the strata's field over the hero's). */
static void test_chromatic_sky_furnace(void **state)
{
    (void)state;
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0.5 2 4] "
        "\"float g\" 0.5",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [2 6 12]",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [2 6 12]",
    };
    for (size_t k = 0; k < 3; ++k) {
        char *text = sky_furnace(media[k], k == 2 ? "\"float stepsize\" 3" : "");
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 8, 8, 1024);
        double sum[3] = {0, 0, 0}, var[3] = {0, 0, 0};
        for (int i = 0; i < 64; ++i)
            for (int c = 0; c < 3; ++c) {
                sum[c] += ch(px[i].mean, c);
                var[c] += ch(px[i].se, c) * ch(px[i].se, c);
            }
        for (int c = 0; c < 3; ++c) {
            double mean = sum[c] / 64, se = sqrt(var[c]) / 64, want = 0.5 * (c + 1);
            if (verbose())
                print_message("medium %zu channel %d: %.6f +- %.6f (want %g)\n", k, c, mean, se,
                              want);
            assert_true(se < 0.02 * want);
            assert_true(fabs(mean - want) < 4.0 * se + 1e-12);
        }
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}

/* A closed room whose walls emit Le and reflect with albedo rho, filled with
 * an albedo-1 medium: the radiance is Le / (1 - rho) everywhere, in every
 * direction (the medium neither adds nor removes light from a uniform
 * field). Exercises area-light MIS (light sampling against BSDF and phase
 * sampling), shadow rays by ratio tracking, and surface-medium bounces; and
 * (the third) the continuations of paths split at their first scattering
 * point, which meet walls, the light and the medium again. */
static char *emitting_room(const char *medium, const char *integrator)
{
    char *box = box_mesh(v3(-2, -2, -2), v3(2, 2, 2));
    char *s = sfmt("MediumInterface \"\" \"m\"\n"
                   "LookAt 0 0 -1.5  0 0.3 1  0 1 0\nCamera \"perspective\" \"float fov\" 70\n"
                   "Film \"rgb\" \"integer xresolution\" 6 \"integer yresolution\" 6\n"
                   "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                   "%s\nWorldBegin\n"
                   "MakeNamedMedium \"m\" %s\nMediumInterface \"\" \"\"\n"
                   "Material \"diffuse\" \"rgb reflectance\" [0.5 0.25 0.75]\n"
                   "AreaLightSource \"diffuse\" \"rgb L\" [1 2 0.5] \"bool twosided\" true\n%s",
                   integrator, medium, box);
    free(box);
    return s;
}

static void test_emitting_room_furnace(void **state)
{
    (void)state;
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0.3 0.6 0.9] "
        "\"float g\" 0.4",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [3 1 2] \"float g\" -0.2",
    };
    const char *integ[] = {"Integrator \"volpath\" \"integer maxdepth\" 400",
                           "Integrator \"volpath\" \"integer maxdepth\" 400 "
                           "\"string lightsampler\" \"uniform\"",
                           "Integrator \"volpath\" \"integer maxdepth\" 400 "
                           "\"integer mediumsplits\" 3"};
    const double want[3] = {1.0 / 0.5, 2.0 / 0.75, 0.5 / 0.25};
    for (size_t k = 0; k < 3; ++k) {
        char *text = emitting_room(media[k % 2], integ[k]);
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 6, 6, 1024);
        double sum[3] = {0, 0, 0}, var[3] = {0, 0, 0};
        for (int i = 0; i < 36; ++i)
            for (int c = 0; c < 3; ++c) {
                sum[c] += ch(px[i].mean, c);
                var[c] += ch(px[i].se, c) * ch(px[i].se, c);
            }
        for (int c = 0; c < 3; ++c) {
            double mean = sum[c] / 36, se = sqrt(var[c]) / 36;
            if (verbose())
                print_message("room %zu channel %d: %.5f +- %.5f (want %g)\n", k, c, mean, se,
                              want[c]);
            assert_true(se < 0.02 * want[c]);
            assert_true(fabs(mean - want[c]) < 4.0 * se);
        }
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}

/* ---- maxdepth 1 is single scattering ---- */

/* Fog in a box around a diffuse floor and sphere, lit by every kind of light
 * (spot, point, distant, sky, an emitting sphere inside the fog). */
static char *one_bounce_scene(const char *medium, const char *integrator)
{
    char *box = box_mesh(v3(-1.6, -0.5, -1.6), v3(1.6, 2.2, 1.6));
    char *s = sfmt(
        "LookAt 0 1.2 -4.5  0 0.6 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
        "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
        "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n"
        "LightSource \"spot\" \"rgb I\" [6 5 4] \"point3 from\" [0.3 2 0] \"point3 to\" [0 0 0] "
        "\"float coneangle\" 35\n"
        "LightSource \"point\" \"rgb I\" [1 0.6 0.3] \"point3 from\" [1 1 -1]\n"
        "LightSource \"distant\" \"rgb L\" [0.4 0.4 0.5] \"point3 from\" [1 2 -1] "
        "\"point3 to\" [0 0 0]\n"
        "LightSource \"infinite\" \"rgb L\" [0.05 0.08 0.1]\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 3 2]\nTranslate -0.9 1.2 0.6\n"
        "Shape \"sphere\" \"float radius\" 0.2\nAttributeEnd\n"
        "MakeNamedMedium \"m\" %s\n"
        "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n%sAttributeEnd\n"
        "Material \"diffuse\" \"rgb reflectance\" [0.6 0.5 0.4]\n"
        "Shape \"trianglemesh\" \"point3 P\" [-3 0 -3  3 0 -3  3 0 3  -3 0 3] "
        "\"integer indices\" [0 1 2 0 2 3]\n"
        "AttributeBegin\nTranslate 0.4 0.45 0.3\nShape \"sphere\" \"float radius\" 0.45\n"
        "AttributeEnd\n",
        integrator, medium, box);
    free(box);
    return s;
}

/* Block means (4x4 blocks of 4x4 pixels) of volpath maxdepth 1 and of
 * singlescatter agree within noise. */
static void test_maxdepth_1_matches_singlescatter(void **state)
{
    (void)state;
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.2 0.1] "
        "\"rgb sigma_s\" [0.4 0.3 0.6] \"float g\" 0.3",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [2 3 1] \"float g\" -0.4",
    };
    const char *ss = "Integrator \"singlescatter\" \"string transmittance\" \"ratio\"";
    const char *vp = "Integrator \"volpath\" \"integer maxdepth\" 1";
    for (size_t k = 0; k < 2; ++k) {
        char *ta = one_bounce_scene(media[k], ss), *tb = one_bounce_scene(media[k], vp);
        render_scene *ra = build(ta), *rb = build(tb);
        pstat *a = image_stats(ra, 16, 16, 1024), *b = image_stats(rb, 16, 16, 1024);
        double worst = 0.0, sum_a = 0.0, sum_b = 0.0, var_a = 0.0, var_b = 0.0;
        for (int by = 0; by < 4; ++by)
            for (int bx = 0; bx < 4; ++bx)
                for (int c = 0; c < 3; ++c) {
                    double ma = 0, mb = 0, va = 0, vb = 0;
                    for (int y = 4 * by; y < 4 * by + 4; ++y)
                        for (int x = 4 * bx; x < 4 * bx + 4; ++x) {
                            const pstat *pa = &a[y * 16 + x], *pb = &b[y * 16 + x];
                            ma += ch(pa->mean, c) / 16;
                            mb += ch(pb->mean, c) / 16;
                            va += ch(pa->se, c) * ch(pa->se, c) / 256;
                            vb += ch(pb->se, c) * ch(pb->se, c) / 256;
                        }
                    sum_a += ma;
                    sum_b += mb;
                    var_a += va;
                    var_b += vb;
                    double z = fabs(ma - mb) / sqrt(va + vb + 1e-300);
                    worst = fmax(worst, z);
                }
        double z_all = fabs(sum_a - sum_b) / sqrt(var_a + var_b);
        if (verbose())
            print_message("medium %zu: image mean %.5f vs %.5f (z %.2f), worst block z %.2f\n",
                          k, sum_a / 48, sum_b / 48, z_all, worst);
        assert_true(z_all < 4.0);
        assert_true(worst < 4.5);
        free(a);
        free(b);
        render_scene_destroy(ra);
        render_scene_destroy(rb);
        free(ta);
        free(tb);
    }
}

/* The mean of a 4x4 image at 4096 spp matches `want` per channel within
 * noise (4 standard errors), the noise below 1% of it. */
static void expect_image_mean(render_scene *rs, rgb want, const char *what)
{
    rgb mean, se;
    image_mean_se(rs, 4, 4, 4096, &mean, &se);
    expect_within_noise(mean, se, want, 1e-9, what);
}

/* pbrt-v4's procedural cloud below y = 0 is solid (density 1): a slab of it,
 * seen along x under a white sky with absorption only, transmits
 * exp(-sigma_a) per unit length; singlescatter refuses the medium. */
static void test_cloud_solid_slab(void **state)
{
    (void)state;
    const char *fmt =
        "LookAt -1 -0.75 0.5  0 -0.75 0.5  0 1 0\n"
        "Camera \"orthographic\" \"float screenwindow\" [-0.1 0.1 -0.1 0.1]\n"
        "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
        "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n"
        "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
        "MakeNamedMedium \"c\" \"string type\" \"cloud\" \"rgb sigma_a\" [0.5 1 2] "
        "\"rgb sigma_s\" [0 0 0] \"point3 p0\" [0 -1 0] \"point3 p1\" [1 -0.5 1]\n"
        "AttributeBegin\nMediumInterface \"c\" \"\"\nMaterial \"\"\n"
        "Translate 0.5 -0.75 0.5\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n";
    char *text = sfmt(fmt, "Integrator \"volpath\"");
    render_scene *rs = build(text);
    expect_image_mean(rs, rgb_make(exp(-0.5), exp(-1.0), exp(-2.0)), "cloud slab");
    render_scene_destroy(rs);
    free(text);
    text = sfmt(fmt, "Integrator \"singlescatter\"");
    char msg[4096];
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "test.pbrt:8:1: MakeNamedMedium \"c\": a \"cloud\" medium needs "
                                "Integrator \"volpath\""));
    free(text);
}

/* pbrt-v4's rgbgrid: constant per-channel sigma_a samples (4 per axis over
 * the unit box, cell-centred, falling to half at the faces) transmit
 * exp(-sigma_a h (n - 1/4)) along an axis, per channel; singlescatter
 * refuses the medium. */
static void test_rgbgrid_slab(void **state)
{
    (void)state;
    char sa[64 * 16] = "", ss[64 * 8] = "";
    for (int i = 0; i < 64; ++i) {
        strcat(sa, "0.5 1 2 ");
        strcat(ss, "0 0 0 ");
    }
    const char *fmt =
        "LookAt 0.5 0.5 -1  0.5 0.5 0  0 1 0\n"
        "Camera \"orthographic\" \"float screenwindow\" [-0.1 0.1 -0.1 0.1]\n"
        "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
        "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n"
        "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
        "MakeNamedMedium \"g\" \"string type\" \"rgbgrid\" \"integer nx\" 4 \"integer ny\" 4 "
        "\"integer nz\" 4 \"rgb sigma_a\" [%s] \"rgb sigma_s\" [%s]\n"
        "AttributeBegin\nMediumInterface \"g\" \"\"\nMaterial \"\"\n"
        "Translate 0.5 0.5 0.5\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n";
    char *text = sfmt(fmt, "Integrator \"volpath\"", sa, ss);
    render_scene *rs = build(text);
    const double len = 0.25 * (4 - 0.25);
    expect_image_mean(rs, rgb_make(exp(-0.5 * len), exp(-1.0 * len), exp(-2.0 * len)),
                      "rgbgrid slab");
    render_scene_destroy(rs);
    free(text);
    text = sfmt(fmt, "Integrator \"singlescatter\"", sa, ss);
    char msg[4096];
    build_scene_expect_error(text, msg, sizeof msg);
    assert_non_null(strstr(msg, "a \"rgbgrid\" medium needs Integrator \"volpath\""));
    free(text);
}

/* fog_sphere.vdb at density scale 1e12: majorant cells that straddle its
 * surface hold ~1e12 null collisions per unit length. The walk gives up after
 * VOLPATH_MAX_COLLISIONS per segment (the segment counts as opaque), so each
 * sample stays bounded and finite instead of running for hours. */
static void test_absurd_density_is_bounded(void **state)
{
    (void)state;
    char *text = sfmt("LookAt 0 0 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
                      "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                      "Sampler \"independent\" \"integer pixelsamples\" 2\n"
                      "Integrator \"volpath\" \"integer maxdepth\" 5\nWorldBegin\n"
                      "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [2 2 -2]\n"
                      "LightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\n"
                      "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" "
                      "\"%s/fog_sphere.vdb\" \"rgb sigma_a\" [0.1 0.1 0.1] "
                      "\"rgb sigma_s\" [1 1 1] \"float scale\" 1e12\n"
                      "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
                      "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
                      VOLUMES);
    render_scene *rs = build(text);
    pstat *px = image_stats(rs, 8, 8, 2);
    uint64_t lookups = 0;
    for (int i = 0; i < 64; ++i) {
        assert_true(px[i].min >= 0.0);
        lookups += px[i].lookups;
    }
    /* Well below one budget per sample and segment (64 pixels, 2 samples). */
    assert_true(lookups < 128u * 4u * VOLPATH_MAX_COLLISIONS);
    free(px);
    render_scene_destroy(rs);
    free(text);
}

/* ---- "mediumsplits" ---- */

/* A chromatic fog sphere (`medium`: MakeNamedMedium's parameters) over a
 * grey floor, lit by a sun and a sky: the paths' first scattering points in
 * the fog take light samples, their continuations scatter again, bounce off
 * the floor (roulette there) and escape. `extra`: more integrator
 * parameters; `shapes`: more shapes and lights. */
static char *split_scene(const char *medium, const char *extra, const char *shapes)
{
    return sfmt("LookAt 0 0.4 4  0 -0.2 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n"
                "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                "Integrator \"volpath\" \"integer maxdepth\" 30 %s\n"
                "WorldBegin\n"
                "LightSource \"distant\" \"point3 from\" [-1 2 1] \"point3 to\" [0 0 0] "
                "\"rgb L\" [3 3 3]\n"
                "LightSource \"infinite\" \"rgb L\" [0.2 0.3 0.4]\n"
                "MakeNamedMedium \"m\" %s\n"
                "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
                "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n"
                "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
                "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                "\"point3 P\" [-4 -1.05 -4  4 -1.05 -4  4 -1.05 4  -4 -1.05 4]\n%s",
                extra, medium, shapes);
}

/* Per-pixel statistics of split_scene(medium, extra, shapes) under `opt`:
 * the image mean, its standard error, and the mean of the pixels' variances. */
static void split_stats(const char *medium, const char *extra, const char *shapes,
                        const render_options *opt, int spp, rgb *mean, rgb *se, double *var)
{
    char *text = split_scene(medium, extra, shapes);
    render_scene *rs = build_scene_or_fail(text, (render_options *)opt);
    pstat *px = image_stats(rs, 8, 8, spp);
    double m[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    *var = 0.0;
    for (int i = 0; i < 64; ++i)
        for (int c = 0; c < 3; ++c) {
            m[c] += ch(px[i].mean, c) / 64;
            v[c] += ch(px[i].se, c) * ch(px[i].se, c) / (64.0 * 64.0);
            *var += ch(px[i].se, c) * ch(px[i].se, c) * spp / (3 * 64.0);
        }
    *mean = rgb_make(m[0], m[1], m[2]);
    *se = rgb_make(sqrt(v[0]), sqrt(v[1]), sqrt(v[2]));
    free(px);
    render_scene_destroy(rs);
    free(text);
}

/* Splitting is unbiased: the image split in four at the first scattering
 * point has the unsplit image's mean, within noise, and a sample's variance
 * well under it (independent continuations). In RGB, and spectrally with a
 * dispersive glass sphere beside the fog (each continuation that meets it
 * keeps the hero's wavelength alone; the others all four). Tracked, and
 * marched at 2 voxels (the bias of the strata is the same split or not); and
 * homogeneous fog with a point light inside, which each segment also
 * light-samples equiangularly (MIS with the split vertex's light sample). */
static void test_splits_keep_the_mean_and_lower_the_noise(void **state)
{
    (void)state;
    const render_options rgb_opt = {.seed = 0, .color = RENDER_COLOR_RGB};
    const render_options spectral_opt = {.seed = 0, .color = RENDER_COLOR_SPECTRAL};
    const char *glass = "Material \"dielectric\" \"spectrum eta\" [360 1.9  830 1.3]\n"
                        "AttributeBegin\nTranslate 1.1 -0.6 0.5\n"
                        "Shape \"sphere\" \"float radius\" 0.45\nAttributeEnd\n";
    const char *grid = "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES
                       "/fog_sphere.vdb\" \"rgb sigma_a\" [0.3 0.3 0.3] "
                       "\"rgb sigma_s\" [2 6 12] \"float g\" 0.5";
    const char *fog = "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.1 0.1] "
                      "\"rgb sigma_s\" [0.4 0.8 1.2] \"float g\" 0.3";
    const char *lamp = "LightSource \"point\" \"point3 from\" [0.3 0.2 0.4] \"rgb I\" [2 2 2]\n";
    struct {
        const render_options *opt;
        const char *medium, *step, *shapes;
        int spp;
    } cases[] = {{&rgb_opt, grid, "", "", 512},
                 {&rgb_opt, grid, "\"float stepsize\" 2", "", 512},
                 {&spectral_opt, grid, "", glass, 2048},
                 {&rgb_opt, fog, "", lamp, 512}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char *one = sfmt("%s", cases[k].step);
        char *four = sfmt("%s \"integer mediumsplits\" 4", cases[k].step);
        rgb m1, s1, m4, s4;
        double v1, v4;
        split_stats(cases[k].medium, one, cases[k].shapes, cases[k].opt, cases[k].spp, &m1, &s1,
                    &v1);
        split_stats(cases[k].medium, four, cases[k].shapes, cases[k].opt, cases[k].spp, &m4, &s4,
                    &v4);
        for (int c = 0; c < 3; ++c) {
            double se = hypot(ch(s1, c), ch(s4, c));
            if (verbose())
                print_message("case %zu c%d: unsplit %.5f +- %.5f, split %.5f +- %.5f\n", k, c,
                              ch(m1, c), ch(s1, c), ch(m4, c), ch(s4, c));
            assert_true(ch(s1, c) < 0.01 * ch(m1, c));
            assert_true(fabs(ch(m4, c) - ch(m1, c)) < 4.0 * se);
        }
        if (verbose())
            print_message("case %zu: a sample's variance split / unsplit %.3f\n", k, v4 / v1);
        assert_true(v4 < 0.8 * v1);
        free(one);
        free(four);
    }
}

/* "stepsize" and "mediumsplits" are refused where they would change nothing
 * (no grid medium that can be marched; no medium at all) and out of range,
 * at their place. */
static void test_knob_refusals(void **state)
{
    (void)state;
    const char *fog = "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES
                      "/fog_sphere.vdb\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [2 6 12]";
    const char *cases[][4] = {
        {"\"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [1 1 1]",
         "\"float stepsize\" 2", "stepsize", "would change nothing"},
        {fog, "\"float stepsize\" -1", "stepsize", ">= 0"},
        {fog, "\"integer mediumsplits\" 0", "mediumsplits", "from 1"},
        {fog, "\"integer mediumsplits\" 257", "mediumsplits", "to 256"},
        {NULL, "\"integer mediumsplits\" 2", "mediumsplits", "no medium"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char *text =
            cases[k][0] ? sky_furnace(cases[k][0], cases[k][1])
                        : sfmt("LookAt 0 0 4  0 0 0  0 1 0\nCamera \"perspective\"\n"
                               "Film \"rgb\" \"integer xresolution\" 8 "
                               "\"integer yresolution\" 8\n"
                               "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                               "Integrator \"volpath\" \"integer maxdepth\" 5 %s\n"
                               "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                               "Shape \"sphere\" \"float radius\" 1\n",
                               cases[k][1]);
        char msg[1024];
        build_scene_expect_error(text, msg, sizeof msg);
        print_message("%s\n", msg);
        assert_non_null(strstr(msg, "test.pbrt:5:"));
        assert_non_null(strstr(msg, cases[k][2]));
        assert_non_null(strstr(msg, cases[k][3]));
        free(text);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grey_sky_furnace_is_exact),
        cmocka_unit_test(test_chromatic_sky_furnace),
        cmocka_unit_test(test_emitting_room_furnace),
        cmocka_unit_test(test_maxdepth_1_matches_singlescatter),
        cmocka_unit_test(test_absurd_density_is_bounded),
        cmocka_unit_test(test_cloud_solid_slab),
        cmocka_unit_test(test_rgbgrid_slab),
        cmocka_unit_test(test_splits_keep_the_mean_and_lower_the_noise),
        cmocka_unit_test(test_knob_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
