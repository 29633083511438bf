#define _POSIX_C_SOURCE 200809L
/* `haze info FILE`: describes VDB, NanoVDB, EXR and pbrt files by their
 * content; one-line errors with exit 1 for bad files, exit 2 for usage. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "cli_util.h"

#include <unistd.h>

static const char tiny_scene[] =
    "LookAt 0 1 -3  0 0.5 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 50\n"
    "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 2\n"
    "WorldBegin\n"
    "LightSource \"point\" \"point3 from\" [1 2 -1] \"rgb I\" [3 3 3]\n"
    "Material \"diffuse\"\n"
    "MakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.8 0.1 0.1]\n"
    "AttributeBegin\n"
    "  AreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n"
    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2]\n"
    "    \"point3 P\" [-0.5 1.5 0.5  0.5 1.5 0.5  0 1.5 1]\n"
    "AttributeEnd\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point3 P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]\n"
    "NamedMaterial \"red\"\n"
    "Shape \"sphere\" \"float radius\" 0.4\n";

static char scene_path[1024];

static int setup(void **state)
{
    (void)state;
    snprintf(scene_path, sizeof scene_path, "%s/info_tiny.pbrt", HAZE_TMP);
    write_text_file(scene_path, tiny_scene);
    return 0;
}

/* The line of `out` that starts (after spaces) with `key`, or NULL. */
static const char *line_with(const char *out, const char *key)
{
    size_t n = strlen(key);
    for (const char *l = out; l && *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : NULL) {
        const char *p = l;
        while (*p == ' ')
            p++;
        if (!strncmp(p, key, n))
            return p;
    }
    return NULL;
}

/* Copies the line starting at p (without the newline) into buf. */
static const char *one_line(const char *p, char *buf, size_t size)
{
    assert_non_null(p);
    size_t n = strcspn(p, "\n");
    if (n >= size)
        n = size - 1;
    memcpy(buf, p, n);
    buf[n] = '\0';
    return buf;
}

static void test_vdb_smoke(void **state)
{
    (void)state;
    char out[16384], args[2048];
    snprintf(args, sizeof args, "info '%s'", HAZE_SCENES "/../volumes/smoke.vdb");
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "OpenVDB file"));
    const char *density = strstr(out, "grid \"density\"");
    const char *v = strstr(out, "grid \"v\"");
    assert_non_null(density);
    assert_non_null(v);
    assert_true(density < v);
    char line[256];
    /* Each block: its type and the smoke's 27397 active voxels. */
    assert_string_equal(one_line(line_with(density, "type"), line, sizeof line),
                        "type            float");
    assert_string_equal(one_line(line_with(v, "type"), line, sizeof line), "type            vec3s");
    assert_string_equal(one_line(line_with(density, "active voxels"), line, sizeof line),
                        "active voxels   27397");
    assert_string_equal(one_line(line_with(v, "active voxels"), line, sizeof line),
                        "active voxels   27397");
    assert_non_null(line_with(density, "index bounds"));
    assert_non_null(line_with(density, "world bounds"));
    assert_non_null(line_with(density, "voxel size"));
    /* Density lies in (0, 1]; the velocity range is of vector lengths. */
    double lo, hi;
    assert_int_equal(sscanf(line_with(density, "value range"), "value range %lf .. %lf", &lo, &hi), 2);
    assert_true(lo > 0.0 && lo < hi && hi <= 1.0);
    assert_non_null(strstr(one_line(line_with(v, "value range"), line, sizeof line),
                           "(vector length)"));
    assert_non_null(strstr(out, "\n2 grids\n"));
}

/* Grids are listed one at a time under the names "gridname" accepts: a
 * file holding two grids named "density" lists "density[0]" and "density[1]"
 * (all of a file's grids at once took 6 GiB for one of 20,000 grids). */
static void test_vdb_duplicate_names(void **state)
{
    (void)state;
    char out[16384], args[2048];
    snprintf(args, sizeof args, "info '%s'", HAZE_TEST_VOLUMES "/dup_names.vdb");
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    const char *first = strstr(out, "grid \"density[0]\"\n");
    const char *second = strstr(out, "grid \"density[1]\"\n");
    assert_non_null(first);
    assert_non_null(second);
    assert_true(first < second);
}

static void test_nvdb_box(void **state)
{
    (void)state;
    char out[8192], args[2048], line[256];
    snprintf(args, sizeof args, "info '%s'", HAZE_SCENES "/../volumes/box.nvdb");
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "NanoVDB file"));
    const char *g = strstr(out, "grid \"density\"");
    assert_non_null(g);
    /* A 32^3 box of density 1. */
    assert_string_equal(one_line(line_with(g, "active voxels"), line, sizeof line),
                        "active voxels   32768");
    assert_string_equal(one_line(line_with(g, "index bounds"), line, sizeof line),
                        "index bounds    [0, 0, 0] .. [31, 31, 31]  (32 x 32 x 32)");
    assert_string_equal(one_line(line_with(g, "value range"), line, sizeof line),
                        "value range     1 .. 1");
    assert_string_equal(one_line(line_with(g, "voxel size"), line, sizeof line),
                        "voxel size      0.03125");
    assert_non_null(strstr(out, "\n1 grid\n"));
}

static void test_exr_from_render(void **state)
{
    (void)state;
    char exr[1024], args[4096], out[16384], line[256];
    snprintf(exr, sizeof exr, "%s/info_tiny.exr", HAZE_TMP);
    unlink(exr);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet --threads 1", scene_path, exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);

    /* A copy without the extension: the kind comes from the content. */
    char copy[1024];
    snprintf(copy, sizeof copy, "%s/info_tiny_noext", HAZE_TMP);
    size_t n = 0;
    unsigned char *data = read_whole_file(exr, &n);
    assert_non_null(data);
    FILE *f = fopen(copy, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
    free(data);

    snprintf(args, sizeof args, "info '%s'", copy);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "OpenEXR image"));
    assert_string_equal(one_line(line_with(out, "size"), line, sizeof line),
                        "size            24 x 16");
    assert_string_equal(one_line(line_with(out, "data window"), line, sizeof line),
                        "data window     (0, 0) .. (23, 15)");
    assert_non_null(strstr(out, "channels (4)"));
    const char *names[] = {"R", "G", "B", "A"};
    for (int c = 0; c < 4; c++) {
        char key[8], name[16], type[16];
        double lo, hi, mean;
        unsigned long nan, inf;
        snprintf(key, sizeof key, "%s ", names[c]);
        const char *l = line_with(strstr(out, "channels ("), key);
        assert_non_null(l);
        assert_int_equal(sscanf(l, "%15s %15s %lf %lf %lf %lu %lu", name, type, &lo, &hi, &mean,
                                &nan, &inf),
                         7);
        assert_string_equal(name, names[c]);
        assert_true(!strcmp(type, "half") || !strcmp(type, "float"));
        assert_true(lo <= mean && mean <= hi);
        assert_int_equal(nan, 0);
        assert_int_equal(inf, 0);
        if (c == 3) { /* alpha: every pixel is covered */
            assert_true(lo == 1.0 && hi == 1.0);
        } else { /* lit surfaces and the visible emitter */
            assert_true(lo >= 0.0 && hi > 0.0 && mean > 0.0);
        }
    }
    assert_non_null(line_with(out, "compression"));
    assert_non_null(strstr(out, "\"haze "));
}

static void test_pbrt(void **state)
{
    (void)state;
    char out[8192], args[2048], line[256];
    snprintf(args, sizeof args, "info '%s'", scene_path);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "pbrt-v4 scene"));
    assert_string_equal(one_line(line_with(out, "camera"), line, sizeof line),
                        "camera          perspective, fov 50");
    assert_non_null(strstr(one_line(line_with(out, "film"), line, sizeof line), "rgb, 24 x 16"));
    assert_string_equal(one_line(line_with(out, "sampler"), line, sizeof line),
                        "sampler         zsobol, 2 spp");
    assert_string_equal(one_line(line_with(out, "shapes"), line, sizeof line), "shapes          3");
    assert_string_equal(one_line(line_with(out, "lights"), line, sizeof line),
                        "lights          1 (+ 1 area light)");
    assert_string_equal(one_line(line_with(out, "materials"), line, sizeof line),
                        "materials       2 (1 named)");
    assert_string_equal(one_line(line_with(out, "instances"), line, sizeof line),
                        "instances       0");
    assert_string_equal(one_line(line_with(out, "media"), line, sizeof line), "media           0");
}

/* volpath's knobs, where a scene sets them, on the integrator line. */
static void test_pbrt_volpath_knobs(void **state)
{
    (void)state;
    const char *integrators[] = {"Integrator \"volpath\" \"integer maxdepth\" 64 "
                                 "\"float shadowcache\" 1 \"float stepsize\" 2 "
                                 "\"integer mediumsplits\" 4\n",
                                 "Integrator \"volpath\"\n"};
    const char *want[] = {"integrator      volpath, max depth 64, shadow cache 1 voxels, marched at "
                          "2 voxels, 4 continuations from the first medium vertex",
                          "integrator      volpath, max depth 5 (default)"};
    for (int k = 0; k < 2; ++k) {
        char path[1024], text[4096], out[8192], args[2048], line[256];
        snprintf(path, sizeof path, "%s/info_volpath.pbrt", HAZE_TMP);
        snprintf(text, sizeof text, "%s%s", integrators[k], tiny_scene);
        write_text_file(path, text);
        snprintf(args, sizeof args, "info '%s'", path);
        assert_int_equal(run_haze(args, out, sizeof out), 0);
        assert_string_equal(one_line(line_with(out, "integrator"), line, sizeof line), want[k]);
    }
}

/* Windows in the file's own coordinates, however they are offset. */
static void test_exr_offset_windows(void **state)
{
    (void)state;
    char exr[1024], cmd[2048], out[16384];
    snprintf(exr, sizeof exr, "%s/info_offset.exr", HAZE_TMP);
    snprintf(cmd, sizeof cmd,
             "oiiotool --create 24x8 3 --fullsize 32x32-16-16 --origin -8+2 -o '%s'", exr);
    if (system(cmd) != 0)
        skip(); /* oiiotool (openimageio-tools) missing */
    snprintf(cmd, sizeof cmd, "info '%s'", exr);
    assert_int_equal(run_haze(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "data window     (-8, 2) .. (15, 9)\n"));
    assert_non_null(strstr(out, "display window  (-16, -16) .. (15, 15)  (32 x 32)\n"));
}

/* Names from files reach the terminal escaped: a scene's film filename
 * holding an escape sequence that would clear the screen. */
static void test_control_bytes_escaped(void **state)
{
    (void)state;
    char path[1024], args[2048], out[16384];
    snprintf(path, sizeof path, "%s/info_escape.pbrt", HAZE_TMP);
    /* haze info tells text from binary by the first 4 KiB: pad them. */
    char text[8192];
    snprintf(text, sizeof text, "#%4200s\nFilm \"rgb\" \"string filename\" \"a\x1b[2J\x9b\xff.exr\"\n"
             "WorldBegin\n", "");
    write_text_file(path, text);
    snprintf(args, sizeof args, "info '%s'", path);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_null(strchr(out, 0x1b));
    assert_non_null(strstr(out, "\"a\\x1b[2J\\x9b\\xff.exr\""));
    /* And in error messages. */
    write_text_file(path, "WorldBegin\nShape \"\x1b]0;owned\x07\"\n");
    snprintf(args, sizeof args, "render '%s' -o '%s/info_escape.exr'", path, HAZE_TMP);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "\\x1b]0;owned\\x07"));
    assert_null(strchr(out, 0x1b));
    assert_null(strchr(out, 0x07));
}

static void test_bad_files_exit_1(void **state)
{
    (void)state;
    char path[1024], args[2048], out[4096];
    /* Binary garbage: one line naming the file. */
    snprintf(path, sizeof path, "%s/info_garbage.vdb", HAZE_TMP);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (int i = 0; i < 512; i++)
        fputc((i * 37 + 11) & 0xff, f);
    fclose(f);
    snprintf(args, sizeof args, "info '%s'", path);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, path));
    assert_non_null(strstr(out, "unrecognised file format"));
    assert_non_null(strchr(out, '\n'));
    assert_null(strchr(strchr(out, '\n') + 1, '\n'));

    /* A truncated VDB. */
    size_t n = 0;
    unsigned char *data = read_whole_file(HAZE_SCENES "/../volumes/smoke.vdb", &n);
    assert_non_null(data);
    assert_true(n > 200);
    snprintf(path, sizeof path, "%s/info_trunc.vdb", HAZE_TMP);
    f = fopen(path, "wb");
    assert_non_null(f);
    fwrite(data, 1, 200, f);
    fclose(f);
    free(data);
    snprintf(args, sizeof args, "info '%s'", path);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, path));
    assert_null(strchr(strchr(out, '\n') + 1, '\n'));

    /* Missing, empty, and a text file that is no scene. */
    assert_int_equal(run_haze("info /nonexistent/none.exr", out, sizeof out), 1);
    assert_non_null(strstr(out, "/nonexistent/none.exr"));
    snprintf(path, sizeof path, "%s/info_empty.exr", HAZE_TMP);
    write_text_file(path, "");
    snprintf(args, sizeof args, "info '%s'", path);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "empty"));
    snprintf(path, sizeof path, "%s/info_text.pbrt", HAZE_TMP);
    write_text_file(path, "Camera \"perspective\"\nWorldBegin\n  Shpe \"sphere\"\n");
    snprintf(args, sizeof args, "info '%s'", path);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    char expect[1200];
    snprintf(expect, sizeof expect, "%s:3:3:", path);
    assert_non_null(strstr(out, expect));
}

/* Writes HAZE_TMP/NAME holding `text` (its path into path) and runs haze
 * info on it: the exit status, its output in out. */
static int info_on(const char *name, const char *text, char *path, char *out, size_t n)
{
    char args[2048];
    snprintf(path, 1024, "%s/%s", HAZE_TMP, name);
    write_text_file(path, text);
    snprintf(args, sizeof args, "info '%s'", path);
    return run_haze(args, out, n);
}

/* Only text that looks like a scene (its first word a directive, or a .pbrt
 * name) is parsed as one: a stray byte or prose is "not a ... file". */
static void test_scene_sniffed(void **state)
{
    (void)state;
    static const char *const not_scenes[][2] = {
        {"info_one_byte", "v"}, {"info_prose.txt", "hello, world\n"},
        {"info_comment.txt", "# only a comment\n"}, {"info_word.txt", "Hello, world\n"}};
    char path[1024], out[4096], want[1200];
    for (size_t i = 0; i < sizeof not_scenes / sizeof not_scenes[0]; i++) {
        assert_int_equal(info_on(not_scenes[i][0], not_scenes[i][1], path, out, sizeof out), 1);
        snprintf(want, sizeof want, "%s: unrecognised file format: not a .vdb, .nvdb, .exr, "
                                    ".bsdf or .pbrt file", path);
        if (!strstr(out, want))
            fail_msg("%s: got \"%s\", want \"%s\"", not_scenes[i][0], out, want);
        assert_null(strchr(strchr(out, '\n') + 1, '\n'));
    }
    /* A scene under another name, after comments and blank lines. */
    const char *scene = "# a scene\n\n  # indented\nFilm \"rgb\"\nWorldBegin\n";
    assert_int_equal(info_on("info_scene.txt", scene, path, out, sizeof out), 0);
    assert_non_null(strstr(out, "pbrt-v4 scene"));
    /* Any text named .pbrt is parsed: its errors are scene errors. */
    assert_int_equal(info_on("info_one_byte.pbrt", "v", path, out, sizeof out), 1);
    assert_non_null(strstr(out, "info_one_byte.pbrt:1:1: unknown directive"));
}

/* An RGL .bsdf file: its fields and what the measured BRDF holds; a tensor
 * file that is no BRDF is described with the reason; a truncated one is
 * refused in one line. */
static void test_bsdf(void **state)
{
    (void)state;
    char out[8192];
    assert_int_equal(run_haze("info '" HAZE_TEST_BSDF "/ggx-aniso.bsdf'", out, sizeof out), 0);
    print_message("%s", out);
    assert_non_null(strstr(out, "ggx-aniso.bsdf: tensor file, 10 fields"));
    assert_non_null(strstr(out, "  spectra      float32  [13, 16, 2, 32, 32]\n"));
    assert_non_null(strstr(out, "description: haze test BRDF"));
    assert_non_null(strstr(out, "measured BRDF: anisotropic, 16 x 13 incident directions, 2 "
                                "wavelengths (400..500 nm), jacobian 1"));
    assert_int_equal(run_haze("info '" HAZE_TESTS "/bad-input/data/not-a-brdf.bsdf'", out,
                              sizeof out),
                     0);
    assert_non_null(strstr(out, "not a measured BRDF haze renders: no field \"theta_i\""));
    assert_int_equal(run_haze("info '" HAZE_TESTS "/bad-input/data/truncated.bsdf'", out,
                              sizeof out),
                     1);
    assert_non_null(strstr(out, "truncated.bsdf: truncated: field \"spectra\""));
    assert_null(strchr(strchr(out, '\n') + 1, '\n'));
}

static void test_usage_exit_2(void **state)
{
    (void)state;
    char out[4096];
    assert_int_equal(run_haze("info", out, sizeof out), 2);
    assert_non_null(strstr(out, "info needs a file"));
    assert_int_equal(run_haze("info a b", out, sizeof out), 2);
    assert_int_equal(run_haze("info --bogus", out, sizeof out), 2);
    assert_int_equal(run_haze("--help", out, sizeof out), 0);
    assert_non_null(strstr(out, "haze info FILE"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vdb_smoke),       cmocka_unit_test(test_nvdb_box),
        cmocka_unit_test(test_bsdf),
        cmocka_unit_test(test_vdb_duplicate_names),
        cmocka_unit_test(test_exr_from_render), cmocka_unit_test(test_pbrt),
        cmocka_unit_test(test_pbrt_volpath_knobs),
        cmocka_unit_test(test_exr_offset_windows), cmocka_unit_test(test_control_bytes_escaped),
        cmocka_unit_test(test_bad_files_exit_1), cmocka_unit_test(test_scene_sniffed),
        cmocka_unit_test(test_usage_exit_2),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
