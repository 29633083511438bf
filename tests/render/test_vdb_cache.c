/* The cache of converted .vdb grids (media/vdb_cache.h): a second render of
 * the same .vdb file reads its grids from the cache without the reader
 * process (it runs with no reader at all) and writes the same pixels; an
 * entry that fails to load is converted again and rewritten; a changed file
 * gets entries of its own; HAZE_CACHE_DIR="" turns the cache off; a cache
 * directory that cannot be made costs nothing but the cache. */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "render/cli_util.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

static char dir[1024], cache[1100], scene[1100];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "%s/vdb_cache-%ld", HAZE_TMP, (long)getpid());
    snprintf(cache, sizeof cache, "%s/cache", dir);
    snprintf(scene, sizeof scene, "%s/box.pbrt", dir);
    if (mkdir(dir, 0755) != 0)
        return -1;
    char text[2048];
    snprintf(text, sizeof text,
             "LookAt 0.5 0.5 -3  0.5 0.5 0.5  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
             "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 4\nIntegrator \"singlescatter\"\n"
             "WorldBegin\n"
             "LightSource \"distant\" \"point3 from\" [0 4 0] \"rgb L\" [3 3 3]\n"
             "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"%s/grid.vdb\"\n"
             "  \"rgb sigma_s\" [2 2 2] \"rgb sigma_a\" [0.5 0.5 0.5]\n"
             "MediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
             "Translate 0.5 0.5 0.5\nShape \"sphere\" \"float radius\" 1\n",
             dir);
    write_text_file(scene, text);
    return 0;
}

static void copy_file(const char *from, const char *to)
{
    size_t n = 0;
    unsigned char *b = read_whole_file(from, &n);
    assert_non_null(b);
    FILE *f = fopen(to, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
    free(b);
}

/* Renders the scene with the environment `env` (a shell prefix) into NAME.exr. */
static int render(const char *env, const char *name, char *out, size_t n)
{
    char args[4096];
    snprintf(args, sizeof args, "render '%s' -o '%s/%s.exr' --quiet", scene, dir, name);
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "%s '%s' %s 2>&1", env, HAZE_BIN, args);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t got = fread(out, 1, n - 1, p);
    out[got] = '\0';
    int status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* The two renders' images have the same pixels. */
static bool same_image(const char *a, const char *b)
{
    char pa[1200], pb[1200];
    snprintf(pa, sizeof pa, "%s/%s.exr", dir, a);
    snprintf(pb, sizeof pb, "%s/%s.exr", dir, b);
    return exr_pixels_equal(pa, pb);
}

/* The one .nvdb entry of the cache directory (its path into out). */
static int nvdb_entries(char *out, size_t n)
{
    DIR *d = opendir(cache);
    if (!d)
        return 0;
    int count = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        size_t len = strlen(e->d_name);
        if (len > 5 && strcmp(e->d_name + len - 5, ".nvdb") == 0) {
            snprintf(out, n, "%s/%s", cache, e->d_name);
            count++;
        }
    }
    closedir(d);
    return count;
}

static void test_second_render_reads_the_cache(void **state)
{
    (void)state;
    char env[2048], out[4096], entry[1400];
    char grid[1200];
    snprintf(grid, sizeof grid, "%s/grid.vdb", dir);
    copy_file(VOLUMES "box.vdb", grid);
    snprintf(env, sizeof env, "HAZE_CACHE_DIR='%s'", cache);
    assert_int_equal(render(env, "first", out, sizeof out), 0);
    assert_int_equal(nvdb_entries(entry, sizeof entry), 1);
    /* No reader at all: the grid can only come from the cache. */
    snprintf(env, sizeof env, "HAZE_CACHE_DIR='%s' HAZE_VDB_READER=/nonexistent", cache);
    assert_int_equal(render(env, "second", out, sizeof out), 0);
    assert_true(same_image("first", "second"));
    /* Without the cache the same pixels, and the reader is needed. */
    assert_int_equal(render("HAZE_CACHE_DIR=", "uncached", out, sizeof out), 0);
    assert_true(same_image("first", "uncached"));
    assert_int_equal(render("HAZE_CACHE_DIR= HAZE_VDB_READER=/nonexistent", "noreader", out,
                            sizeof out),
                     1);

    /* A broken entry (cut short) is converted again and rewritten. */
    struct stat st;
    assert_int_equal(stat(entry, &st), 0);
    assert_int_equal(truncate(entry, st.st_size / 2), 0);
    snprintf(env, sizeof env, "HAZE_CACHE_DIR='%s'", cache);
    assert_int_equal(render(env, "repaired", out, sizeof out), 0);
    assert_true(same_image("first", "repaired"));
    struct stat st2;
    assert_int_equal(stat(entry, &st2), 0);
    assert_int_equal(st2.st_size, st.st_size);

    /* Another file under the same name: entries of its own, its own image. */
    copy_file(VOLUMES "fog_sphere.vdb", grid);
    assert_int_equal(render(env, "changed", out, sizeof out), 0);
    assert_int_equal(nvdb_entries(entry, sizeof entry), 2);
    assert_int_equal(render("HAZE_CACHE_DIR=", "changed_uncached", out, sizeof out), 0);
    assert_true(same_image("changed", "changed_uncached"));
    assert_false(same_image("first", "changed"));
}

static void test_unusable_cache_dir(void **state)
{
    (void)state;
    char blocker[1200], env[2048], out[4096];
    snprintf(blocker, sizeof blocker, "%s/blocker", dir);
    write_text_file(blocker, "a file where the cache directory would go\n");
    snprintf(env, sizeof env, "HAZE_CACHE_DIR='%s/sub'", blocker);
    assert_int_equal(render(env, "blocked", out, sizeof out), 0);
    assert_string_equal(out, "");
    assert_int_equal(render("HAZE_CACHE_DIR=", "blocked_ref", out, sizeof out), 0);
    assert_true(same_image("blocked", "blocked_ref"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_second_render_reads_the_cache),
        cmocka_unit_test(test_unusable_cache_dir),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
