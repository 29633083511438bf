#define _POSIX_C_SOURCE 200809L
/* `haze diff A.exr B.exr`: metrics against values computed here, the max's
 * location, --metric/--threshold exit codes, NaN/Inf exclusion, heatmaps,
 * exit 2 on mismatched or broken inputs, and agreement with OpenImageIO's
 * idiff when it is installed. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "cli_util.h"

#include <math.h>
#include <unistd.h>

#include "film/exr.h"

enum { W = 5, H = 4 };

/* The reference image's value: dyadic, so an offset of 0.25 is exact. */
static float ref_value(int x, int y, int c)
{
    return (float)(x + 2 * y + 3 * c) / 8.0f;
}

typedef float (*pixel_fn)(int x, int y, int c);

static float offset_value(int x, int y, int c)
{
    return ref_value(x, y, c) + 0.25f;
}

/* Offset 0.25 everywhere, and 1.5 at (3, 2) in G. */
static float spike_value(int x, int y, int c)
{
    return ref_value(x, y, c) + (x == 3 && y == 2 && c == 1 ? 1.5f : 0.25f);
}

static void tmp_path(char *buf, size_t size, const char *name)
{
    snprintf(buf, size, "%s/diff_%s", HAZE_TMP, name);
}

/* Writes a w x h float EXR whose channels are named by the comma-free
 * strings in names; channel c of pixel (x, y) is fn(x, y, c). */
static void write_image(const char *path, int w, int h, int x0, int y0, int nc,
                        const char *const *names, pixel_fn fn)
{
    exr_image img;
    hz_error err = {{0}};
    assert_int_equal(exr_image_alloc(&img, w, h, nc, &err), HZ_OK);
    img.data_x0 = x0;
    img.data_y0 = y0;
    img.display_width = x0 + w;
    img.display_height = y0 + h;
    for (int c = 0; c < nc; c++) {
        snprintf(img.channels[c].name, sizeof img.channels[c].name, "%s", names[c]);
        img.channels[c].half = false;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                img.channels[c].pixels[y * w + x] = fn(x, y, c);
    }
    if (exr_write(path, &img, &err) != HZ_OK)
        fail_msg("%s", err.message);
    exr_image_free(&img);
}

static const char *const rgb[] = {"R", "G", "B"};

typedef struct {
    double mse, rmse, relmse, mae, max, psnr, mean_a, mean_b, rel_mean;
    char at[64];
    unsigned long bad_a, bad_b;
} row;

/* Parses the table row of channel `name` ("all" for the overall row). */
static row parse_row(const char *out, const char *name)
{
    const char *t = strstr(out, "\nchannel ");
    assert_non_null(t);
    char key[80];
    snprintf(key, sizeof key, "\n%s ", name);
    const char *l = strstr(t, key);
    if (!l)
        fail_msg("no row '%s' in:\n%s", name, out);
    row r;
    char got[64];
    int n = sscanf(l + 1, "%63s %lf %lf %lf %lf %lf %63s %lf %lf %lf %lf %lu %lu", got, &r.mse,
                   &r.rmse, &r.relmse, &r.mae, &r.max, r.at, &r.psnr, &r.mean_a, &r.mean_b,
                   &r.rel_mean, &r.bad_a, &r.bad_b);
    if (n != 13)
        fail_msg("cannot parse row '%s' (%d fields) in:\n%s", name, n, out);
    assert_string_equal(got, name);
    return r;
}

static void assert_close(double got, double want)
{
    if (isinf(want) && got == want)
        return;
    double tol = 6e-6 * fabs(want) + 1e-12; /* the table prints 6 significant digits */
    if (!(fabs(got - want) <= tol))
        fail_msg("got %.9g, want %.9g", got, want);
}

typedef struct {
    double sq, rel, abs, a, b, max;
    size_t n;
} expect;

/* The metrics computed here from the same float values haze reads. */
static expect expected(pixel_fn fa, pixel_fn fb, int c0, int c1)
{
    expect e = {0};
    for (int c = c0; c < c1; c++)
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double a = fa(x, y, c), b = fb(x, y, c), d = a - b;
                if (!isfinite(a) || !isfinite(b))
                    continue;
                e.n++;
                e.sq += d * d;
                e.rel += d * d / ((b + 0.01) * (b + 0.01));
                e.abs += fabs(d);
                e.a += a;
                e.b += b;
                if (fabs(d) > e.max)
                    e.max = fabs(d);
            }
    return e;
}

static void check_row(const row *r, const expect *e)
{
    double n = (double)e->n;
    assert_close(r->mse, e->sq / n);
    assert_close(r->rmse, sqrt(e->sq / n));
    assert_close(r->relmse, e->rel / n);
    assert_close(r->mae, e->abs / n);
    assert_close(r->max, e->max);
    assert_close(r->psnr, e->sq > 0 ? 10.0 * log10(n / e->sq) : INFINITY);
    assert_close(r->mean_a, e->a / n);
    assert_close(r->mean_b, e->b / n);
    assert_close(r->rel_mean, (e->a - e->b) / fabs(e->b));
}

static char ref_exr[1024], off_exr[1024], spike_exr[1024];

static int setup(void **state)
{
    (void)state;
    tmp_path(ref_exr, sizeof ref_exr, "ref.exr");
    tmp_path(off_exr, sizeof off_exr, "offset.exr");
    tmp_path(spike_exr, sizeof spike_exr, "spike.exr");
    write_image(ref_exr, W, H, 0, 0, 3, rgb, ref_value);
    write_image(off_exr, W, H, 0, 0, 3, rgb, offset_value);
    write_image(spike_exr, W, H, 0, 0, 3, rgb, spike_value);
    return 0;
}

static void test_identical(void **state)
{
    (void)state;
    char args[4096], out[16384];
    snprintf(args, sizeof args, "diff '%s' '%s'", ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "PSNR with peak 1"));
    const char *names[] = {"R", "G", "B", "all"};
    for (int i = 0; i < 4; i++) {
        row r = parse_row(out, names[i]);
        assert_true(r.mse == 0.0 && r.rmse == 0.0 && r.relmse == 0.0 && r.mae == 0.0 &&
                    r.max == 0.0 && r.rel_mean == 0.0);
        assert_true(isinf(r.psnr) && r.psnr > 0);
        assert_int_equal(r.bad_a, 0);
        assert_int_equal(r.bad_b, 0);
    }
    snprintf(args, sizeof args, "diff '%s' '%s' --metric max --threshold 0", ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "PASS: max 0 <= threshold 0"));
}

static void test_constant_offset(void **state)
{
    (void)state;
    char args[4096], out[16384];
    snprintf(args, sizeof args, "diff '%s' '%s'", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    const char *names[] = {"R", "G", "B"};
    for (int c = 0; c < 3; c++) {
        row r = parse_row(out, names[c]);
        expect e = expected(offset_value, ref_value, c, c + 1);
        check_row(&r, &e);
        /* Exact by construction. */
        assert_true(r.mse == 0.0625 && r.rmse == 0.25 && r.mae == 0.25 && r.max == 0.25);
    }
    row all = parse_row(out, "all");
    expect e = expected(offset_value, ref_value, 0, 3);
    check_row(&all, &e);
    assert_true(all.mse == 0.0625 && all.rmse == 0.25 && all.mae == 0.25 && all.max == 0.25);
    /* relMSE is not symmetric: B is the reference. */
    snprintf(args, sizeof args, "diff '%s' '%s'", ref_exr, off_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    row rev = parse_row(out, "all");
    expect er = expected(ref_value, offset_value, 0, 3);
    check_row(&rev, &er);
    assert_true(rev.relmse < all.relmse);
}

static void test_max_location(void **state)
{
    (void)state;
    char a[1024], b[1024], args[4096], out[16384];
    /* A data window away from the origin: the location is in its coordinates. */
    tmp_path(a, sizeof a, "spike_win.exr");
    tmp_path(b, sizeof b, "ref_win.exr");
    write_image(a, W, H, 10, 20, 3, rgb, spike_value);
    write_image(b, W, H, 10, 20, 3, rgb, ref_value);
    snprintf(args, sizeof args, "diff '%s' '%s'", a, b);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    row g = parse_row(out, "G");
    assert_string_equal(g.at, "(13,22)");
    assert_true(g.max == 1.5);
    expect eg = expected(spike_value, ref_value, 1, 2);
    check_row(&g, &eg);
    row all = parse_row(out, "all");
    assert_string_equal(all.at, "(13,22,G)");
    expect e = expected(spike_value, ref_value, 0, 3);
    check_row(&all, &e);
    assert_non_null(strstr(out, "max abs error 1.5 at pixel (13, 22) channel G\n"));
    /* --channels picks the rows (and the overall figures). */
    snprintf(args, sizeof args, "diff '%s' '%s' --channels B,R", a, b);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_null(strstr(out, "\nG "));
    row br = parse_row(out, "all");
    assert_true(br.max == 0.25 && br.mse == 0.0625);
}

static void test_thresholds(void **state)
{
    (void)state;
    char args[4096], out[16384];
    /* Overall: MSE 0.0625, RMSE 0.25, max 0.25, PSNR 12.04 dB. */
    snprintf(args, sizeof args, "diff '%s' '%s' --metric rmse --threshold 0.3", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "PASS: rmse 0.25 <= threshold 0.3"));
    snprintf(args, sizeof args, "diff '%s' '%s' --metric rmse --threshold 0.2", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "FAIL: rmse 0.25 > threshold 0.2"));
    snprintf(args, sizeof args, "diff '%s' '%s' --metric max --threshold 0.25", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "diff '%s' '%s' --metric MSE --threshold 0.06", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "FAIL: mse 0.0625 > threshold 0.06"));
    snprintf(args, sizeof args, "diff '%s' '%s' --metric psnr --threshold 12", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "diff '%s' '%s' --metric psnr --threshold 12.1", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "FAIL: psnr 12.0411998 < threshold 12.1"));
    snprintf(args, sizeof args, "diff '%s' '%s' --metric mae --threshold 0.3", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "diff '%s' '%s' --metric relmse --threshold 0.01", off_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "FAIL: relmse"));
}

static float nan_a(int x, int y, int c)
{
    if (x == 1 && y == 1 && c == 0)
        return NAN;
    return offset_value(x, y, c);
}

static float inf_b(int x, int y, int c)
{
    if (x == 4 && y == 3 && c == 2)
        return INFINITY;
    return ref_value(x, y, c);
}

static void test_nonfinite_excluded(void **state)
{
    (void)state;
    char a[1024], b[1024], args[4096], out[16384];
    tmp_path(a, sizeof a, "nan.exr");
    tmp_path(b, sizeof b, "inf.exr");
    write_image(a, W, H, 0, 0, 3, rgb, nan_a);
    write_image(b, W, H, 0, 0, 3, rgb, inf_b);
    snprintf(args, sizeof args, "diff '%s' '%s'", a, b);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    row r = parse_row(out, "R"), g = parse_row(out, "G"), bl = parse_row(out, "B"),
        all = parse_row(out, "all");
    assert_int_equal(r.bad_a, 1);
    assert_int_equal(r.bad_b, 0);
    assert_int_equal(g.bad_a + g.bad_b, 0);
    assert_int_equal(bl.bad_a, 0);
    assert_int_equal(bl.bad_b, 1);
    assert_int_equal(all.bad_a, 1);
    assert_int_equal(all.bad_b, 1);
    /* The remaining pairs all differ by exactly 0.25. */
    assert_true(all.mse == 0.0625 && all.max == 0.25 && r.mse == 0.0625 && bl.mse == 0.0625);
    expect e = expected(nan_a, inf_b, 0, 3);
    assert_int_equal(e.n, 58);
    check_row(&all, &e);
    assert_non_null(strstr(out, "2 of 60 value pairs excluded"));
}

static void test_heatmaps(void **state)
{
    (void)state;
    char heat[1024], png[1024], args[4096], out[16384];
    tmp_path(heat, sizeof heat, "heat.exr");
    tmp_path(png, sizeof png, "heat.png");
    unlink(heat);
    unlink(png);
    snprintf(args, sizeof args, "diff '%s' '%s' --heatmap '%s'", spike_exr, ref_exr, heat);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    exr_image h;
    hz_error err = {{0}};
    if (exr_read(heat, &h, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(h.width, W);
    assert_int_equal(h.height, H);
    assert_int_equal(h.channel_count, 1);
    assert_string_equal(h.channels[0].name, "Y");
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double sum = 0.0;
            for (int c = 0; c < 3; c++)
                sum += fabs((double)spike_value(x, y, c) - (double)ref_value(x, y, c));
            float want = (float)(sum / 3.0);
            float got = h.channels[0].pixels[y * W + x];
            if (got != want)
                fail_msg("heatmap (%d, %d): got %.9g, want %.9g", x, y, got, want);
        }
    assert_true(h.channels[0].pixels[2 * W + 3] == (float)((0.25 + 1.5 + 0.25) / 3.0));
    exr_image_free(&h);

    snprintf(args, sizeof args, "diff '%s' '%s' --heatmap '%s'", spike_exr, ref_exr, png);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    size_t n = 0;
    unsigned char *data = read_whole_file(png, &n);
    assert_non_null(data);
    assert_true(n > 33);
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    assert_memory_equal(data, sig, 8);
    assert_memory_equal(data + 12, "IHDR", 4);
    uint32_t pw = (uint32_t)data[16] << 24 | (uint32_t)data[17] << 16 | (uint32_t)data[18] << 8 | data[19];
    uint32_t ph = (uint32_t)data[20] << 24 | (uint32_t)data[21] << 16 | (uint32_t)data[22] << 8 | data[23];
    assert_int_equal(pw, W);
    assert_int_equal(ph, H);
    free(data);

    /* An unwritable heatmap: exit 2, one line, and no report. */
    snprintf(args, sizeof args, "diff '%s' '%s' --heatmap /nonexistent/dir/heat.exr", spike_exr,
             ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    assert_non_null(strstr(out, "/nonexistent/dir/heat.exr"));
    assert_null(strchr(strchr(out, '\n') + 1, '\n'));
}

/* Exit 2 and exactly one line containing `want`. */
static void expect_exit2(const char *args, const char *want)
{
    char out[8192];
    int rc = run_haze(args, out, sizeof out);
    if (rc != 2 || !strstr(out, want))
        fail_msg("haze %s: exit %d, output:\n%s(expected exit 2 and '%s')", args, rc, out, want);
    const char *nl = strchr(out, '\n');
    assert_non_null(nl);
    assert_null(strchr(nl + 1, '\n'));
}

static void test_input_errors(void **state)
{
    (void)state;
    char p[1024], q[1024], args[4096];
    /* Different sizes, and equal sizes in different data windows. */
    tmp_path(p, sizeof p, "small.exr");
    write_image(p, W - 1, H, 0, 0, 3, rgb, ref_value);
    snprintf(args, sizeof args, "diff '%s' '%s'", ref_exr, p);
    expect_exit2(args, "sizes differ");
    tmp_path(p, sizeof p, "moved.exr");
    write_image(p, W, H, 1, 0, 3, rgb, ref_value);
    snprintf(args, sizeof args, "diff '%s' '%s'", ref_exr, p);
    expect_exit2(args, "data windows differ");

    /* A requested channel missing in either image; no shared channel. */
    snprintf(args, sizeof args, "diff '%s' '%s' --channels R,Z", ref_exr, off_exr);
    expect_exit2(args, "no channel \"Z\"");
    static const char *const ya[] = {"Y", "A"};
    tmp_path(p, sizeof p, "ya.exr");
    write_image(p, W, H, 0, 0, 2, ya, ref_value);
    snprintf(args, sizeof args, "diff '%s' '%s' --channels G", ref_exr, p);
    expect_exit2(args, "no channel \"G\"");
    snprintf(args, sizeof args, "diff '%s' '%s'", ref_exr, p);
    expect_exit2(args, "no channel in common");

    /* Truncated, garbage, missing files. */
    size_t n = 0;
    unsigned char *data = read_whole_file(ref_exr, &n);
    assert_non_null(data);
    tmp_path(q, sizeof q, "truncated.exr");
    FILE *f = fopen(q, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n / 2, f), n / 2);
    fclose(f);
    free(data);
    snprintf(args, sizeof args, "diff '%s' '%s'", q, ref_exr);
    expect_exit2(args, q);
    tmp_path(q, sizeof q, "garbage.exr");
    write_text_file(q, "this is not an EXR file\n");
    snprintf(args, sizeof args, "diff '%s' '%s'", ref_exr, q);
    expect_exit2(args, q);
    snprintf(args, sizeof args, "diff '%s' /nonexistent/b.exr", ref_exr);
    expect_exit2(args, "/nonexistent/b.exr");
}

static void test_usage(void **state)
{
    (void)state;
    char out[8192], args[4096];
    assert_int_equal(run_haze("diff", out, sizeof out), 2);
    assert_non_null(strstr(out, "diff needs two EXR images"));
    snprintf(args, sizeof args, "diff '%s'", ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    snprintf(args, sizeof args, "diff '%s' '%s' '%s'", ref_exr, ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    snprintf(args, sizeof args, "diff '%s' '%s' --metric ssim --threshold 1", ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    assert_non_null(strstr(out, "unknown metric 'ssim'"));
    snprintf(args, sizeof args, "diff '%s' '%s' --metric mse", ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    assert_non_null(strstr(out, "needs --threshold"));
    snprintf(args, sizeof args, "diff '%s' '%s' --threshold 1", ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    snprintf(args, sizeof args, "diff '%s' '%s' --metric mse --threshold abc", ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    snprintf(args, sizeof args, "diff '%s' '%s' --bogus", ref_exr, ref_exr);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    assert_int_equal(run_haze("diff --help", out, sizeof out), 0);
    assert_non_null(strstr(out, "--heatmap"));
    assert_int_equal(run_haze("--help", out, sizeof out), 0);
    assert_non_null(strstr(out, "haze diff A.exr B.exr"));
}

/* OpenImageIO's idiff (Debian openimageio-tools) on the same pair: its RMS
 * error and max error (with location) agree with haze's overall figures. */
static void test_idiff_agrees(void **state)
{
    (void)state;
    if (system("command -v idiff >/dev/null 2>&1") != 0) {
        print_message("idiff not installed (Debian package openimageio-tools): skipped\n");
        skip();
    }
    char cmd[4096], out[16384], args[4096];
    snprintf(cmd, sizeof cmd, "idiff '%s' '%s' 2>&1", spike_exr, ref_exr);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t n = fread(out, 1, sizeof out - 1, p);
    out[n] = '\0';
    pclose(p); /* idiff exits non-zero when the images differ */
    double rms = -1, mx = -1;
    int x = -1, y = -1;
    char ch[32] = "";
    const char *l = strstr(out, "RMS error = ");
    if (!l)
        fail_msg("no RMS error in idiff output:\n%s", out);
    assert_int_equal(sscanf(l, "RMS error = %lf", &rms), 1);
    l = strstr(out, "Max error");
    if (!l)
        fail_msg("no Max error in idiff output:\n%s", out);
    assert_int_equal(sscanf(l, "Max error = %lf @ (%d, %d, %31[^)])", &mx, &x, &y, ch), 4);

    snprintf(args, sizeof args, "diff '%s' '%s'", spike_exr, ref_exr);
    char hout[16384];
    assert_int_equal(run_haze(args, hout, sizeof hout), 0);
    row all = parse_row(hout, "all");
    if (fabs(rms - all.rmse) > 1e-5 * all.rmse)
        fail_msg("idiff RMS %.9g, haze %.9g", rms, all.rmse);
    if (fabs(mx - all.max) > 1e-5 * all.max)
        fail_msg("idiff max %.9g, haze %.9g", mx, all.max);
    char at[96];
    snprintf(at, sizeof at, "(%d,%d,%s)", x, y, ch);
    assert_string_equal(at, all.at);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_identical),          cmocka_unit_test(test_constant_offset),
        cmocka_unit_test(test_max_location),       cmocka_unit_test(test_thresholds),
        cmocka_unit_test(test_nonfinite_excluded), cmocka_unit_test(test_heatmaps),
        cmocka_unit_test(test_input_errors),       cmocka_unit_test(test_usage),
        cmocka_unit_test(test_idiff_agrees),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
