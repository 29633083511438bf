/* Small stand-ins of pbrt-v4-scenes files (tests/standins, README there):
 * the same directives, parameters and structure as the published scenes,
 * with generated data (haze's test volumes, a generated sky map) under the
 * file names the scenes use. Each must render with `haze render` as it is:
 * exit 0, no error, every pixel finite, a lit image, and, for the media
 * scenes, density lookups (the medium is really marched). */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include <string.h>

#include "render/cli_util.h"
#include "standins/standin_textures.h"

#define STANDINS HAZE_TESTS "/standins"
#define VOLUMES HAZE_SCENES "/../volumes"

static char dir[1024];

static void copy_file(const char *from, const char *to)
{
    size_t n = 0;
    unsigned char *b = read_whole_file(from, &n);
    if (!b)
        fail_msg("cannot read %s", from);
    FILE *f = fopen(to, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
    free(b);
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "%s/standins", HAZE_TMP);
    /* A fresh scratch directory each run (the last one stays for a look). */
    char rm[1200];
    snprintf(rm, sizeof rm, "rm -rf '%s'", dir);
    if (system(rm) != 0)
        return -1;
    char sub[1200];
    if (mkdir(dir, 0755) != 0)
        return -1;
    snprintf(sub, sizeof sub, "%s/textures", dir);
    if (mkdir(sub, 0755) != 0)
        return -1;
    snprintf(sub, sizeof sub, "%s/geometry", dir);
    return mkdir(sub, 0755);
}

/* The scene files and the data they name, under the names they use. */
static void stage(void)
{
    static const char *files[] = {
        "bunny-cloud.pbrt",      "explosion.pbrt",         "disney-cloud.pbrt",
        "clouds.pbrt",           "killeroo-simple.pbrt",   "geometry/creature.pbrt",
        "sanmiguel-courtyard.pbrt", "geometry/courtyard-mat.pbrt",
        "geometry/courtyard-geom.pbrt", "crown.pbrt", "geometry/gem.ply",
        "hair-eumel-2.pbrt", "geometry/straight-hair.pbrt.gz",
        "contemporary-bathroom.pbrt", "geometry/bathroom-materials.pbrt",
        "villa-daylight.pbrt", "geometry/villa-materials.pbrt",
        "kroken.pbrt", "geometry/kroken-lights.pbrt", "geometry/kroken-materials.pbrt"};
    static const char *data[][2] = {{"box.nvdb", "bunny_cloud.nvdb"},
                                    {"box.nvdb", "wdas_cloud_quarter.nvdb"},
                                    {"box_fire.nvdb", "fire.nvdb"}};
    char from[1400], to[1400];
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        snprintf(from, sizeof from, STANDINS "/%s", files[i]);
        snprintf(to, sizeof to, "%s/%s", dir, files[i]);
        copy_file(from, to);
    }
    for (size_t i = 0; i < sizeof data / sizeof data[0]; ++i) {
        snprintf(from, sizeof from, VOLUMES "/%s", data[i][0]);
        snprintf(to, sizeof to, "%s/%s", dir, data[i][1]);
        copy_file(from, to);
    }
    hz_error err = {0};
    if (standin_textures_write(dir, &err) != HZ_OK)
        fail_msg("%s", err.message);
}

/* The value of "stat NAME" in haze's --stats output (-1 when absent). */
static double stat_value(const char *out, const char *name)
{
    char key[96];
    snprintf(key, sizeof key, "stat %s ", name);
    const char *p = strstr(out, key);
    return p ? atof(p + strlen(key)) : -1.0;
}

/* Renders `scene` from the staged directory and checks its image: every
 * pixel finite, the mean luminance above `min_mean`; media scenes must
 * have looked up their density. */
static void render_standin(const char *scene, bool media, double min_mean)
{
    char args[4096], out[16384], exr[1400];
    snprintf(exr, sizeof exr, "%s/%s.exr", dir, scene);
    snprintf(args, sizeof args, "render '%s/%s.pbrt' -o '%s' --quiet --stats --threads 2", dir,
             scene, exr);
    int status = run_haze(args, out, sizeof out);
    print_message("%s: exit %d\n%s", scene, status, out);
    assert_int_equal(status, 0);
    assert_null(strstr(out, "error"));
    exr_image img;
    hz_error err;
    assert_int_equal(exr_read(exr, &img, &err), HZ_OK);
    const exr_channel *ch[3] = {exr_find_channel(&img, "R"), exr_find_channel(&img, "G"),
                                exr_find_channel(&img, "B")};
    assert_true(ch[0] && ch[1] && ch[2]);
    size_t n = (size_t)img.width * (size_t)img.height;
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            float v = ch[c]->pixels[i];
            /* A camera sensor's matrix can make saturated colours
             * (firelight) negative in a channel, as in pbrt-v4. */
            if (!isfinite(v))
                fail_msg("%s: pixel %zu channel %d is %g", scene, i, c, (double)v);
            sum += v / 3.0;
        }
    exr_image_free(&img);
    double mean = sum / (double)n;
    print_message("%s: mean %.4g\n", scene, mean);
    assert_true(mean > min_mean);
    if (media)
        assert_true(stat_value(out, "density_lookups_per_pixel") > 0.0 ||
                    stat_value(out, "majorant_steps_per_pixel") > 0.0);
}

static void test_media_scenes(void **state)
{
    (void)state;
    stage();
    render_standin("bunny-cloud", true, 0.05);
    render_standin("explosion", true, 0.05);
    render_standin("disney-cloud", true, 0.01);
    render_standin("clouds", true, 0.05);
}

static void test_surface_scenes(void **state)
{
    (void)state;
    render_standin("killeroo-simple", false, 0.001);
    render_standin("sanmiguel-courtyard", false, 0.01);
    render_standin("crown", false, 0.001);
    render_standin("hair-eumel-2", false, 0.001);
    render_standin("contemporary-bathroom", false, 0.01);
    render_standin("villa-daylight", false, 0.01);
    render_standin("kroken", false, 0.01);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_media_scenes),
        cmocka_unit_test(test_surface_scenes),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
