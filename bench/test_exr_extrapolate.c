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

static void path_of(char *buf, size_t n, const char *what)
{
    snprintf(buf, n, "%s/extrapolate-%ld-%s.exr", HAZE_TMP, (long)getpid(), what);
}

static void test_every_value(void **state)
{
    (void)state;
    char fine[512], coarse[512], out[512];
    path_of(fine, sizeof fine, "fine");
    path_of(coarse, sizeof coarse, "coarse");
    path_of(out, sizeof out, "out");
    write_image(fine, 5, 3, 1);
    write_image(coarse, 5, 3, 4);
    assert_int_equal(run(fine, coarse, out), 0);
    exr_image img = {0};
    hz_error err = {0};
    assert_int_equal(exr_read(out, &img, &err), HZ_OK);
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
    unlink(fine);
    unlink(coarse);
    unlink(out);
}

static void test_refusals(void **state)
{
    (void)state;
    char fine[512], coarse[512], out[512];
    path_of(fine, sizeof fine, "fine2");
    path_of(coarse, sizeof coarse, "coarse2");
    path_of(out, sizeof out, "out2");
    write_image(fine, 5, 3, 1);
    write_image(coarse, 4, 3, 4);
    assert_int_equal(run(fine, coarse, out), 1);
    assert_int_not_equal(access(out, F_OK), 0);
    assert_int_equal(run(fine, "/nonexistent/x.exr", out), 1);
    assert_int_not_equal(access(out, F_OK), 0);
    write_image(coarse, 5, 3, 4);
    assert_int_equal(run(fine, coarse, "/nonexistent/out.exr"), 1);
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s %s 2>/dev/null", EXR_EXTRAPOLATE_BIN, fine);
    int st = system(cmd);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 2);
    unlink(fine);
    unlink(coarse);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_value),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
