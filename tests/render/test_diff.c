#define _POSIX_C_SOURCE 200809L
/* `haze diff A.exr B.exr`: metrics against values computed here, the max's
 * location, --metric/--threshold exit codes, NaN/Inf exclusion, heatmaps,
 * exit 2 on mismatched or broken inputs, and agreement with OpenImageIO's
 * idiff when it is installed. --ztest: on constructed images with known
 * statistics (the false-failure rate over many seeds against alpha, a 5%
 * shift caught by the block and image scales, an outlier at its exact
 * coordinates, the Sidak level), and on real renders (a re-seeded render
 * passes, one light 5% brighter fails). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "cli_util.h"

#include <math.h>
#include <sys/stat.h>
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

/* Writes a w x h float EXR (data window at (x0, y0)) whose channels are
 * named by names; planes[c] holds channel c row by row. */
static void write_planes(const char *path, int w, int h, int x0, int y0, int nc,
                         const char *const *names, float *const *planes)
{
    exr_image img;
    hz_error err = {0};
    assert_int_equal(exr_image_alloc(&img, w, h, nc, &err), HZ_OK);
    img.data_x0 = x0;
    img.data_y0 = y0;
    img.display_width = x0 + w;
    img.display_height = y0 + h;
    for (int c = 0; c < nc; c++) {
        snprintf(img.channels[c].name, sizeof img.channels[c].name, "%s", names[c]);
        img.channels[c].half = false;
        memcpy(img.channels[c].pixels, planes[c], (size_t)w * (size_t)h * sizeof(float));
    }
    if (exr_write(path, &img, &err) != HZ_OK)
        fail_msg("%s", err.message);
    exr_image_free(&img);
}

/* The same with channel c of pixel (x, y) = fn(x, y, c). */
static void write_image(const char *path, int w, int h, int x0, int y0, int nc,
                        const char *const *names, pixel_fn fn)
{
    float *planes[8];
    assert_true(nc <= 8);
    for (int c = 0; c < nc; c++) {
        planes[c] = malloc((size_t)w * (size_t)h * sizeof(float));
        assert_non_null(planes[c]);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                planes[c][y * w + x] = fn(x, y, c);
    }
    write_planes(path, w, h, x0, y0, nc, names, planes);
    for (int c = 0; c < nc; c++)
        free(planes[c]);
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
                e.rel += d * d / ((fabs(b) + 0.01) * (fabs(b) + 0.01));
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

    /* With a threshold, a NaN in A where the reference B is finite fails,
     * however good the metric of the other pairs. */
    snprintf(args, sizeof args, "diff '%s' '%s' --metric mse --threshold 1", a, b);
    assert_int_equal(run_haze(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "FAIL: mse: 1 values are NaN/Inf in A where B is finite"));
    /* A non-finite reference value alone (A finite there) is only excluded. */
    snprintf(args, sizeof args, "diff '%s' '%s' --metric mse --threshold 1", off_exr, b);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
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
    hz_error err = {0};
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

/* --heatmap replaces only a regular file, and never one of the images it
 * compares (by any name), as haze render -o and haze merge -o: exit 2, one
 * line, the input byte for byte intact. */
static void test_heatmap_guarded(void **state)
{
    (void)state;
    char args[4096], out[8192], fifo[1024], alias[1024];
    size_t n0 = 0, n1 = 0;
    unsigned char *before = read_whole_file(ref_exr, &n0);
    assert_non_null(before);
    tmp_path(alias, sizeof alias, "ref-link.exr");
    unlink(alias);
    assert_int_equal(link(ref_exr, alias), 0);
    snprintf(args, sizeof args, "diff '%s' '%s' --heatmap '%s'", spike_exr, ref_exr, alias);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    assert_non_null(strstr(out, "which the diff reads; refusing to replace it"));
    unsigned char *after = read_whole_file(ref_exr, &n1);
    assert_int_equal(n1, n0);
    assert_memory_equal(after, before, n0);
    free(after);
    free(before);
    unlink(alias);
    tmp_path(fifo, sizeof fifo, "heat-fifo.exr");
    unlink(fifo);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    snprintf(args, sizeof args, "diff '%s' '%s' --heatmap '%s'", spike_exr, ref_exr, fifo);
    assert_int_equal(run_haze_within(30, args, out, sizeof out), 2);
    assert_non_null(strstr(out, "is a FIFO"));
    unlink(fifo);
}

/* Exit 2 and exactly one line containing `want` (within 30 s: a FIFO must
 * not be waited on). */
static void expect_exit2(const char *args, const char *want)
{
    char out[8192];
    int rc = run_haze_within(30, args, out, sizeof out);
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

    /* A FIFO on either side: refused, not waited on for a writer. */
    tmp_path(q, sizeof q, "fifo.exr");
    unlink(q);
    assert_int_equal(mkfifo(q, 0600), 0);
    char want[1200];
    snprintf(want, sizeof want, "%s: cannot read: is a FIFO; haze reads only regular files", q);
    snprintf(args, sizeof args, "diff '%s' '%s'", q, ref_exr);
    expect_exit2(args, want);
    snprintf(args, sizeof args, "diff '%s' '%s'", ref_exr, q);
    expect_exit2(args, want);
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


/* ------------------------------------------------------------------ z-test */

/* splitmix64 and Box-Muller: the noise of the constructed images. */
static double uniform01(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    z ^= z >> 31;
    return ((double)(z >> 11) + 0.5) * 0x1p-53; /* in (0, 1) */
}

static double gauss(uint64_t *s)
{
    double u1 = uniform01(s), u2 = uniform01(s);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* A pair of images with known statistics: the true mean mu(x, y, c); the
 * reference B = mu + N(0, vB) carries Variance = vB; A = (1 + shift) mu +
 * N(0, vA). With counts, both carry SampleCount.Y (B 1024, A 16, so haze
 * derives vA = 64 vB); otherwise A carries its own Variance = vA = 4 vB. The
 * difference a - b has relative standard deviation `noise` (times zt_factor). */
typedef struct {
    int w, h, x0, y0;
    uint64_t seed;
    bool counts;
    double noise, shift;
    int ox, oy, oc;     /* outlier pixel (data-window coordinates), ox < 0: none */
    double out_sigmas;  /* added to A there, in standard deviations of a - b */
    bool nan_outlier;   /* A is NaN there instead */
    bool b_variance;    /* false: B has no Variance channels */
    bool flat;          /* the noise factor is 1 everywhere */
} zt_case;

static zt_case zt_default(uint64_t seed)
{
    zt_case k = {64, 64, 0, 0, seed, false, 0.02, 0.0, -1, 0, 0, 0.0, false, true, false};
    return k;
}

/* The factor of the noise at (x, y), in [0.5, 1.5]. */
static double zt_factor(int x, int y, const zt_case *k)
{
    return k->flat ? 1.0 : 0.5 + 0.25 * ((x * 7 + y * 3) % 5);
}

static double zt_mu(int x, int y, int c, const zt_case *k)
{
    return 0.2 + 0.6 * (double)(x + y) / (double)(k->w + k->h) + 0.1 * c;
}

static void zt_write(const zt_case *k, const char *a_path, const char *b_path)
{
    size_t n = (size_t)k->w * (size_t)k->h;
    float *p[14];
    for (int i = 0; i < 14; i++) {
        p[i] = malloc(n * sizeof(float));
        assert_non_null(p[i]);
    }
    /* p[0..2] A's R G B, p[3..5] A's variance, p[6] A's count; p[7..9] B's
     * R G B, p[10..12] B's variance, p[13] B's count. */
    double ratio = k->counts ? 1024.0 / 16.0 : 4.0;
    uint64_t rng = k->seed * 0x2545f4914f6cdd1du + 1;
    for (int c = 0; c < 3; c++)
        for (int y = 0; y < k->h; y++)
            for (int x = 0; x < k->w; x++) {
                size_t i = (size_t)y * (size_t)k->w + (size_t)x;
                double mu = zt_mu(x, y, c, k);
                double sd = k->noise * mu * zt_factor(x, y, k);
                double vb = sd * sd / (1.0 + ratio), va = ratio * vb;
                double a = (1.0 + k->shift) * mu + sqrt(va) * gauss(&rng);
                double b = mu + sqrt(vb) * gauss(&rng);
                if (x == k->ox && y == k->oy && c == k->oc)
                    a = k->nan_outlier ? NAN : a + k->out_sigmas * sd;
                p[c][i] = (float)a;
                p[3 + c][i] = (float)va;
                p[7 + c][i] = (float)b;
                p[10 + c][i] = (float)vb;
                p[6][i] = 16.0f;
                p[13][i] = 1024.0f;
            }
    static const char *const a_own[] = {"R", "G", "B", "Variance.R", "Variance.G", "Variance.B"};
    static const char *const a_cnt[] = {"R", "G", "B", "SampleCount.Y"};
    static const char *const b_all[] = {"R", "G", "B", "Variance.R", "Variance.G", "Variance.B",
                                        "SampleCount.Y"};
    float *const a_cnt_planes[] = {p[0], p[1], p[2], p[6]};
    if (k->counts)
        write_planes(a_path, k->w, k->h, k->x0, k->y0, 4, a_cnt, a_cnt_planes);
    else
        write_planes(a_path, k->w, k->h, k->x0, k->y0, 6, a_own, p);
    write_planes(b_path, k->w, k->h, k->x0, k->y0, k->b_variance ? (k->counts ? 7 : 6) : 3, b_all,
                 p + 7);
    for (int i = 0; i < 14; i++)
        free(p[i]);
}

typedef struct {
    size_t tests, failed, limit;
    double worst;
    char at[96];
} zt_row;

/* The row of one scale ("pixel", "block", "image") of the z-test table. */
static zt_row zt_parse(const char *out, const char *scale)
{
    const char *t = strstr(out, "\nscale ");
    if (!t)
        fail_msg("no z-test table in:\n%s", out);
    char key[32];
    snprintf(key, sizeof key, "\n%s ", scale);
    const char *l = strstr(t, key);
    if (!l)
        fail_msg("no z-test row '%s' in:\n%s", scale, out);
    zt_row r;
    memset(&r, 0, sizeof r);
    if (sscanf(l + 1, "%*s %zu %zu %zu %lf %95[^\n]", &r.tests, &r.failed, &r.limit, &r.worst, r.at) != 5)
        fail_msg("cannot parse z-test row '%s' in:\n%s", scale, out);
    return r;
}

static double zt_parse_level(const char *out)
{
    const char *l = strstr(out, "Sidak level per test ");
    if (!l)
        fail_msg("no Sidak level in:\n%s", out);
    return strtod(l + strlen("Sidak level per test "), NULL);
}

static double zt_image_z(const char *out, const char *channel)
{
    const char *l = strstr(out, "\nimage z:");
    assert_non_null(l);
    char key[8];
    snprintf(key, sizeof key, " %s ", channel);
    const char *k = strstr(l, key);
    if (!k || strchr(l + 1, '\n') < k)
        fail_msg("no image z of %s in:\n%s", channel, out);
    return strtod(k + strlen(key), NULL);
}

/* Runs the z-test on A against B with extra options; returns the exit code. */
static int zt_run(const char *a, const char *b, const char *extra, char *out, size_t size)
{
    char args[4096];
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest %s", a, b, extra);
    return run_haze(args, out, size);
}

/* (a) A consistent with B: the first seeds pass with the defaults; with
 * --alpha 0.5 --accept 1 (pure Sidak: fail when any test fails; a large alpha
 * so that 40 seeds measure the rate) the fraction of seeds that fail is about
 * alpha, the pixel tests fail at the per-test level, and the image-level z is
 * standard normal. Counts and A's own variance alternate. */
static void test_ztest_false_failures(void **state)
{
    (void)state;
    enum { SEEDS = 40, DEFAULT_SEEDS = 8 };
    char a[1024], b[1024];
    static char out[65536];
    tmp_path(a, sizeof a, "zt_a.exr");
    tmp_path(b, sizeof b, "zt_b.exr");
    int runs_failed = 0;
    size_t pixel_failures = 0, pixel_tests = 0;
    double level = 0.0, sum_z2 = 0.0, worst_default = 0.0;
    for (int s = 0; s < SEEDS; s++) {
        zt_case k = zt_default((uint64_t)s + 1);
        k.counts = s % 2;
        zt_write(&k, a, b);
        int rc;
        zt_row px;
        if (s < DEFAULT_SEEDS) {
            rc = zt_run(a, b, "", out, sizeof out);
            if (rc != 0)
                fail_msg("seed %d: consistent images fail the default z-test:\n%s", s + 1, out);
            assert_non_null(strstr(out, k.counts ? "variance of A: B's Variance x SampleCount.Y"
                                                 : "variance of A: A's own Variance"));
            px = zt_parse(out, "pixel");
            if (fabs(px.worst) > worst_default)
                worst_default = fabs(px.worst);
        }
        rc = zt_run(a, b, "--alpha 0.5 --accept 1", out, sizeof out);
        assert_true(rc == 0 || rc == 1);
        runs_failed += rc;
        px = zt_parse(out, "pixel");
        zt_row bl = zt_parse(out, "block"), im = zt_parse(out, "image");
        assert_int_equal(rc, px.failed + bl.failed + im.failed > 0);
        assert_int_equal(px.tests, 64 * 64 * 3);
        assert_int_equal(bl.tests, 8 * 8 * 3);
        assert_int_equal(im.tests, 3);
        assert_int_equal(px.limit + bl.limit + im.limit, 0);
        pixel_failures += px.failed;
        pixel_tests += px.tests;
        level = zt_parse_level(out);
        for (int c = 0; c < 3; c++) {
            double z = zt_image_z(out, rgb[c]);
            sum_z2 += z * z;
        }
    }
    /* Binomial(40, P) with P = 0.5 for independent tests (Sidak is exact
     * then; the blocks depend on their pixels, which can only lower P). */
    double expect_pixels = (double)pixel_tests * level;
    double mean_z2 = sum_z2 / (3.0 * SEEDS);
    print_message("z-test false failures: %d of %d seeds at alpha 0.5 (expected <= %.0f); %zu pixel "
                  "tests failed (expected %.1f); mean image z^2 %.3f (expected 1); worst pixel |z| "
                  "at the defaults %.3f\n",
                  runs_failed, SEEDS, 0.5 * SEEDS, pixel_failures, expect_pixels, mean_z2,
                  worst_default);
    assert_true(runs_failed >= 8 && runs_failed <= 32); /* 20 +- 3.8 sd */
    assert_true(fabs((double)pixel_failures - expect_pixels) <= 4.0 * sqrt(expect_pixels) + 1.0);
    assert_true(fabs(mean_z2 - 1.0) <= 4.0 * sqrt(2.0 / (3.0 * SEEDS))); /* chi^2 / n */
}

/* (b) A uniform 5% shift with 5% noise per pixel: each pixel's z is about
 * N(1, 1), so the pixel scale passes, but every 8x8 block sums to z ~ 8 and
 * the image to z ~ 64. */
static void test_ztest_shift(void **state)
{
    (void)state;
    char a[1024], b[1024], out[65536];
    tmp_path(a, sizeof a, "zt_shift_a.exr");
    tmp_path(b, sizeof b, "zt_shift_b.exr");
    zt_case k = zt_default(7);
    k.noise = 0.05;
    k.shift = 0.05;
    k.flat = true; /* z ~ N(1, 1) at every pixel */
    for (int counts = 0; counts < 2; counts++) {
        k.counts = counts;
        zt_write(&k, a, b);
        assert_int_equal(zt_run(a, b, "", out, sizeof out), 1);
        zt_row px = zt_parse(out, "pixel"), bl = zt_parse(out, "block"), im = zt_parse(out, "image");
        assert_true(px.failed <= px.limit);
        assert_int_equal(px.limit, 12); /* floor(0.001 * 12288) */
        assert_true(bl.failed >= bl.tests * 9 / 10);
        assert_int_equal(im.failed, 3);
        /* The image z is sum(a - b) / sqrt(sum var) = sum 0.05 mu / sqrt(sum
         * (0.05 mu)^2) + N(0, 1), about 64 + N(0, 1). */
        for (int c = 0; c < 3; c++) {
            double num = 0.0, var = 0.0;
            for (int y = 0; y < 64; y++)
                for (int x = 0; x < 64; x++) {
                    double mu = zt_mu(x, y, c, &k);
                    num += 0.05 * mu;
                    var += (0.05 * mu) * (0.05 * mu);
                }
            double z = zt_image_z(out, rgb[c]), want = num / sqrt(var);
            print_message("shift, %s: image z %s %.3f (expected %.3f +- 1)\n",
                          counts ? "counts" : "own variance", rgb[c], z, want);
            assert_true(fabs(z - want) < 4.5);
        }
        assert_non_null(strstr(out, "FAIL: z-test"));
    }
    /* A 0.1% shift is within the noise at every scale (image z ~ 1.3). */
    k.shift = 0.001;
    k.counts = false;
    zt_write(&k, a, b);
    assert_int_equal(zt_run(a, b, "", out, sizeof out), 0);
    assert_non_null(strstr(out, "PASS: z-test"));
}

/* (c) One outlier pixel: reported at its display-window coordinates, with the
 * block that contains it; a moderate outlier fails its pixel test only (within
 * the accepted fraction), a NaN fails every scale. */
static void test_ztest_outlier(void **state)
{
    (void)state;
    char a[1024], b[1024], heat[1024], out[65536];
    tmp_path(a, sizeof a, "zt_out_a.exr");
    tmp_path(b, sizeof b, "zt_out_b.exr");
    tmp_path(heat, sizeof heat, "zt_heat.exr");
    zt_case k = zt_default(11);
    k.x0 = 10;
    k.y0 = 20;
    k.ox = 37; /* absolute (47, 65); block x 32..39, y 40..47 -> (42, 60)..(49, 67) */
    k.oy = 45;
    k.oc = 1;
    k.out_sigmas = 60.0;
    zt_write(&k, a, b);
    unlink(heat);
    char extra[1100];
    snprintf(extra, sizeof extra, "--heatmap '%s'", heat);
    assert_int_equal(zt_run(a, b, extra, out, sizeof out), 1);
    zt_row px = zt_parse(out, "pixel"), bl = zt_parse(out, "block"), im = zt_parse(out, "image");
    assert_string_equal(px.at, "(47, 65) G");
    assert_true(px.worst > 55.0 && px.worst < 65.0);
    assert_true(px.failed >= 1 && px.failed <= px.limit);
    assert_string_equal(bl.at, "(42, 60)..(49, 67) G");
    assert_true(bl.failed >= 1);
    assert_int_equal(im.failed, 0);
    const char *list = strstr(out, "failing pixels: ");
    assert_non_null(list);
    assert_non_null(strstr(list, "\n  (47, 65) G: a "));
    list = strstr(out, "failing blocks: ");
    assert_non_null(list);
    assert_non_null(strstr(list, "\n  (42, 60)..(49, 67) G: sum(a-b) "));
    /* The heatmap: |z| per pixel, largest at the outlier. */
    exr_image h;
    hz_error err = {0};
    if (exr_read(heat, &h, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(h.data_x0, 10);
    assert_int_equal(h.data_y0, 20);
    float top = 0.0f;
    int top_i = -1;
    for (int i = 0; i < 64 * 64; i++)
        if (h.channels[0].pixels[i] > top) {
            top = h.channels[0].pixels[i];
            top_i = i;
        }
    assert_int_equal(top_i, 45 * 64 + 37);
    assert_float_equal(top, px.worst, 1e-3);
    exr_image_free(&h);

    /* 8 sigma: the pixel test fails (z ~ 8 > 4.74), its block (z ~ 1 + 8/8) and
     * the image pass, and one failure is within floor(0.001 * 12288) = 12. */
    k.out_sigmas = 8.0;
    zt_write(&k, a, b);
    assert_int_equal(zt_run(a, b, "", out, sizeof out), 0);
    px = zt_parse(out, "pixel");
    assert_string_equal(px.at, "(47, 65) G");
    assert_true(px.failed >= 1);
    assert_non_null(strstr(out, "\n  (47, 65) G: a "));
    assert_non_null(strstr(out, "PASS: z-test"));
    assert_int_equal(zt_run(a, b, "--accept 1", out, sizeof out), 1); /* no failure accepted */
    assert_non_null(strstr(out, "FAIL: z-test"));

    /* A NaN in A fails its pixel, its block and the image test of G. */
    k.nan_outlier = true;
    zt_write(&k, a, b);
    assert_int_equal(zt_run(a, b, "", out, sizeof out), 1);
    px = zt_parse(out, "pixel");
    bl = zt_parse(out, "block");
    im = zt_parse(out, "image");
    assert_string_equal(px.at, "(47, 65) G");
    assert_true(isnan(px.worst));
    assert_string_equal(bl.at, "(42, 60)..(49, 67) G");
    assert_int_equal(im.failed, 1);
    assert_string_equal(im.at, "G");
}

/* (d) The per-test level is 1 - (1 - alpha)^(1/N) over N = (pixels + blocks +
 * 1) * channels, partial edge blocks included. */
static void test_ztest_sidak(void **state)
{
    (void)state;
    char a[1024], b[1024], out[65536];
    tmp_path(a, sizeof a, "zt_sidak_a.exr");
    tmp_path(b, sizeof b, "zt_sidak_b.exr");
    zt_case k = zt_default(3);
    k.w = 13; /* 2 x 2 blocks: 8 + 5 columns, 8 + 3 rows */
    k.h = 11;
    zt_write(&k, a, b);
    const struct {
        const char *extra;
        double alpha;
        int channels;
    } cases[] = {{"", 0.01, 3}, {"--alpha 0.05", 0.05, 3}, {"--alpha 1e-6 --channels G", 1e-6, 1},
                 {"--channels B,R --alpha 0.3", 0.3, 2}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        assert_int_equal(zt_run(a, b, cases[i].extra, out, sizeof out), 0);
        double n = (13.0 * 11.0 + 4.0 + 1.0) * cases[i].channels;
        double want = -expm1(log1p(-cases[i].alpha) / n);
        double got = zt_parse_level(out);
        if (got != want)
            fail_msg("%s: level %.17g, want %.17g", cases[i].extra, got, want);
        /* The naive formula agrees to rounding. */
        assert_true(fabs(got - (1.0 - pow(1.0 - cases[i].alpha, 1.0 / n))) <= 1e-15);
        zt_row bl = zt_parse(out, "block");
        assert_int_equal(bl.tests, 4 * cases[i].channels);
        assert_int_equal(zt_parse(out, "pixel").tests, 143 * cases[i].channels);
        /* The printed critical |z| solves erfc(z / sqrt 2) = level. */
        const char *l = strstr(out, "fails when |z| > ");
        assert_non_null(l);
        double zc = strtod(l + strlen("fails when |z| > "), NULL);
        assert_true(erfc((zc - 1e-4) / sqrt(2.0)) > want && erfc((zc + 1e-4) / sqrt(2.0)) < want);
    }
    /* Channels: R G B in that order, only those B has a variance for. */
    assert_non_null(strstr(out, "channels R B\n"));
}

/* (e) Missing statistics: exit 2 and one line saying what is missing. */
static void test_ztest_errors(void **state)
{
    (void)state;
    char a[1024], b[1024], args[4096];
    tmp_path(a, sizeof a, "zt_err_a.exr");
    tmp_path(b, sizeof b, "zt_err_b.exr");
    zt_case k = zt_default(5);
    k.w = k.h = 9;
    k.b_variance = false;
    zt_write(&k, a, b);
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest", a, b);
    expect_exit2(args, "has no Variance.R, Variance.G or Variance.B");
    /* B has variances and counts, A only a count: fine; A with neither: error. */
    k.b_variance = true;
    k.counts = true;
    zt_write(&k, a, b);
    char out[16384];
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    /* The metrics leave the statistics layers out unless named. */
    assert_null(strstr(out, "\nVariance.R "));
    assert_null(strstr(out, "\nSampleCount.Y "));
    snprintf(args, sizeof args, "diff '%s' '%s' --channels R,SampleCount.Y", a, b);
    assert_int_equal(run_haze(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\nSampleCount.Y "));
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest", ref_exr, b);
    expect_exit2(args, "sizes differ");
    char c[1024];
    tmp_path(c, sizeof c, "zt_err_plain.exr");
    write_image(c, 9, 9, 0, 0, 3, rgb, ref_value);
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest", c, b);
    expect_exit2(args, "no variance for");
    expect_exit2(args, "Variance.R");
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest --channels A", c, b);
    expect_exit2(args, "no channel \"A\"");
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest", b, c); /* the plain one as reference */
    expect_exit2(args, "has no Variance.R");
    /* Invalid reference statistics. */
    static const char *const rv[] = {"R", "G", "B", "Variance.R", "Variance.G", "Variance.B"};
    write_image(c, W, H, 0, 0, 6, rv, offset_value); /* Variance.R = ref + 0.25 > 0 */
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest", ref_exr, c);
    assert_int_equal(run_haze(args, out, sizeof out), 2);
    assert_non_null(strstr(out, "no variance for")); /* A has no statistics */
    write_image(c, W, H, 0, 0, 6, rv, nan_a);
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest", c, c);
    expect_exit2(args, "R is nan at pixel (1, 1)");
    /* A gbuffer film's Variance is of the samples: refused as a z-test's. */
    static const char *const gb[] = {"R", "G", "B", "Variance.R", "Variance.G", "Variance.B",
                                     "RelativeVariance.R"};
    write_image(c, W, H, 0, 0, 7, gb, offset_value);
    snprintf(args, sizeof args, "diff '%s' '%s' --ztest", ref_exr, c);
    expect_exit2(args, "is a Film \"gbuffer\" image");
    /* Options (usage errors add a line pointing at --help). */
    const struct {
        const char *opts, *want;
    } usage[] = {{"--alpha 0.05", "--alpha needs --ztest"},
                 {"--ztest --accept 0.9 --alpha 1", "--alpha must lie strictly between 0 and 1"},
                 {"--ztest --accept 1.5", "--accept must lie in [0, 1]"},
                 {"--ztest --accept x", "--accept needs a finite number"},
                 {"--ztest --alpha", "option --alpha needs a value"}};
    for (size_t i = 0; i < sizeof usage / sizeof usage[0]; i++) {
        snprintf(args, sizeof args, "diff '%s' '%s' %s", a, b, usage[i].opts);
        int rc = run_haze(args, out, sizeof out);
        if (rc != 2 || !strstr(out, usage[i].want))
            fail_msg("haze %s: exit %d, output:\n%s(expected exit 2 and '%s')", args, rc, out,
                     usage[i].want);
    }
}

/* --ztest with --metric: both checks must pass. */
static void test_ztest_with_metric(void **state)
{
    (void)state;
    char a[1024], b[1024], out[65536];
    tmp_path(a, sizeof a, "zt_m_a.exr");
    tmp_path(b, sizeof b, "zt_m_b.exr");
    zt_case k = zt_default(9);
    k.w = k.h = 16;
    zt_write(&k, a, b);
    assert_int_equal(zt_run(a, b, "--metric rmse --threshold 1", out, sizeof out), 0);
    assert_non_null(strstr(out, "PASS: rmse"));
    assert_non_null(strstr(out, "PASS: z-test"));
    assert_int_equal(zt_run(a, b, "--metric rmse --threshold 1e-6", out, sizeof out), 1);
    assert_non_null(strstr(out, "FAIL: rmse"));
    assert_non_null(strstr(out, "PASS: z-test"));
    k.shift = 0.2;
    zt_write(&k, a, b);
    assert_int_equal(zt_run(a, b, "--metric rmse --threshold 1", out, sizeof out), 1);
    assert_non_null(strstr(out, "PASS: rmse"));
    assert_non_null(strstr(out, "FAIL: z-test"));
}

/* (f) Real renders: a reference at 1024 spp with variance and sample count; a
 * re-seeded render at 16 spp passes; the same scene with the point light 5%
 * brighter fails (through the block and image scales: at 16 spp the shift is
 * within each pixel's noise). */
static const char zt_scene[] =
    "LookAt 0 3.2 -2.2   0 0.4 0.6   0 1 0\n"
    "Camera \"perspective\" \"float fov\" 40\n"
    "Film \"rgb\" \"integer xresolution\" 48 \"integer yresolution\" 32\n"
    "    \"bool writevariance\" true \"bool writesamplecount\" true\n"
    "Sampler \"independent\" \"integer pixelsamples\" 16\n"
    "WorldBegin\n"
    "LightSource \"point\" \"point3 from\" [1.5 2.5 -0.5] \"rgb I\" [%s]\n"
    "AttributeBegin\n"
    "  AreaLightSource \"diffuse\" \"rgb L\" [0.6 0.8 1.2]\n"
    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "      \"point3 P\" [-2 3.5 -1  2 3.5 -1  2 3.5 3  -2 3.5 3]\n"
    "AttributeEnd\n"
    "Material \"diffuse\" \"rgb reflectance\" [0.6 0.6 0.6]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "    \"point3 P\" [-8 0 -8  8 0 -8  8 0 8  -8 0 8]\n"
    "Translate 0 0.9 0.6\n"
    "Shape \"sphere\" \"float radius\" 0.5\n";

static void zt_render(const char *intensity, const char *exr, int spp, int seed)
{
    char scene[1024], text[2048], args[4096], out[8192];
    snprintf(scene, sizeof scene, "%s.pbrt", exr);
    snprintf(text, sizeof text, zt_scene, intensity);
    write_text_file(scene, text);
    snprintf(args, sizeof args, "render '%s' -o '%s' --spp %d --seed %d --quiet", scene, exr, spp,
             seed);
    if (run_haze(args, out, sizeof out) != 0)
        fail_msg("haze %s:\n%s", args, out);
}

static void test_ztest_render(void **state)
{
    (void)state;
    char ref[1024], a[1024], out[65536];
    tmp_path(ref, sizeof ref, "zt_render_ref.exr");
    tmp_path(a, sizeof a, "zt_render_a.exr");
    zt_render("12 9 6", ref, 1024, 1);
    for (int seed = 2; seed <= 4; seed++) {
        zt_render("12 9 6", a, 16, seed);
        int rc = zt_run(a, ref, "", out, sizeof out);
        zt_row px = zt_parse(out, "pixel"), bl = zt_parse(out, "block");
        print_message("re-seeded render (seed %d): exit %d, pixel tests failed %zu (limit %zu), "
                      "worst pixel z %.3f, worst block z %.3f, image z R %.3f G %.3f B %.3f\n",
                      seed, rc, px.failed, px.limit, px.worst, bl.worst, zt_image_z(out, "R"),
                      zt_image_z(out, "G"), zt_image_z(out, "B"));
        if (rc != 0)
            fail_msg("a re-seeded render fails the z-test:\n%s", out);
        assert_non_null(strstr(out, "variance of A: the larger of A's own Variance and B's "
                                    "Variance x SampleCount.Y"));
    }
    zt_render("12.6 9.45 6.3", a, 16, 2);
    assert_int_equal(zt_run(a, ref, "", out, sizeof out), 1);
    zt_row px = zt_parse(out, "pixel"), bl = zt_parse(out, "block"), im = zt_parse(out, "image");
    print_message("point light 5%% brighter: pixel tests failed %zu (limit %zu), block tests failed "
                  "%zu of %zu, image z R %.3f G %.3f B %.3f\n",
                  px.failed, px.limit, bl.failed, bl.tests, zt_image_z(out, "R"), zt_image_z(out, "G"),
                  zt_image_z(out, "B"));
    assert_true(bl.failed > 0);
    assert_int_equal(im.failed, 3);
    assert_true(zt_image_z(out, "R") > 10.0); /* the warm light shows most in R */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_identical),          cmocka_unit_test(test_constant_offset),
        cmocka_unit_test(test_max_location),       cmocka_unit_test(test_thresholds),
        cmocka_unit_test(test_nonfinite_excluded), cmocka_unit_test(test_heatmaps),
        cmocka_unit_test(test_heatmap_guarded),
        cmocka_unit_test(test_input_errors),       cmocka_unit_test(test_usage),
        cmocka_unit_test(test_idiff_agrees),       cmocka_unit_test(test_ztest_false_failures),
        cmocka_unit_test(test_ztest_shift),        cmocka_unit_test(test_ztest_outlier),
        cmocka_unit_test(test_ztest_sidak),        cmocka_unit_test(test_ztest_errors),
        cmocka_unit_test(test_ztest_with_metric),  cmocka_unit_test(test_ztest_render),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
