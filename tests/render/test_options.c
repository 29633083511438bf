/* pbrt-v4's Option directive: what haze honours changes the image exactly as
 * the matching command-line flag does; the rest is refused at its place. */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "render/cli_util.h"

#define DIR HAZE_TMP "/options"

static const char body[] = "LookAt 0 0 -5 0 0 0 0 1 0\nCamera \"perspective\"\n"
                           "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                           "Sampler \"zsobol\" \"integer pixelsamples\" 4\nWorldBegin\n"
                           "LightSource \"infinite\" \"rgb L\" [1 1 1]\nShape \"sphere\"\n";

/* Renders `option` + body with `flags` into DIR/NAME.exr; returns the status. */
static int render(const char *name, const char *option, const char *flags, char *out, size_t n)
{
    char path[512], text[2048], args[2048];
    snprintf(path, sizeof path, DIR "/%s.pbrt", name);
    snprintf(text, sizeof text, "%s%s", option, body);
    write_text_file(path, text);
    snprintf(args, sizeof args, "render '%s' -o '" DIR "/%s.exr' --quiet %s", path, name, flags);
    return run_haze(args, out, n);
}

static void test_honoured_options(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(render("plain", "", "", out, sizeof out), 0);
    assert_int_equal(render("flag_seed", "", "--seed 7", out, sizeof out), 0);
    assert_int_equal(render("opt_seed", "Option \"integer seed\" 7\n", "", out, sizeof out), 0);
    assert_true(exr_pixels_equal(DIR "/flag_seed.exr", DIR "/opt_seed.exr"));
    assert_false(exr_pixels_equal(DIR "/plain.exr", DIR "/opt_seed.exr"));
    /* --seed on the command line wins over the scene's Option. */
    assert_int_equal(render("both_seed", "Option \"integer seed\" 3\n", "--seed 7", out, sizeof out),
                     0);
    assert_true(exr_pixels_equal(DIR "/flag_seed.exr", DIR "/both_seed.exr"));

    assert_int_equal(render("flag_jitter", "", "--disable-pixel-jitter", out, sizeof out), 0);
    assert_int_equal(
        render("opt_jitter", "Option \"bool disablepixeljitter\" true\n", "", out, sizeof out), 0);
    assert_true(exr_pixels_equal(DIR "/flag_jitter.exr", DIR "/opt_jitter.exr"));
    assert_false(exr_pixels_equal(DIR "/plain.exr", DIR "/opt_jitter.exr"));

    /* No-ops in haze, by construction (docs/scene-format.md). */
    assert_int_equal(render("diffuse", "Option \"bool forcediffuse\" true\n", "", out, sizeof out),
                     0);
    assert_true(exr_pixels_equal(DIR "/plain.exr", DIR "/diffuse.exr"));
    assert_int_equal(
        render("world", "Option \"string rendercoordsys\" \"world\"\n", "", out, sizeof out), 0);
}

static void test_refused_options(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(render("stats", "Option \"bool pixelstats\" true\n", "", out, sizeof out), 1);
    assert_non_null(strstr(out, "stats.pbrt:1:8: Option \"pixelstats\" is not supported by haze"));
    assert_int_equal(
        render("space", "Option \"string rendercoordsys\" \"sideways\"\n", "", out, sizeof out), 1);
    assert_non_null(strstr(out, "space.pbrt:1:8: Option \"rendercoordsys\" \"sideways\" is not one"));
    assert_int_equal(render("neg", "Option \"integer seed\" -2\n", "", out, sizeof out), 1);
    assert_non_null(strstr(out, "neg.pbrt:1:8: Option \"seed\" must be >= 0"));
}

/* Sampler warnings name the Sampler's place, and concern the count used. */
static void test_sampler_warnings(void **state)
{
    (void)state;
    char out[4096];
    const char *scene = "Sampler \"zsobol\" \"integer pixelsamples\" 125\n"
                        "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                        "WorldBegin\n";
    write_text_file(DIR "/spp.pbrt", scene);
    assert_int_equal(run_haze("render '" DIR "/spp.pbrt' -o '" DIR "/spp.exr' --quiet", out,
                              sizeof out),
                     0);
    assert_non_null(
        strstr(out, "spp.pbrt:1:1: warning: sobol: 125 pixel samples rounded up to 128"));
    assert_int_equal(run_haze("render '" DIR "/spp.pbrt' -o '" DIR "/spp.exr' --quiet --spp 4",
                              out, sizeof out),
                     0);
    assert_null(strstr(out, "rounded"));
    assert_int_equal(run_haze("render '" DIR "/spp.pbrt' -o '" DIR "/spp.exr' --quiet --spp 5",
                              out, sizeof out),
                     0);
    assert_non_null(strstr(out, "warning: sobol: 5 pixel samples rounded up to 8"));
    assert_null(strstr(out, "125"));
}

/* pbrt-v4's Accelerator only sets the speed of its own BVH or kd-tree: haze
 * checks it as pbrt-v4 reads it, warns that it changes nothing, and renders
 * the image of the scene without it, bit for bit. */
static void test_accelerator(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(render("accel", "Accelerator \"kdtree\" \"integer maxprims\" 2\n", "", out,
                            sizeof out),
                     0);
    assert_non_null(strstr(out, "accel.pbrt:1:1: warning: Accelerator \"kdtree\" changes "
                                "nothing in haze"));
    assert_int_equal(render("noaccel", "", "", out, sizeof out), 0);
    assert_true(exr_pixels_equal(DIR "/accel.exr", DIR "/noaccel.exr"));
    assert_int_equal(render("accel_bad", "Accelerator \"bvh\" \"string splitmethod\" \"best\"\n",
                            "", out, sizeof out),
                     1);
    assert_non_null(strstr(out, "accel_bad.pbrt:1:19: \"splitmethod\" \"best\" is unknown"));
    assert_int_equal(render("accel_kind", "Accelerator \"octree\"\n", "", out, sizeof out), 1);
    assert_non_null(strstr(out, "accel_kind.pbrt:1:1: Accelerator \"octree\" is unknown"));
    assert_int_equal(render("accel_param", "Accelerator \"bvh\" \"integer maxprims\" 3\n", "",
                            out, sizeof out),
                     1);
    assert_non_null(strstr(out, "unused parameter \"integer maxprims\""));
}

/* --portable-isa pins Embree to SSE4.2; haze recomputes hit points in
 * double, so on one machine the widest ISA and SSE4.2 give the same pixels
 * (they may differ only where a ray grazes a shared edge). */
static void test_portable_isa(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(render("isa_native", "", "", out, sizeof out), 0);
    assert_int_equal(render("isa_portable", "", "--portable-isa", out, sizeof out), 0);
    assert_true(exr_pixels_equal(DIR "/isa_native.exr", DIR "/isa_portable.exr"));
}

int main(void)
{
    mkdir(HAZE_TMP, 0755);
    mkdir(DIR, 0755);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_honoured_options),
        cmocka_unit_test(test_refused_options),
        cmocka_unit_test(test_sampler_warnings),
        cmocka_unit_test(test_accelerator),
        cmocka_unit_test(test_portable_isa),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
