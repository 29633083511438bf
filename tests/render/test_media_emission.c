/* Emitting media: closed forms of absorbing emission (the source term is
 * sigma_a Le, as pbrt-v4) under both integrators, and what does not glow. */
#include "media_test_util.h"

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

/* Mean and standard error over the image's pixels. */
static void image_mean(render_scene *rs, int spp, rgb *mean, rgb *se)
{
    pstat *px = image_stats(rs, 4, 4, spp);
    double m[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int i = 0; i < 16; ++i)
        for (int c = 0; c < 3; ++c) {
            m[c] += ch(px[i].mean, c) / 16;
            v[c] += ch(px[i].se, c) * ch(px[i].se, c) / 256;
        }
    free(px);
    *mean = rgb_make(m[0], m[1], m[2]);
    *se = rgb_make(sqrt(v[0]), sqrt(v[1]), sqrt(v[2]));
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
    for (int c = 0; c < 3; ++c) {
        if (verbose())
            print_message("volpath slab c%d: %.5f +- %.5f, want %.5f\n", c, ch(mean, c),
                          ch(se, c), ch(want, c));
        assert_true(ch(se, c) < 0.01 * ch(want, c));
        assert_true(fabs(ch(mean, c) - ch(want, c)) < 4.0 * ch(se, c));
    }
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
        pstat p = pixel_stats_raw(rs, 1, 1, 64);
        expect_rgb_close(p.mean, rgb_make(3, 2, 1), k == 0 ? 1e-9 : 0.05, 1e-9, "unbounded", k,
                         0);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_homogeneous_slab),
        cmocka_unit_test(test_unbounded_and_dark),
        cmocka_unit_test(test_parameters),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
