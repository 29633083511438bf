/* Progressive passes (`haze render --time-limit`, src/render/progressive.h):
 * the pass schedule; passes that add up to S samples give the render of S
 * samples bit for bit (every AOV); a pass cut short is undone; the command
 * line writes the complete passes and names them in the header. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <signal.h>
#include <stdatomic.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli_util.h"
#include "core/clock.h"
#include "film/exr.h"
#include "render/progressive.h"
#include "render_test_util.h"

/* A medium over a floor under a sky and a distant light: surfaces, media,
 * shadow rays; every AOV; an independent sampler (sample i of a pixel does
 * not depend on the count). */
static char *scene_text(int spp)
{
    char *s = malloc(4096);
    assert_non_null(s);
    snprintf(s, 4096,
             "LookAt 0 1 -4  0 0.6 0  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 40\n"
             "Film \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 36\n"
             "    \"bool writedepth\" true \"bool writevariance\" true\n"
             "    \"bool writesamplecount\" true\n"
             "Sampler \"independent\" \"integer pixelsamples\" %d\n"
             "WorldBegin\n"
             "LightSource \"distant\" \"point3 from\" [1 3 -2] \"point3 to\" [0 0 0]"
             " \"rgb L\" [3 3 3]\n"
             "LightSource \"infinite\" \"rgb L\" [0.1 0.12 0.15]\n"
             "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
             "    \"rgb sigma_a\" [0.2 0.2 0.2] \"rgb sigma_s\" [1 1 1]\n"
             "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "    \"point3 P\" [-5 0 -5  5 0 -5  5 0 5  -5 0 5]\n"
             "AttributeBegin\n"
             "  Material \"interface\"\n"
             "  MediumInterface \"fog\" \"\"\n"
             "  Translate 0 0.7 0\n"
             "  Shape \"sphere\" \"float radius\" 0.7\n"
             "AttributeEnd\n",
             spp);
    return s;
}

/* Every accumulator of the film, as one buffer (free it). */
static unsigned char *film_bytes(film *f, size_t *n)
{
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    size_t total = acc.count_count * sizeof(uint32_t);
    for (int i = 0; i < 3; ++i)
        total += acc.double_count[i] * sizeof(double);
    unsigned char *b = malloc(total), *p = b;
    assert_non_null(b);
    for (int i = 0; i < 3; ++i) {
        memcpy(p, acc.doubles[i], acc.double_count[i] * sizeof(double));
        p += acc.double_count[i] * sizeof(double);
    }
    memcpy(p, acc.counts, acc.count_count * sizeof(uint32_t));
    *n = total;
    return b;
}

/* One render of `spp` samples; its accumulators. */
static unsigned char *render_once(int spp, size_t *n)
{
    char *text = scene_text(spp);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    renderer_options opt = {.threads = 2};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run(rs, &opt, &st, &err), HZ_OK);
    assert_int_equal(st.spp, spp);
    unsigned char *b = film_bytes(render_scene_film(rs), n);
    render_scene_destroy(rs);
    return b;
}

static void test_pass_schedule(void **state)
{
    (void)state;
    const int spp16[] = {1, 2, 4, 8, 16}, spp12[] = {1, 2, 4, 8, 12};
    int b = 0;
    for (int i = 0; i < 5; ++i)
        assert_int_equal(b = progressive_pass_end(b, 16), spp16[i]);
    b = 0;
    for (int i = 0; i < 5; ++i)
        assert_int_equal(b = progressive_pass_end(b, 12), spp12[i]);
    assert_int_equal(progressive_pass_end(0, 1), 1);
    assert_int_equal(progressive_pass_end(1 << 23, 1 << 24), 1 << 24);
    /* 1 s for 2 samples: 4 more need 2 s */
    assert_true(progressive_pass_fits(10.0, 12.0, 1.0, 2, 4));
    assert_false(progressive_pass_fits(10.0, 11.9, 1.0, 2, 4));
}

/* No deadline in reach: every pass runs and the film is the one-render film. */
static void test_all_passes_bit_identical(void **state)
{
    (void)state;
    size_t n1 = 0, n2 = 0;
    unsigned char *once = render_once(12, &n1);
    char *text = scene_text(12);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    for (int threads = 1; threads <= 2; ++threads) {
        if (threads == 2) {
            render_scene_destroy(rs);
            text = scene_text(12);
            rs = build_scene_or_fail(text, NULL);
            free(text);
        }
        renderer_options opt = {.threads = threads};
        render_stats st;
        hz_error err = {0};
        assert_int_equal(
            renderer_run_progressive(rs, &opt, hz_clock_seconds() + 1e6, &st, &err), HZ_OK);
        assert_int_equal(st.spp, 12);
        assert_int_equal(st.passes, 5);
        assert_false(st.interrupted);
        assert_true(st.camera_rays >= 12u * 40 * 36);
        unsigned char *prog = film_bytes(render_scene_film(rs), &n2);
        assert_int_equal(n1, n2);
        assert_memory_equal(once, prog, n1);
        free(prog);
    }
    render_scene_destroy(rs);
    free(once);
}

/* A deadline already passed: the first pass still runs, no other. */
static void test_first_pass_always_completes(void **state)
{
    (void)state;
    size_t n1 = 0, n2 = 0;
    unsigned char *one = render_once(1, &n1);
    char *text = scene_text(64);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    renderer_options opt = {.threads = 2};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run_progressive(rs, &opt, hz_clock_seconds() - 1.0, &st, &err),
                     HZ_OK);
    assert_int_equal(st.spp, 1);
    assert_int_equal(st.passes, 1);
    assert_int_equal(st.tiles_done, st.tile_count);
    unsigned char *prog = film_bytes(render_scene_film(rs), &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(one, prog, n1);
    free(prog);
    free(one);
    render_scene_destroy(rs);
}

/* One thread claims tiles 0..T-1 and then gets -1, pass after pass; in the
 * third pass it asks for a cancel after `cut` tiles, as a signal would. */
typedef struct {
    int tile_count, cut;
    atomic_int calls;
    volatile sig_atomic_t cancel;
} cutter;

static int cutter_next(void *p)
{
    cutter *c = p;
    int n = atomic_fetch_add(&c->calls, 1);
    int pass = n / (c->tile_count + 1), t = n % (c->tile_count + 1);
    if (pass == 2 && t == c->cut) {
        c->cancel = 1;
        return -1;
    }
    return t < c->tile_count ? t : -1;
}

/* Passes [0,1) and [1,2) complete, [2,4) is cut after 3 tiles: the film is
 * the 2-sample film, not one with 4 samples in 3 tiles. */
static void test_cut_pass_undone(void **state)
{
    (void)state;
    size_t n1 = 0, n2 = 0;
    unsigned char *two = render_once(2, &n1);
    char *text = scene_text(16);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    cutter c = {.tile_count = 3 * 3, .cut = 3};
    atomic_init(&c.calls, 0);
    renderer_options opt = {.threads = 1, .next_tile = cutter_next, .tile_ctx = &c,
                            .cancel = &c.cancel};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run_progressive(rs, &opt, hz_clock_seconds() + 1e6, &st, &err),
                     HZ_OK);
    assert_int_equal(st.tile_count, c.tile_count);
    assert_int_equal(st.spp, 2);
    assert_int_equal(st.passes, 2);
    assert_false(st.interrupted);
    unsigned char *prog = film_bytes(render_scene_film(rs), &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(two, prog, n1);
    free(prog);
    free(two);
    render_scene_destroy(rs);
}

static char dir[1024];

static const char *exr_attribute(const exr_image *img, const char *name)
{
    for (int i = 0; i < img->attribute_count; ++i)
        if (!strcmp(img->attribute_names[i], name))
            return img->attribute_values[i];
    return NULL;
}

/* The command line: a limit no render reaches gives the full render's pixels
 * and says so in the header; a short one still writes a whole image (the
 * first pass at least) within about the limit; bad values are usage errors. */
static void test_command_line(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "%s/progressive-%ld", HAZE_TMP, (long)getpid());
    mkdir(dir, 0755);
    char scene[1200], full[1200], prog[1200], quick[1200], args[4096], out[8192];
    snprintf(scene, sizeof scene, "%s/s.pbrt", dir);
    snprintf(full, sizeof full, "%s/full.exr", dir);
    snprintf(prog, sizeof prog, "%s/prog.exr", dir);
    snprintf(quick, sizeof quick, "%s/quick.exr", dir);
    char *text = scene_text(8);
    write_text_file(scene, text);
    free(text);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet", scene, full);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "render '%s' -o '%s' --time-limit 1e6", scene, prog);
    if (run_haze(args, out, sizeof out) != 0)
        fail_msg("%s", out);
    assert_non_null(strstr(out, "8 spp in 4 passes"));
    assert_true(exr_pixels_equal(full, prog));
    exr_image img;
    hz_error err = {0};
    assert_int_equal(exr_read(prog, &img, &err), HZ_OK);
    const char *passes = exr_attribute(&img, "haze:passes"), *spp = exr_attribute(&img, "haze:spp");
    assert_non_null(passes);
    assert_non_null(spp);
    assert_string_equal(passes, "4");
    assert_string_equal(spp, "8");
    exr_image_free(&img);

    double t0 = hz_clock_seconds();
    snprintf(args, sizeof args, "render '%s' -o '%s' --spp 1048576 --time-limit 0.5 --quiet",
             scene, quick);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    double took = hz_clock_seconds() - t0;
    assert_true(took < (UNDER_ASAN ? 30.0 : 5.0));
    assert_int_equal(exr_read(quick, &img, &err), HZ_OK);
    spp = exr_attribute(&img, "haze:spp");
    assert_non_null(spp);
    assert_true(atol(spp) >= 1 && atol(spp) < 1048576);
    exr_image_free(&img);

    const char *bad[] = {"0", "-1", "abc", "nan", "inf", "1e10"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(args, sizeof args, "render '%s' -o '%s' --time-limit %s", scene, quick, bad[i]);
        assert_int_equal(run_haze(args, out, sizeof out), 2);
        assert_non_null(strstr(out, "--time-limit"));
    }
    unlink(scene);
    unlink(full);
    unlink(prog);
    unlink(quick);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pass_schedule),
        cmocka_unit_test(test_all_passes_bit_identical),
        cmocka_unit_test(test_first_pass_always_completes),
        cmocka_unit_test(test_cut_pass_undone),
        cmocka_unit_test(test_command_line),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
