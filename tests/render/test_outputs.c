/* Where haze render may write (cli/outputs.h): outputs that would destroy
 * something are refused before rendering, with one line, exit 1, and the
 * thing left exactly as it was. */
#define _XOPEN_SOURCE 700
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "film/png.h"
#include "render/cli_util.h"

#define DIR HAZE_TMP "/outputs"

static const char scene_text[] =
    "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\n"
    "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 1\nWorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [1 1 1]\nInclude \"part.pbrt\"\n";

/* Runs `haze render DIR/scene.pbrt ARGS` from DIR; returns the status and
 * fills out with what it printed. */
static int render_in_dir(const char *args, char *out, size_t n)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "render '" DIR "/scene.pbrt' %s --quiet", args);
    return run_haze(cmd, out, n);
}

static void expect_refused(const char *args, const char *message)
{
    char out[2048];
    assert_int_equal(render_in_dir(args, out, sizeof out), 1);
    if (!strstr(out, message))
        fail_msg("haze render %s: got \"%s\", want \"%s\"", args, out, message);
    const char *nl = strchr(out, '\n');
    assert_true(nl && nl[1] == '\0'); /* one line */
}

static void setup_dir(void)
{
    mkdir(HAZE_TMP, 0755);
    mkdir(DIR, 0755);
    write_text_file(DIR "/scene.pbrt", scene_text);
    write_text_file(DIR "/part.pbrt", "Shape \"sphere\"\n");
}

static void test_wrong_extensions(void **state)
{
    (void)state;
    setup_dir();
    expect_refused("-o '" DIR "/scene.pbrt'", "output '" DIR "/scene.pbrt' must end in .exr");
    expect_refused("-o /dev/null", "output '/dev/null' must end in .exr");
    expect_refused("-o '" DIR "/x.exr' --preview '" DIR "/x.exr'", "must end in .png");
    expect_refused("-o '" DIR "/x.png'", "must end in .exr");
    size_t n = 0;
    unsigned char *kept = read_whole_file(DIR "/scene.pbrt", &n);
    assert_int_equal(n, strlen(scene_text));
    assert_memory_equal(kept, scene_text, n);
    free(kept);
}

/* Devices, FIFOs and directories are never replaced, whatever their name. */
static void test_non_regular_outputs(void **state)
{
    (void)state;
    setup_dir();
    unlink(DIR "/fifo.exr");
    assert_int_equal(mkfifo(DIR "/fifo.exr", 0600), 0);
    expect_refused("-o '" DIR "/fifo.exr'", "is a FIFO; haze replaces only regular files");
    struct stat st;
    assert_int_equal(lstat(DIR "/fifo.exr", &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
    mkdir(DIR "/dir.exr", 0755);
    expect_refused("-o '" DIR "/dir.exr'", "is a directory; haze replaces only regular files");
    unlink(DIR "/null.exr");
    assert_int_equal(symlink("/dev/null", DIR "/null.exr"), 0);
    expect_refused("-o '" DIR "/null.exr'", "'/dev/null' is a device");
    assert_int_equal(lstat("/dev/null", &st), 0);
    assert_true(S_ISCHR(st.st_mode));
    unlink(DIR "/dangling.exr");
    assert_int_equal(symlink("nowhere.exr", DIR "/dangling.exr"), 0);
    expect_refused("-o '" DIR "/dangling.exr'", "is a symlink to a missing file");
}

/* An output that is an input of the render (through a symlink or another
 * name for the same file) would destroy it. */
static void test_inputs_are_not_outputs(void **state)
{
    (void)state;
    setup_dir();
    unlink(DIR "/alias.exr");
    unlink(DIR "/part.png");
    assert_int_equal(symlink("scene.pbrt", DIR "/alias.exr"), 0);
    expect_refused("-o '" DIR "/alias.exr'", "which the render reads; refusing to replace it");
    assert_int_equal(link(DIR "/part.pbrt", DIR "/part.png"), 0);
    expect_refused("-o '" DIR "/ok.exr' --preview '" DIR "/part.png'",
                   "preview '" DIR "/part.png' is '" DIR "/part.pbrt', which the render reads");
    /* The same file twice: a PNG name linked to the EXR. */
    write_text_file(DIR "/twice.exr", "x");
    unlink(DIR "/twice.png");
    assert_int_equal(symlink("twice.exr", DIR "/twice.png"), 0);
    expect_refused("-o '" DIR "/twice.exr' --preview '" DIR "/twice.png'", "are the same file");
    /* An image texture is an input too. */
    const uint8_t px[3] = {10, 20, 30};
    hz_error err;
    assert_int_equal(png_out_write_rgb8(DIR "/tex.png", 1, 1, px, &err), HZ_OK);
    write_text_file(DIR "/part.pbrt", "Texture \"t\" \"spectrum\" \"imagemap\" "
                                      "\"string filename\" \"tex.png\"\nShape \"sphere\"\n");
    expect_refused("-o '" DIR "/ok.exr' --preview '" DIR "/tex.png'",
                   "which the render reads; refusing to replace it");
    setup_dir();
}

/* A symlink is written through: the link stays, its target gets the image. */
static void test_symlink_written_through(void **state)
{
    (void)state;
    setup_dir();
    write_text_file(DIR "/target.exr", "old");
    unlink(DIR "/link.exr");
    assert_int_equal(symlink("target.exr", DIR "/link.exr"), 0);
    char out[2048];
    if (render_in_dir("-o '" DIR "/link.exr'", out, sizeof out) != 0)
        fail_msg("%s", out);
    struct stat st;
    assert_int_equal(lstat(DIR "/link.exr", &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    size_t n = 0;
    unsigned char *b = read_whole_file(DIR "/target.exr", &n);
    assert_true(n > 4 && b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01);
    free(b);
    assert_int_equal(count_temporaries_in(DIR), 0);
}

/* Parts of different renders (another seed, another spp, an include whose
 * bytes changed) are refused by haze merge; parts of one render merge into
 * the full render's pixels. */
static void test_merge_refuses_other_renders(void **state)
{
    (void)state;
    setup_dir();
    char out[4096];
    const char *left = "--pixelbounds 0,4,0,8", *right = "--pixelbounds 4,8,0,8";
    char args[2048];
#define PART(name, bounds, extra)                                                                 \
    snprintf(args, sizeof args, "-o '" DIR "/" name ".exr' %s %s", bounds, extra);                \
    assert_int_equal(render_in_dir(args, out, sizeof out), 0)
    PART("full", "", "");
    PART("l", left, "");
    PART("r", right, "");
    PART("r_seed", right, "--seed 5");
    PART("r_spp", right, "--spp 2");
    write_text_file(DIR "/part.pbrt", "Shape \"sphere\" \"float radius\" 0.9\n");
    PART("r_include", right, "");
    write_text_file(DIR "/part.pbrt", "Shape \"sphere\"\n");
#undef PART
    assert_int_equal(run_haze("merge '" DIR "/l.exr' '" DIR "/r.exr' -o '" DIR "/merged.exr'", out,
                              sizeof out),
                     0);
    assert_true(exr_pixels_equal(DIR "/merged.exr", DIR "/full.exr"));
    const char *others[] = {"r_seed", "r_spp", "r_include"};
    for (int i = 0; i < 3; ++i) {
        snprintf(args, sizeof args, "merge '" DIR "/l.exr' '" DIR "/%s.exr' -o '" DIR "/bad.exr'",
                 others[i]);
        assert_int_equal(run_haze(args, out, sizeof out), 1);
        if (!strstr(out, "are parts of different renders"))
            fail_msg("%s: %s", others[i], out);
    }
}

static void expect_merge_refused(const char *output, const char *message)
{
    char args[2048], out[2048];
    snprintf(args, sizeof args, "merge '" DIR "/l.exr' '" DIR "/r.exr' -o '%s'", output);
    int rc = run_haze(args, out, sizeof out);
    if (rc != 1 || !strstr(out, message))
        fail_msg("haze %s: exit %d, got \"%s\", want exit 1 and \"%s\"", args, rc, out, message);
    const char *nl = strchr(out, '\n');
    assert_true(nl && nl[1] == '\0'); /* one line */
}

/* A scene DIR/film.pbrt whose Film line (line 3) is `film`. */
static void write_film_scene(const char *film)
{
    char text[2048];
    snprintf(text, sizeof text,
             "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\n%s\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 1\nWorldBegin\n"
             "LightSource \"infinite\" \"rgb L\" [1 1 1]\nShape \"sphere\"\n",
             film);
    write_text_file(DIR "/film.pbrt", text);
}

static int render_film_scene(const char *args, char *out, size_t n)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "render '" DIR "/film.pbrt' %s --quiet", args);
    return run_haze(cmd, out, n);
}

static bool is_png(const char *path)
{
    size_t n = 0;
    unsigned char *b = read_whole_file(path, &n);
    bool png = b && n > 8 && memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0;
    free(b);
    return png;
}

/* (Not opendir: DIR is this file's directory.) */
static int entries_in(const char *dir)
{
    struct dirent **list;
    int n = scandir(dir, &list, NULL, NULL);
    for (int i = 0; i < n; ++i)
        free(list[i]);
    if (n >= 0)
        free(list);
    return n;
}

#define FILM_RES "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8 "

/* A Film filename ending in .png writes that PNG (the --preview writer's
 * bytes) and nothing else, as pbrt-v4; -o NAME.exr wins over it. */
static void test_film_png(void **state)
{
    (void)state;
    setup_dir();
    mkdir(DIR "/png", 0755);
    unlink(DIR "/png/film.png");
    unlink(DIR "/png/preview.png");
    unlink(DIR "/png/o.exr");
    write_film_scene(FILM_RES "\"string filename\" \"" DIR "/png/film.png\"");
    int before = entries_in(DIR "/png");
    char out[2048];
    if (render_film_scene("--preview '" DIR "/png/preview.png'", out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_true(is_png(DIR "/png/film.png"));
    assert_true(files_equal(DIR "/png/film.png", DIR "/png/preview.png"));
    assert_int_equal(entries_in(DIR "/png"), before + 2); /* no EXR beside them */
    unlink(DIR "/png/film.png");
    if (render_film_scene("-o '" DIR "/png/o.exr'", out, sizeof out) != 0)
        fail_msg("%s", out);
    struct stat st;
    assert_int_equal(stat(DIR "/png/o.exr", &st), 0);
    assert_int_not_equal(stat(DIR "/png/film.png", &st), 0);
    assert_int_equal(count_temporaries_in(DIR "/png"), 0);
}

static void expect_film_refused(const char *args, const char *message)
{
    char out[2048];
    assert_int_equal(render_film_scene(args, out, sizeof out), 1);
    if (!strstr(out, message))
        fail_msg("haze render %s: got \"%s\", want \"%s\"", args, out, message);
    const char *nl = strchr(out, '\n');
    assert_true(nl && nl[1] == '\0'); /* one line */
}

/* haze merge -o is checked as haze render -o: no FIFO, directory, part (by
 * any name) or non-.exr name is replaced, and nothing is written. */
static void test_merge_outputs(void **state)
{
    (void)state;
    setup_dir();
    char out[4096];
    assert_int_equal(render_in_dir("-o '" DIR "/l.exr' --pixelbounds 0,4,0,8", out, sizeof out), 0);
    assert_int_equal(render_in_dir("-o '" DIR "/r.exr' --pixelbounds 4,8,0,8", out, sizeof out), 0);
    size_t n_l = 0, n = 0;
    unsigned char *l = read_whole_file(DIR "/l.exr", &n_l);
    assert_non_null(l);

    unlink(DIR "/fifo.exr");
    assert_int_equal(mkfifo(DIR "/fifo.exr", 0600), 0);
    expect_merge_refused(DIR "/fifo.exr", "merge: output '" DIR "/fifo.exr' is a FIFO; haze "
                                          "replaces only regular files");
    struct stat st;
    assert_int_equal(lstat(DIR "/fifo.exr", &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
    mkdir(DIR "/dir.exr", 0755);
    expect_merge_refused(DIR "/dir.exr", "is a directory; haze replaces only regular files");

    unlink(DIR "/m.png");
    expect_merge_refused(DIR "/m.png", "merge: output '" DIR "/m.png' must end in .exr");
    assert_int_not_equal(lstat(DIR "/m.png", &st), 0);

    /* A part under another name: a path spelled otherwise, a hard link, a
     * symlink. */
    unlink(DIR "/hard.exr");
    unlink(DIR "/soft.exr");
    assert_int_equal(link(DIR "/l.exr", DIR "/hard.exr"), 0);
    assert_int_equal(symlink("l.exr", DIR "/soft.exr"), 0);
    const char *aliases[] = {DIR "/./l.exr", DIR "/hard.exr", DIR "/soft.exr"};
    for (int i = 0; i < 3; ++i)
        expect_merge_refused(aliases[i], "which the merge reads; refusing to replace it");
    unsigned char *kept = read_whole_file(DIR "/l.exr", &n);
    assert_int_equal(n, n_l);
    assert_memory_equal(kept, l, n);
    free(kept);
    free(l);
    assert_int_equal(count_temporaries_in(DIR), 0);
}

/* Other extensions stay refused at the Film, -o or not; what a PNG cannot
 * hold is refused rather than dropped, unless -o gives an EXR. */
static void test_film_filename_refused(void **state)
{
    (void)state;
    setup_dir();
    write_film_scene(FILM_RES "\"string filename\" \"x.tif\"");
    expect_film_refused("", "film.pbrt:3:");
    expect_film_refused("-o '" DIR "/o.exr'", "\"x.tif\" must end in .exr or .png");
    write_film_scene(FILM_RES "\"string filename\" \"" DIR "/d.png\" \"bool writedepth\" true");
    expect_film_refused("", "film.pbrt:3:");
    expect_film_refused("", "\"bool writedepth\" needs an EXR");
    char out[2048];
    if (render_film_scene("-o '" DIR "/d.exr'", out, sizeof out) != 0)
        fail_msg("%s", out);
    write_film_scene("Film \"gbuffer\" \"integer xresolution\" 8 \"integer yresolution\" 8 "
                     "\"string filename\" \"" DIR "/g.png\"");
    expect_film_refused("", "Film \"gbuffer\" writes only EXR");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wrong_extensions),
        cmocka_unit_test(test_non_regular_outputs),
        cmocka_unit_test(test_inputs_are_not_outputs),
        cmocka_unit_test(test_symlink_written_through),
        cmocka_unit_test(test_merge_refuses_other_renders),
        cmocka_unit_test(test_merge_outputs),
        cmocka_unit_test(test_film_png),
        cmocka_unit_test(test_film_filename_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
