#define _POSIX_C_SOURCE 200809L
/* The command line as users meet it: exit codes, one-line errors with
 * file:line:column, outputs, and thread-count independence. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "cli_util.h"
#include "film/exr.h"

#include <unistd.h>

static const char small_scene[] =
    "LookAt 0 1 -3  0 0.5 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 50\n"
    "Film \"rgb\" \"integer xresolution\" 48 \"integer yresolution\" 32\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
    "WorldBegin\n"
    "LightSource \"point\" \"point3 from\" [1 2 -1] \"rgb I\" [3 3 3]\n"
    "AttributeBegin\n"
    "  AreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n"
    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2]\n"
    "    \"point3 P\" [-0.5 1.5 0.5  0.5 1.5 0.5  0 1.5 1]\n"
    "AttributeEnd\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]\n"
    "Shape \"sphere\" \"float radius\" 0.4\n";

static char scene_path[1024];

static int setup(void **state)
{
    (void)state;
    snprintf(scene_path, sizeof scene_path, "%s/cli_small.pbrt", HAZE_TMP);
    write_text_file(scene_path, small_scene);
    return 0;
}

static void test_version_and_help(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(run_haze("--version", out, sizeof out), 0);
    assert_non_null(strstr(out, "haze "));
    assert_int_equal(run_haze("--help", out, sizeof out), 0);
    assert_non_null(strstr(out, "haze render"));
}

static void test_usage_errors_exit_2(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(run_haze("", out, sizeof out), 2);
    assert_int_equal(run_haze("frobnicate", out, sizeof out), 2);
    assert_int_equal(run_haze("render", out, sizeof out), 2);
    assert_int_equal(run_haze("render x.pbrt --spp", out, sizeof out), 2);
    assert_int_equal(run_haze("render x.pbrt --spp zero", out, sizeof out), 2);
    assert_non_null(strstr(out, "--spp"));
    assert_int_equal(run_haze("render x.pbrt --threads 0", out, sizeof out), 2);
    assert_int_equal(run_haze("render x.pbrt --bogus", out, sizeof out), 2);
    assert_non_null(strstr(out, "--bogus"));
}

static void test_missing_scene_exit_1(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(run_haze("render /nonexistent/nothing.pbrt", out, sizeof out), 1);
    assert_non_null(strstr(out, "nothing.pbrt"));
}

static void test_scene_error_names_place(void **state)
{
    (void)state;
    char path[1024], args[2048], out[4096], expect[1200];
    snprintf(path, sizeof path, "%s/cli_bad.pbrt", HAZE_TMP);
    write_text_file(path, "Camera \"perspective\"\nWorldBegin\n  Shpe \"sphere\"\n");
    snprintf(args, sizeof args, "render '%s' -o '%s/bad.exr'", path, HAZE_TMP);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    snprintf(expect, sizeof expect, "%s:3:3:", path);
    assert_non_null(strstr(out, expect));
    /* One line. */
    assert_non_null(strchr(out, '\n'));
    assert_null(strchr(strchr(out, '\n') + 1, '\n'));

    /* Unused parameter: named with its place. */
    write_text_file(path, "Camera \"perspective\" \"float fvo\" 30\nWorldBegin\n");
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    snprintf(expect, sizeof expect, "%s:1:22:", path);
    assert_non_null(strstr(out, expect));
    assert_non_null(strstr(out, "fvo"));
}

/* The same scene and seed give the same image for any thread count: surfaces,
 * and both kinds of media (their random walks draw from per-sample streams).
 * Compared as what the files hold (every channel's pixels bit for bit, the
 * header's attributes), not as bytes: once in about 200 renders here one
 * chunk's zlib stream came out encoded differently for the same bytes (its
 * inflated bytes equal; igzip replays the other encoding every time). */
static void expect_threads_bit_identical(const char *scene, const char *extra)
{
    char a[1024], b[1024], args[4096], out[4096];
    snprintf(a, sizeof a, "%s/cli_t1.exr", HAZE_TMP);
    snprintf(b, sizeof b, "%s/cli_t2.exr", HAZE_TMP);
    snprintf(args, sizeof args, "render '%s' -o '%s' --threads 1 --quiet %s", scene, a, extra);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "render '%s' -o '%s' --threads 2 --quiet %s", scene, b, extra);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    exr_image ia, ib;
    hz_error err;
    assert_int_equal(exr_read(a, &ia, &err), HZ_OK);
    assert_int_equal(exr_read(b, &ib, &err), HZ_OK);
    assert_int_equal(ia.width, ib.width);
    assert_int_equal(ia.height, ib.height);
    assert_int_equal(ia.channel_count, ib.channel_count);
    size_t npix = (size_t)ia.width * (size_t)ia.height;
    assert_true(npix * (size_t)ia.channel_count > 250);
    for (int c = 0; c < ia.channel_count; ++c) {
        assert_string_equal(ia.channels[c].name, ib.channels[c].name);
        assert_memory_equal(ia.channels[c].pixels, ib.channels[c].pixels, npix * sizeof(float));
    }
    assert_int_equal(ia.attribute_count, ib.attribute_count);
    for (int k = 0; k < ia.attribute_count; ++k) {
        assert_string_equal(ia.attribute_names[k], ib.attribute_names[k]);
        assert_string_equal(ia.attribute_values[k], ib.attribute_values[k]);
    }
    exr_image_free(&ia);
    exr_image_free(&ib);
}

static void test_threads_bit_identical(void **state)
{
    (void)state;
    expect_threads_bit_identical(scene_path, "");
    expect_threads_bit_identical(HAZE_SCENES "/smoke.pbrt", "--spp 1");
    expect_threads_bit_identical(HAZE_SCENES "/foggy-dof.pbrt", "--spp 1");
    expect_threads_bit_identical(HAZE_SCENES "/camera-pan.pbrt", "--spp 1"); /* motion blur */
    /* volpath with its knobs: split paths (each copy's own scramble and
     * stream), marched grid media, the shadow cache's columns built on
     * whichever thread reaches them first. */
    char path[1024];
    snprintf(path, sizeof path, "%s/cli_volpath_knobs.pbrt", HAZE_TMP);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "LookAt 0 0.3 4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 35\n"
            "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
            "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
            "Integrator \"volpath\" \"integer maxdepth\" 20 \"integer mediumsplits\" 3 "
            "\"float stepsize\" 2 \"float shadowcache\" 1\n"
            "WorldBegin\n"
            "LightSource \"distant\" \"point3 from\" [-1 2 1] \"point3 to\" [0 0 0] "
            "\"rgb L\" [3 3 3]\n"
            "LightSource \"infinite\" \"rgb L\" [0.2 0.3 0.4]\n"
            "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" "
            "\"%s/../volumes/fog_sphere.vdb\" \"rgb sigma_a\" [0.1 0.1 0.1] "
            "\"rgb sigma_s\" [4 4 4] \"float g\" 0.5\n"
            "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
            "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
            HAZE_SCENES);
    assert_int_equal(fclose(f), 0);
    expect_threads_bit_identical(path, "");
}

static void test_output_dir_missing_exit_1(void **state)
{
    (void)state;
    char args[4096], out[4096];
    snprintf(args, sizeof args, "render '%s' -o /nonexistent-dir/x.exr --quiet", scene_path);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "/nonexistent-dir"));
}

static void test_summary_and_preview(void **state)
{
    (void)state;
    char exr[1024], png[1024], args[4096], out[8192];
    snprintf(exr, sizeof exr, "%s/cli_sum.exr", HAZE_TMP);
    snprintf(png, sizeof png, "%s/cli_sum.png", HAZE_TMP);
    unlink(png);
    snprintf(args, sizeof args, "render '%s' -o '%s' --preview '%s' --spp 2", scene_path, exr, png);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "48x32"));
    assert_non_null(strstr(out, "2 spp"));
    assert_non_null(strstr(out, "Mrays/s"));
    assert_non_null(strstr(out, "peak memory"));
    size_t n;
    unsigned char *d = read_whole_file(png, &n);
    assert_non_null(d);
    assert_true(n > 8);
    assert_memory_equal(d, "\x89PNG", 4);
    free(d);
}

/* An emitter whose edge falls inside a pixel column: the pixel-centre
 * quantity is exactly L or 0 in every pixel, whatever the sample count. */
static const char edge_scene[] =
    "LookAt 0 0 0  0 0 1  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 40\n"
    "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 8\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 8\n"
    "WorldBegin\n"
    "AreaLightSource \"diffuse\" \"rgb L\" [0.75 0.75 0.75]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-100 -100 5  -100 100 5  0.1371 100 5  0.1371 -100 5]\n";

/* Counts pixels of R that are neither 0 nor exactly 0.75. */
static int count_partial_pixels(const char *exr_path)
{
    exr_image img;
    hz_error err = {0};
    assert_int_equal(exr_read(exr_path, &img, &err), HZ_OK);
    int partial = -1;
    for (int c = 0; c < img.channel_count; ++c)
        if (!strcmp(img.channels[c].name, "R")) {
            partial = 0;
            for (int i = 0; i < img.width * img.height; ++i) {
                float v = img.channels[c].pixels[i];
                partial += v != 0.0f && v != 0.75f;
            }
        }
    exr_image_free(&img);
    return partial;
}

static void test_disable_pixel_jitter(void **state)
{
    (void)state;
    char scene[1024], exr[1024], args[4096], out[4096];
    snprintf(scene, sizeof scene, "%s/cli_edge.pbrt", HAZE_TMP);
    snprintf(exr, sizeof exr, "%s/cli_edge.exr", HAZE_TMP);
    write_text_file(scene, edge_scene);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet", scene, exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_true(count_partial_pixels(exr) >= 8); /* anti-aliased: the edge column is grey */
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet --disable-pixel-jitter", scene, exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_int_equal(count_partial_pixels(exr), 0);
}

/* --stats: the figures are there and add up (every camera ray counted). */
static void test_stats(void **state)
{
    (void)state;
    char exr[1024], args[4096], out[8192];
    snprintf(exr, sizeof exr, "%s/cli_stats.exr", HAZE_TMP);
    snprintf(args, sizeof args, "render '%s' -o '%s' --spp 4 --stats", scene_path, exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    const char *names[] = {"wall_s", "camera_rays", "shadow_rays", "density_lookups_per_pixel",
                           "majorant_steps_per_pixel", "time_surfaces_s", "time_media_s",
                           "time_film_s", "memory_peak_mib", "memory_film_mib",
                           "memory_embree_mib", "memory_grids_mib"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        char key[128];
        snprintf(key, sizeof key, "stat %s ", names[i]);
        assert_non_null(strstr(out, key));
    }
    assert_non_null(strstr(out, "stat camera_rays 6144\n")); /* 48 x 32 x 4 */
    assert_non_null(strstr(out, "stat density_lookups_per_pixel 0.00\n"));
    assert_non_null(strstr(out, "stat time_pilot_s 0.0000\n")); /* no --target-error */
    /* no medium: nothing built on demand, and no pilot to build it */
    assert_non_null(strstr(out, "stat majorant_bricks_built 0\n"));
    assert_non_null(strstr(out, "stat pilot_majorant_bricks_built 0\n"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_version_and_help),
        cmocka_unit_test(test_usage_errors_exit_2),
        cmocka_unit_test(test_missing_scene_exit_1),
        cmocka_unit_test(test_scene_error_names_place),
        cmocka_unit_test(test_threads_bit_identical),
        cmocka_unit_test(test_output_dir_missing_exit_1),
        cmocka_unit_test(test_summary_and_preview),
        cmocka_unit_test(test_disable_pixel_jitter),
        cmocka_unit_test(test_stats),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
