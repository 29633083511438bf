/* Integrator "volpath": selection (haze's default stays singlescatter),
 * parameters and their messages, thread-count determinism, and a scene
 * without media running no media code. */
#define _POSIX_C_SOURCE 200809L
#include "cli_util.h"
#include "media_test_util.h"

static const char *scene_body =
    "WorldBegin\n"
    "LightSource \"spot\" \"rgb I\" [6 5 4] \"point3 from\" [0 2 0] \"point3 to\" [0 0 0]\n"
    "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 3 2]\nTranslate -0.9 1.2 0.6\n"
    "Shape \"sphere\" \"float radius\" 0.2\nAttributeEnd\n"
    "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES
    "/fog_sphere.vdb\" \"rgb sigma_a\" [0.1 0.1 0.1] \"rgb sigma_s\" [4 3 2]\n"
    "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
    "Shape \"sphere\" \"float radius\" 1.1\nAttributeEnd\n"
    "Shape \"trianglemesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "
    "\"integer indices\" [0 1 2 0 2 3]\n";

static const char *camera_text =
    "LookAt 0 0.5 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
    "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 8\n";

static char *render_file(const char *name, const char *integrator, const char *args)
{
    char *scene = sfmt("%s/%s.pbrt", HAZE_TMP, name), *exr = sfmt("%s/%s.exr", HAZE_TMP, name);
    char *text = sfmt("%s%s\n%s", camera_text, integrator, scene_body);
    write_text_file(scene, text);
    char *cmd = sfmt("render '%s' --quiet -o '%s' %s", scene, exr, args);
    char out[4096];
    if (run_haze(cmd, out, sizeof out) != 0)
        fail_msg("haze %s: %s", cmd, out);
    free(cmd);
    free(text);
    free(scene);
    return exr;
}

/* Same scene and seed: the same bytes on one thread and on two. */
static void test_threads_byte_identical(void **state)
{
    (void)state;
    const char *vp = "Integrator \"volpath\" \"integer maxdepth\" 8";
    char *a = render_file("volpath_t1", vp, "--threads 1");
    char *b = render_file("volpath_t2", vp, "--threads 2");
    assert_true(files_equal(a, b));
    free(a);
    free(b);
}

/* A scene naming no Integrator renders exactly as "singlescatter". */
static void test_default_is_singlescatter(void **state)
{
    (void)state;
    char *a = render_file("default_integrator", "", "--threads 2");
    char *b = render_file("named_singlescatter", "Integrator \"singlescatter\"", "--threads 2");
    char *c = render_file("named_volpath", "Integrator \"volpath\"", "--threads 2");
    assert_true(files_equal(a, b));
    assert_false(files_equal(a, c));
    free(a);
    free(b);
    free(c);
}

/* Builds `text` with warnings captured; returns the status and fills msg with
 * the error or the warnings. */
static hz_status build_with_warnings(const char *text, char *msg, size_t n)
{
    scene_desc sd;
    hz_error err = {{0}};
    assert_int_equal(scene_parse_string(text, "test.pbrt", &sd, &err), HZ_OK);
    FILE *warn = tmpfile();
    assert_non_null(warn);
    render_options def = {.seed = 0};
    render_scene *rs = NULL;
    hz_status st = render_scene_create(&sd, &def, warn, &rs, &err);
    scene_desc_free(&sd);
    render_scene_destroy(rs);
    if (st != HZ_OK) {
        snprintf(msg, n, "%s", err.message);
    } else {
        rewind(warn);
        size_t got = fread(msg, 1, n - 1, warn);
        msg[got] = '\0';
    }
    fclose(warn);
    return st;
}

static void test_parameters(void **state)
{
    (void)state;
    char msg[1024];
    assert_int_equal(build_with_warnings("Integrator \"volpath\" \"string lightsampler\" \"bvh\"\n"
                                         "WorldBegin\n",
                                         msg, sizeof msg),
                     HZ_OK);
    assert_string_equal(msg, "test.pbrt:1:22: warning: Integrator \"volpath\" \"lightsampler\" "
                             "\"bvh\" is not supported; using \"power\"\n");
    /* The default (bvh in pbrt-v4) is haze's power sampler, without a warning. */
    assert_int_equal(build_with_warnings("Integrator \"volpath\" \"bool regularize\" true\n"
                                         "WorldBegin\n",
                                         msg, sizeof msg),
                     HZ_OK);
    assert_string_equal(msg, "");
    assert_int_equal(build_with_warnings("Integrator \"volpath\"\n"
                                         "  \"string lightsampler\" \"nearest\"\nWorldBegin\n",
                                         msg, sizeof msg),
                     HZ_ERROR);
    assert_string_equal(msg, "test.pbrt:2:3: \"lightsampler\" \"nearest\" is not one of "
                             "\"uniform\", \"power\", \"bvh\", \"exhaustive\"");
    assert_int_equal(build_with_warnings("Integrator \"volpath\" \"integer maxdepth\" -1\n"
                                         "WorldBegin\n",
                                         msg, sizeof msg),
                     HZ_ERROR);
    assert_string_equal(msg, "test.pbrt:1:22: \"maxdepth\" must be >= 0");
}

/* Surfaces only: the media counters stay at zero, even timed. */
static void test_no_media_no_media_code(void **state)
{
    (void)state;
    render_scene *rs = build(
        "LookAt 0 0.5 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
        "Integrator \"volpath\"\nWorldBegin\n"
        "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [0 2 -1]\n"
        "LightSource \"infinite\" \"rgb L\" [0.2 0.2 0.2]\n"
        "Shape \"sphere\" \"float radius\" 0.8\n"
        "Shape \"trianglemesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "
        "\"integer indices\" [0 1 2 0 2 3]\n");
    const camera *cam = render_scene_camera(rs);
    render_counters c = {.timed = true};
    sampler smp = *render_scene_sampler(rs);
    rgb sum = rgb_grey(0.0);
    for (int i = 0; i < 64; ++i) {
        camera_sample cs = {v2(560.0 + i % 8 * 20.0, 300.0 + i / 8 * 20.0), v2(0.5, 0.5), 0.5,
                              1.0};
        ray_differential rd;
        assert_true(camera_generate_ray_differential(cam, cs, &rd));
        sampler_state st;
        sampler_start(&smp, i % 8, i / 8, 0, &st);
        double depth;
        sum = rgb_add(sum, render_scene_li(rs, &rd, &st, &depth, &c));
    }
    assert_true(sum.r > 0.0);
    assert_true(c.shadow_rays > 0);
    assert_int_equal(c.density_lookups, 0);
    assert_int_equal(c.majorant_steps, 0);
    assert_int_equal(c.media_ns, 0);
    render_scene_destroy(rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_byte_identical),
        cmocka_unit_test(test_default_is_singlescatter),
        cmocka_unit_test(test_parameters),
        cmocka_unit_test(test_no_media_no_media_code),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
