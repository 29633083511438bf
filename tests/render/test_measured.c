/* Material "measured" in whole scenes, under both integrators: a plane of a
 * measured BRDF (tests/bsdf/make_bsdf.c's files) renders within noise of
 * the analytic material the file was made from, and a measured file that
 * cannot be used is refused at its scene place. */
#include "media_test_util.h"

#define BSDF(name) HAZE_TEST_BSDF "/" name

/* An orthographic camera (straight down, or oblique) looks at a plane of
 * `material` lit by `light`, rendered by `integrator`. */
static char *plane_scene(bool oblique, const char *integrator, const char *light,
                         const char *material)
{
    return sfmt("LookAt %s  0 0 0  0 %s\nCamera \"orthographic\"\n"
                "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\nWorldBegin\n%s\n%s\n"
                "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                "\"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10]\n",
                oblique ? "0 5 -3" : "0 5 0", oblique ? "1 0" : "0 1", integrator, light,
                material);
}

static const char *const integrators[2] = {"Integrator \"volpath\" \"integer maxdepth\" 5",
                                           "Integrator \"singlescatter\""};
static const char *const sky = "LightSource \"infinite\" \"rgb L\" [1 1 1]";

static void render_mean(bool oblique, int integ, const char *light, const char *material,
                        int spp, rgb *mean, rgb *se)
{
    char *text = plane_scene(oblique, integrators[integ], light, material);
    render_scene *rs = build(text);
    image_mean_se(rs, 4, 4, spp, mean, se);
    render_scene_destroy(rs);
    free(text);
}

/* Under a uniform sky of radiance 1 a plane seen head-on returns its
 * albedo: the measured Lambertians give the diffuse material's, grey and
 * coloured (the albedo spectrum as haze reduces a reflectance spectrum). */
static void test_lambert_furnace(void **state)
{
    (void)state;
    const char *pairs[2][2] = {
        {"Material \"measured\" \"string filename\" \"" BSDF("lambert.bsdf") "\"",
         "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]"},
        {"Material \"measured\" \"string filename\" \"" BSDF("lambert-colour.bsdf") "\"",
         "Material \"diffuse\" \"spectrum reflectance\" [360 0.1 400 0.1 500 0.3 600 0.6 700 "
         "0.8 830 0.8]"},
    };
    for (int k = 0; k < 2; ++k)
        for (int i = 0; i < 2; ++i) {
            rgb m, mse, d, dse;
            render_mean(false, i, sky, pairs[k][0], 256, &m, &mse);
            render_mean(false, i, sky, pairs[k][1], 256, &d, &dse);
            print_message("%s %s: measured %.5f %.5f %.5f (+- %.5f), diffuse %.5f %.5f %.5f "
                          "(+- %.5f)\n",
                          k ? "colour" : "grey", i ? "singlescatter" : "volpath", m.r, m.g, m.b,
                          mse.g, d.r, d.g, d.b, dse.g);
            for (int c = 0; c < 3; ++c) {
                double noise = sqrt(ch(mse, c) * ch(mse, c) + ch(dse, c) * ch(dse, c));
                assert_true(ch(m, c) > 0.05);
                assert_true(fabs(ch(m, c) - ch(d, c)) < 4.0 * noise + 0.003 * ch(d, c));
            }
        }
}

/* The measured rough conductor against the conductor it was made from
 * (alpha 0.3: roughness 0.09 remapped; eta 1 and k 4: reflectance 0.8),
 * seen obliquely: under the sky (its albedo there) and under a distant
 * light at the mirror direction and off it (f itself), by both
 * integrators. */
static void test_ggx_conductor(void **state)
{
    (void)state;
    const char *measured = "Material \"measured\" \"string filename\" \"" BSDF("ggx.bsdf") "\"";
    const char *analytic = "Material \"conductor\" \"rgb reflectance\" [0.8 0.8 0.8] "
                           "\"float roughness\" 0.09";
    const char *lights[3] = {sky,
                             "LightSource \"distant\" \"point3 from\" [0 5 3] \"point3 to\" "
                             "[0 0 0] \"rgb L\" [2 2 2]",
                             "LightSource \"distant\" \"point3 from\" [2 5 1] \"point3 to\" "
                             "[0 0 0] \"rgb L\" [2 2 2]"};
    const double tol[3] = {0.01, 0.03, 0.03};
    for (int l = 0; l < 3; ++l)
        for (int i = 0; i < 2; ++i) {
            rgb m, mse, a, ase;
            render_mean(true, i, lights[l], measured, l ? 4 : 256, &m, &mse);
            render_mean(true, i, lights[l], analytic, l ? 4 : 256, &a, &ase);
            print_message("light %d, %s: measured %.5f (+- %.5f), analytic %.5f (+- %.5f): "
                          "%+.2f%%\n",
                          l, i ? "singlescatter" : "volpath", m.g, mse.g, a.g, ase.g,
                          100.0 * (m.g / a.g - 1.0));
            double noise = sqrt(mse.g * mse.g + ase.g * ase.g);
            assert_true(m.g > 0.05 && m.r == m.g && m.b == m.g);
            assert_true(fabs(m.g - a.g) < 4.0 * noise + tol[l] * a.g);
        }
}

/* A named measured material, and two materials of one file. */
static void test_named_and_shared(void **state)
{
    (void)state;
    const char *mat = "MakeNamedMaterial \"a\" \"string type\" \"measured\" \"string filename\" \""
                      BSDF("lambert.bsdf") "\"\nMaterial \"measured\" \"string filename\" \""
                      BSDF("lambert.bsdf") "\"\nNamedMaterial \"a\"";
    rgb m, se;
    render_mean(false, 0, sky, mat, 64, &m, &se);
    assert_true(fabs(m.g - 0.5) < 4.0 * se.g + 0.003);
}

/* A scene naming no Integrator renders pbrt-v4's default, volpath, and
 * says so, as for the other glossy materials. */
static void test_default_integrator(void **state)
{
    (void)state;
    const char *text = "WorldBegin\nMaterial \"measured\" \"string filename\" \""
                       BSDF("ggx.bsdf") "\"\nShape \"sphere\"\n";
    scene_desc sd;
    hz_error err = {0};
    assert_int_equal(scene_parse_string(text, "test.pbrt", &sd, &err), HZ_OK);
    FILE *warn = tmpfile();
    assert_non_null(warn);
    render_options def = {.seed = 0, .color = RENDER_COLOR_RGB};
    render_scene *rs = NULL;
    assert_int_equal(render_scene_create(&sd, &def, warn, &rs, &err), HZ_OK);
    rewind(warn);
    char msg[1024];
    size_t got = fread(msg, 1, sizeof msg - 1, warn);
    msg[got] = '\0';
    fclose(warn);
    assert_non_null(strstr(msg, "has a \"measured\" material, which only \"volpath\" renders"));
    render_scene_destroy(rs);
    scene_desc_free(&sd);
}

static void expect_error(const char *material, const char *want)
{
    char *text = plane_scene(false, integrators[0], sky, material);
    char msg[1024];
    build_scene_expect_error(text, msg, sizeof msg);
    print_message("%s\n", msg);
    if (!strstr(msg, want) || !strstr(msg, "test.pbrt:8:"))
        fail_msg("want \"%s\": %s", want, msg);
    free(text);
}

static void test_refused(void **state)
{
    (void)state;
    expect_error("Material \"measured\"", "Material \"measured\" needs \"string filename\"");
    expect_error("Material \"measured\" \"string filename\" \"" HAZE_TMP "/none.bsdf\"",
                 "none.bsdf: No such file or directory");
    expect_error("Material \"measured\" \"string filename\" \"" BSDF("lambert.bsdf")
                 "\" \"float roughness\" 0.1",
                 "unused parameter \"float roughness\" for Material \"measured\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lambert_furnace),
        cmocka_unit_test(test_ggx_conductor),
        cmocka_unit_test(test_named_and_shared),
        cmocka_unit_test(test_default_integrator),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
