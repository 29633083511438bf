/* The bad-input corpus (tests/bad-input): every malformed scene or file makes
 * haze exit with the status its first line expects ("# expect: STATUS TEXT"),
 * print exactly one line that contains TEXT and names the place, and leave an
 * existing good output file untouched. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "render/cli_util.h"

#define CORPUS HAZE_TESTS "/bad-input"

static const char good_bytes[] = "a good image that a failed run must not replace\n";

static void write_good_output(const char *path) { write_text_file(path, good_bytes); }

static void assert_good_output_kept(const char *path)
{
    size_t n = 0;
    unsigned char *b = read_whole_file(path, &n);
    assert_non_null(b);
    assert_int_equal(n, strlen(good_bytes));
    assert_memory_equal(b, good_bytes, n);
    free(b);
}

/* Exactly one line, newline-terminated. */
static void assert_one_line(const char *out)
{
    const char *nl = strchr(out, '\n');
    if (!nl || nl[1] != '\0')
        fail_msg("expected one line of output, got:\n%s", out);
}

/* `out` is exactly the lines "haze: ...want[i]...", in that order. */
static void assert_lines(const char *out, const char *const *want, size_t n)
{
    const char *line = out;
    for (size_t i = 0; i < n; ++i) {
        assert_non_null(line);
        if (strncmp(line, "haze: ", 6) != 0 || !strstr(line, want[i]) ||
            (strchr(line, '\n') && strstr(line, want[i]) > strchr(line, '\n')))
            fail_msg("line %zu lacks '%s': %s", i + 1, want[i], out);
        line = strchr(line, '\n');
        line = line ? line + 1 : NULL;
    }
    if (line && *line)
        fail_msg("more lines than the %zu expected: %s", n, out);
}

/* haze render SCENE -o GOOD over a good output file, killed after
 * `seconds`: the exit status, its output in out. */
static int render_over_good(const char *scene, int seconds, char *out, size_t n)
{
    char args[2048];
    write_good_output(HAZE_TMP "/bad_input_good.exr");
    snprintf(args, sizeof args, "render '%s' -o '" HAZE_TMP "/bad_input_good.exr' --quiet",
             scene);
    return run_haze_within(seconds, args, out, n);
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void test_scene_corpus(void **state)
{
    (void)state;
    DIR *d = opendir(CORPUS);
    assert_non_null(d);
    char *names[256];
    size_t count = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n > 5 && strcmp(e->d_name + n - 5, ".pbrt") == 0 && count < 256)
            names[count++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(names, count, sizeof names[0], compare_names);
    assert_true(count >= 15);
    const char *good = HAZE_TMP "/bad_input_good.exr";
    for (size_t i = 0; i < count; ++i) {
        char path[1024], line[256], expect_text[200];
        int expect_status = -1;
        snprintf(path, sizeof path, CORPUS "/%s", names[i]);
        FILE *f = fopen(path, "r");
        assert_non_null(f);
        assert_non_null(fgets(line, sizeof line, f));
        fclose(f);
        if (sscanf(line, "# expect: %d %199[^\n]", &expect_status, expect_text) != 2)
            fail_msg("%s: first line must be '# expect: STATUS TEXT'", names[i]);
        write_good_output(good);
        char args[2048], out[8192];
        snprintf(args, sizeof args, "render '%s' -o '%s' --quiet", path, good);
        int status = run_haze(args, out, sizeof out);
        print_message("%-28s exit %d: %s", names[i], status, out);
        if (status != expect_status)
            fail_msg("%s: exit status %d, expected %d; output: %s", names[i], status,
                     expect_status, out);
        assert_one_line(out);
        if (strstr(out, expect_text) == NULL)
            fail_msg("%s: message lacks '%s': %s", names[i], expect_text, out);
        /* Scene errors name the file (the scene or the file it includes). */
        if (strstr(out, ".pbrt:") == NULL && strstr(out, ".inc:") == NULL)
            fail_msg("%s: message names no scene place: %s", names[i], out);
        assert_good_output_kept(good);
        free(names[i]);
    }
}

/* A scene's errors come all at once, one "haze:" line each, in file order
 * (the scene, then its include), whether the parser or the scene build finds
 * them; the good output stays. */
static void test_all_errors_in_one_run(void **state)
{
    (void)state;
    const char *inc = HAZE_TMP "/bad_input_many.inc";
    const char *scene = HAZE_TMP "/bad_input_many.pbrt";
    write_text_file(inc, "Shape \"sphere\" \"float radius\" 1 \"float nonsense\" 2\n");
    write_text_file(scene,
                    "Camera \"perspective\" \"float fov\" 45 \"float bogus\" 1\n"
                    "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                    "WorldBegin\n"
                    "Include \"bad_input_many.inc\"\n"
                    "Material \"subsurface\"\n"
                    "Shape \"curve\" \"float width\" 1\n"
                    "LightSource \"laser\" \"float fov\" 30\n"
                    "MakeNamedMedium \"m\" \"string type\" \"fluffy\"\n"
                    "AttributeBegin\nAreaLightSource \"diffuse\" \"float what\" 3\n"
                    "Shape \"sphere\"\nAttributeEnd\n");
    const char *good = HAZE_TMP "/bad_input_good.exr";
    char out[8192];
    assert_int_equal(render_over_good(scene, 600, out, sizeof out), 1);
    static const char *want[] = {
        "bad_input_many.pbrt:1:37: unused parameter \"float bogus\"",
        "bad_input_many.pbrt:5:1: Material \"subsurface\" is not supported",
        "bad_input_many.pbrt:6:1: curve needs \"point3 P\"",
        "bad_input_many.pbrt:7:1: LightSource \"laser\" is not supported",
        "bad_input_many.pbrt:8:1: MakeNamedMedium \"m\": medium type \"fluffy\"",
        "bad_input_many.pbrt:10:27: unused parameter \"float what\"",
        "bad_input_many.inc:1:33: unused parameter \"float nonsense\"",
    };
    assert_lines(out, want, sizeof want / sizeof want[0]);
    assert_good_output_kept(good);
}

/* The parser's errors (types, syntax) and the build's (unsupported kinds)
 * in one report; a definition that failed to parse adds no errors where it
 * is used (its name stands for a placeholder that is never rendered). */
static void test_parse_and_build_errors_in_one_run(void **state)
{
    (void)state;
    const char *scene = HAZE_TMP "/bad_input_mixed.pbrt";
    write_text_file(scene,
                    "Camera \"perspective\" \"float fov\" \"wide\"\n"
                    "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                    "WorldBegin\n"
                    "Texture \"t\" \"spectrum\" \"checkerboard\" \"float uscale\" \"q\"\n"
                    "Material \"diffuse\" \"texture reflectance\" \"t\"\n"
                    "Material \"subsurface\"\n"
                    "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1]\n"
                    "MakeNamedMaterial \"g\" \"string type\" \"diffuse\" \"rgb reflectance\" [1]\n"
                    "NamedMaterial \"g\"\n"
                    "MediumInterface \"m\" \"\"\n"
                    "Shape \"sphere\"\n"
                    "Frobnicate 3\n"
                    "LightSource \"laser\"\n");
    const char *good = HAZE_TMP "/bad_input_good.exr";
    char out[8192];
    assert_int_equal(render_over_good(scene, 600, out, sizeof out), 1);
    static const char *want[] = {
        "bad_input_mixed.pbrt:1:34: parameter \"float fov\" expects numbers",
        "bad_input_mixed.pbrt:4:54: parameter \"float uscale\" expects numbers",
        "bad_input_mixed.pbrt:6:1: Material \"subsurface\" is not supported",
        "bad_input_mixed.pbrt:7:49: parameter \"rgb sigma_a\" needs a multiple of 3",
        "bad_input_mixed.pbrt:8:47: parameter \"rgb reflectance\" needs a multiple of 3",
        "bad_input_mixed.pbrt:12:1: unknown directive",
        "bad_input_mixed.pbrt:13:1: LightSource \"laser\" is not supported",
    };
    assert_lines(out, want, sizeof want / sizeof want[0]);
    assert_good_output_kept(good);
}

/* Corrupt images given to haze diff: exit 2 (unreadable input), one line. */
static void test_corrupt_exr_diff(void **state)
{
    (void)state;
    static const char *files[] = {"truncated.exr", "not-an.exr", "no-such.exr", "huge-window.exr"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char args[1024], out[4096];
        snprintf(args, sizeof args, "diff '" CORPUS "/data/%s' '" CORPUS "/data/%s'", files[i],
                 files[i]);
        int status = run_haze(args, out, sizeof out);
        print_message("%-28s exit %d: %s", files[i], status, out);
        assert_int_equal(status, 2);
        assert_one_line(out);
        assert_non_null(strstr(out, files[i]));
    }
}

/* An output that cannot be written is refused before rendering; a good file
 * at the target of a failed run stays. */
static void test_unwritable_output(void **state)
{
    (void)state;
    char out[4096];
    const char *scene = HAZE_SCENES "/orthographic.pbrt";
    static const char *targets[] = {"/nonexistent-haze-dir/x.exr", "/proc/haze-test.exr"};
    for (size_t i = 0; i < 2; ++i) {
        char args[2048];
        snprintf(args, sizeof args, "render '%s' --spp 1 -o '%s' --quiet", scene, targets[i]);
        int status = run_haze(args, out, sizeof out);
        print_message("%s: exit %d: %s", targets[i], status, out);
        assert_int_equal(status, 1);
        assert_one_line(out);
        assert_non_null(strstr(out, "cannot write"));
    }
}

/* A FIFO named as a volume is refused at once, at its scene place (its open
 * would wait for a writer for ever); the good output stays. */
static void test_fifo_volume(void **state)
{
    (void)state;
    const char *fifo = HAZE_TMP "/bad_input_fifo.vdb";
    const char *scene = HAZE_TMP "/bad_input_fifo.pbrt";
    unlink(fifo);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    write_text_file(scene, "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                           "WorldBegin\n"
                           "MakeNamedMedium \"m\" \"string type\" \"nanovdb\"\n"
                           "  \"string filename\" \"bad_input_fifo.vdb\"\n");
    const char *good = HAZE_TMP "/bad_input_good.exr";
    char out[8192];
    int status = render_over_good(scene, 60, out, sizeof out);
    if (status != 1)
        fail_msg("exit status %d, expected 1; output: %s", status, out);
    static const char *want[] = {"bad_input_fifo.pbrt:3:1: MakeNamedMedium \"m\": " HAZE_TMP
                                 "/bad_input_fifo.vdb: cannot read: is a FIFO; haze reads only "
                                 "regular files"};
    assert_lines(out, want, 1);
    assert_good_output_kept(good);
}

/* FIFOs named as an image texture and an environment map: both refused at
 * once at their scene places (the PNG and EXR readers' opens would wait for
 * a writer for ever); the good output stays. */
static void test_fifo_images(void **state)
{
    (void)state;
    const char *png = HAZE_TMP "/bad_input_fifo.png", *exr = HAZE_TMP "/bad_input_fifo.exr";
    const char *scene = HAZE_TMP "/bad_input_fifo_images.pbrt";
    unlink(png);
    unlink(exr);
    assert_int_equal(mkfifo(png, 0600), 0);
    assert_int_equal(mkfifo(exr, 0600), 0);
    write_text_file(scene, "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                           "WorldBegin\n"
                           "LightSource \"infinite\" \"string filename\" \"bad_input_fifo.exr\"\n"
                           "Texture \"t\" \"spectrum\" \"imagemap\" "
                           "\"string filename\" \"bad_input_fifo.png\"\n"
                           "Material \"diffuse\" \"texture reflectance\" \"t\"\n"
                           "Shape \"sphere\"\n");
    const char *good = HAZE_TMP "/bad_input_good.exr";
    char out[8192];
    int status = render_over_good(scene, 60, out, sizeof out);
    if (status != 1)
        fail_msg("exit status %d, expected 1; output: %s", status, out);
    assert_non_null(strstr(out, "bad_input_fifo_images.pbrt:3:24: light \"filename\": " HAZE_TMP
                                "/bad_input_fifo.exr: cannot read: is a FIFO; haze reads only "
                                "regular files"));
    assert_non_null(strstr(out, "bad_input_fifo_images.pbrt:4:35: cannot read PNG \"" HAZE_TMP
                                "/bad_input_fifo.png\": is a FIFO; haze reads only regular files"));
    assert_good_output_kept(good);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_corpus),
        cmocka_unit_test(test_all_errors_in_one_run),
        cmocka_unit_test(test_parse_and_build_errors_in_one_run),
        cmocka_unit_test(test_corrupt_exr_diff),
        cmocka_unit_test(test_unwritable_output),
        cmocka_unit_test(test_fifo_volume),
        cmocka_unit_test(test_fifo_images),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
