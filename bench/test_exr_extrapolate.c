/* bench/exr_extrapolate: OUT = 2 FINE - COARSE for every value of every
 * channel, and refusals that leave no output file. */
#define _POSIX_C_SOURCE 200809L

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "film/exr.h"

static const char *const names[] = {"R", "G", "B", "A"};

/* A w x h image whose channel c, pixel i holds value(c, i, k). */
static float value(int c, size_t i, int k)
{
    return (float)k * 0.37f + (float)c * 1.5f + (float)i * 0.013f - 0.1f * (float)(i % 3);
}

static void write_image(const char *path, int w, int h, int k)
{
    exr_image img = {0};
    hz_error err = {0};
    assert_int_equal(exr_image_alloc(&img, w, h, 4, &err), HZ_OK);
    for (int c = 0; c < 4; ++c) {
        strcpy(img.channels[c].name, names[c]);
        for (size_t i = 0; i < (size_t)w * (size_t)h; ++i)
            img.channels[c].pixels[i] = value(c, i, k);
    }
    assert_int_equal(exr_write(path, &img, &err), HZ_OK);
    exr_image_free(&img);
}

static int run(const char *fine, const char *coarse, const char *out)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s %s %s %s 2>/dev/null", EXR_EXTRAPOLATE_BIN, fine, coarse, out);
    int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The three files of a case, named by the process and `tag`; FINE (5 x 3,
 * k = 1) and COARSE (coarse_w x 3, k = 4) written. */
typedef struct {
    char fine[512], coarse[512], out[512];
} case_files;

static void case_setup(case_files *f, const char *tag, int coarse_w)
{
    snprintf(f->fine, sizeof f->fine, "%s/extrapolate-%ld-%s-fine.exr", HAZE_TMP, (long)getpid(),
             tag);
    snprintf(f->coarse, sizeof f->coarse, "%s/extrapolate-%ld-%s-coarse.exr", HAZE_TMP,
             (long)getpid(), tag);
    snprintf(f->out, sizeof f->out, "%s/extrapolate-%ld-%s-out.exr", HAZE_TMP, (long)getpid(), tag);
    write_image(f->fine, 5, 3, 1);
    write_image(f->coarse, coarse_w, 3, 4);
}

static void test_every_value(void **state)
{
    (void)state;
    case_files f;
    case_setup(&f, "values", 5);
    assert_int_equal(run(f.fine, f.coarse, f.out), 0);
    exr_image img = {0};
    hz_error err = {0};
    assert_int_equal(exr_read(f.out, &img, &err), HZ_OK);
    assert_int_equal(img.width, 5);
    assert_int_equal(img.height, 3);
    assert_int_equal(img.channel_count, 4);
    for (int c = 0; c < 4; ++c) {
        const exr_channel *ch = exr_find_channel(&img, names[c]);
        assert_non_null(ch);
        for (size_t i = 0; i < 15; ++i) {
            float want = 2.0f * value(c, i, 1) - value(c, i, 4);
            assert_true(ch->pixels[i] == want);
        }
    }
    exr_image_free(&img);
    unlink(f.fine);
    unlink(f.coarse);
    unlink(f.out);
}

static void test_refusals(void **state)
{
    (void)state;
    case_files f;
    case_setup(&f, "refusals", 4); /* COARSE one column narrower */
    assert_int_equal(run(f.fine, f.coarse, f.out), 1);
    assert_int_not_equal(access(f.out, F_OK), 0);
    assert_int_equal(run(f.fine, "/nonexistent/x.exr", f.out), 1);
    assert_int_not_equal(access(f.out, F_OK), 0);
    write_image(f.coarse, 5, 3, 4);
    assert_int_equal(run(f.fine, f.coarse, "/nonexistent/out.exr"), 1);
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s %s 2>/dev/null", EXR_EXTRAPOLATE_BIN, f.fine);
    int st = system(cmd);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 2);
    unlink(f.fine);
    unlink(f.coarse);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_value),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
