/* `haze diff`: see diff.h. */
#define _POSIX_C_SOURCE 200809L
#include "cli/diff.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "film/exr.h"
#include "film/png.h"

static const char diff_usage[] =
    "usage: haze diff A.exr B.exr [--channels R,G,B] [--metric NAME --threshold X]\n"
    "                 [--heatmap OUT.exr|OUT.png]\n"
    "  compares A with the reference B over the channels both have (or --channels)\n"
    "  --channels LIST        comma-separated channel names, each present in both\n"
    "  --metric NAME          mse, rmse, relmse, mae, max or psnr (with --threshold):\n"
    "  --threshold X          exit 1 when the overall metric exceeds X (psnr: is below X)\n"
    "  --heatmap FILE         write the per-pixel mean |A-B| over the channels as a\n"
    "                         one-channel EXR, or a PNG (max error = white) for *.png\n"
    "  exit status: 0 compared (check passed), 1 check failed, 2 usage or file error\n";

static const struct {
    const char *name;
    diff_metric metric;
} metric_names[] = {
    {"mse", DIFF_METRIC_MSE}, {"rmse", DIFF_METRIC_RMSE}, {"relmse", DIFF_METRIC_RELMSE},
    {"mae", DIFF_METRIC_MAE}, {"max", DIFF_METRIC_MAX},   {"psnr", DIFF_METRIC_PSNR},
};

static const char *metric_name(diff_metric m)
{
    for (size_t i = 0; i < sizeof metric_names / sizeof metric_names[0]; i++)
        if (metric_names[i].metric == m)
            return metric_names[i].name;
    return "none";
}

hz_status diff_parse_args(int argc, char **argv, diff_options *opt, bool *help, hz_error *err)
{
    memset(opt, 0, sizeof *opt);
    *help = false;
    bool have_threshold = false;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            *help = true;
            return HZ_OK;
        }
        if (!strcmp(a, "--channels") || !strcmp(a, "--metric") || !strcmp(a, "--threshold") ||
            !strcmp(a, "--heatmap")) {
            if (!val)
                return hz_fail(err, "option %s needs a value", a);
            ++i;
            if (!strcmp(a, "--channels")) {
                if (!val[0])
                    return hz_fail(err, "--channels needs a comma-separated list of names");
                opt->channels = val;
            } else if (!strcmp(a, "--heatmap")) {
                if (!val[0])
                    return hz_fail(err, "--heatmap needs a file name");
                opt->heatmap = val;
            } else if (!strcmp(a, "--metric")) {
                opt->metric = DIFF_METRIC_NONE;
                for (size_t m = 0; m < sizeof metric_names / sizeof metric_names[0]; m++)
                    if (!strcasecmp(val, metric_names[m].name))
                        opt->metric = metric_names[m].metric;
                if (opt->metric == DIFF_METRIC_NONE)
                    return hz_fail(err,
                                   "unknown metric '%s' (metrics: mse, rmse, relmse, mae, max, psnr)",
                                   val);
            } else {
                char *end;
                errno = 0;
                double x = strtod(val, &end);
                if (errno || end == val || *end != '\0' || !isfinite(x))
                    return hz_fail(err, "--threshold needs a finite number, not '%s'", val);
                opt->threshold = x;
                have_threshold = true;
            }
        } else if (a[0] == '-' && a[1] != '\0') {
            return hz_fail(err, "unknown option '%s'", a);
        } else if (!opt->a) {
            opt->a = a;
        } else if (!opt->b) {
            opt->b = a;
        } else {
            return hz_fail(err, "diff takes two images ('%s' is extra)", a);
        }
    }
    if (!opt->b)
        return hz_fail(err, "diff needs two EXR images");
    if (opt->metric != DIFF_METRIC_NONE && !have_threshold)
        return hz_fail(err, "--metric %s needs --threshold X", metric_name(opt->metric));
    if (opt->metric == DIFF_METRIC_NONE && have_threshold)
        return hz_fail(err, "--threshold needs --metric NAME");
    return HZ_OK;
}

/* ------------------------------------------------------------ statistics */

typedef struct {
    char name[64];
    const float *a, *b;
    size_t n;                          /* finite pairs */
    double sum_sq, sum_rel, sum_abs, sum_a, sum_b;
    double max_abs;                    /* -1 until a finite pair is seen */
    int max_x, max_y;                  /* data-window coordinates of max_abs */
    char max_channel[64];
    size_t bad_a, bad_b;               /* NaN/Inf values in A, in B */
} diff_stats;

typedef struct {
    double mse, rmse, relmse, mae, max, psnr, mean_a, mean_b, rel_mean;
} diff_figures;

static void stats_init(diff_stats *s, const char *name)
{
    memset(s, 0, sizeof *s);
    snprintf(s->name, sizeof s->name, "%s", name);
    s->max_abs = -1.0;
}

static diff_figures figures(const diff_stats *s)
{
    diff_figures f;
    double n = (double)s->n;
    f.mse = s->sum_sq / n;
    f.rmse = sqrt(f.mse);
    f.relmse = s->sum_rel / n;
    f.mae = s->sum_abs / n;
    f.max = s->max_abs;
    f.psnr = f.mse > 0.0 ? 10.0 * log10(1.0 / f.mse) : INFINITY;
    f.mean_a = s->sum_a / n;
    f.mean_b = s->sum_b / n;
    if (f.mean_b != 0.0)
        f.rel_mean = (f.mean_a - f.mean_b) / fabs(f.mean_b);
    else
        f.rel_mean = f.mean_a == 0.0 ? 0.0 : copysign(INFINITY, f.mean_a);
    return f;
}

static double figure_of(const diff_figures *f, diff_metric m)
{
    switch (m) {
    case DIFF_METRIC_MSE: return f->mse;
    case DIFF_METRIC_RMSE: return f->rmse;
    case DIFF_METRIC_RELMSE: return f->relmse;
    case DIFF_METRIC_MAE: return f->mae;
    case DIFF_METRIC_MAX: return f->max;
    case DIFF_METRIC_PSNR: return f->psnr;
    default: return NAN;
    }
}

static void accumulate(diff_stats *s, const exr_image *img)
{
    size_t npix = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < npix; i++) {
        float fa = s->a[i], fb = s->b[i];
        bool ok_a = isfinite(fa), ok_b = isfinite(fb);
        s->bad_a += !ok_a;
        s->bad_b += !ok_b;
        if (!ok_a || !ok_b)
            continue;
        double a = fa, b = fb, d = a - b, ad = fabs(d);
        s->n++;
        s->sum_sq += d * d;
        s->sum_rel += d * d / ((b + 0.01) * (b + 0.01));
        s->sum_abs += ad;
        s->sum_a += a;
        s->sum_b += b;
        if (ad > s->max_abs) {
            s->max_abs = ad;
            s->max_x = img->data_x0 + (int)(i % (size_t)img->width);
            s->max_y = img->data_y0 + (int)(i / (size_t)img->width);
            snprintf(s->max_channel, sizeof s->max_channel, "%s", s->name);
        }
    }
}

static void merge(diff_stats *all, const diff_stats *s)
{
    all->n += s->n;
    all->sum_sq += s->sum_sq;
    all->sum_rel += s->sum_rel;
    all->sum_abs += s->sum_abs;
    all->sum_a += s->sum_a;
    all->sum_b += s->sum_b;
    all->bad_a += s->bad_a;
    all->bad_b += s->bad_b;
    if (s->n && s->max_abs > all->max_abs) {
        all->max_abs = s->max_abs;
        all->max_x = s->max_x;
        all->max_y = s->max_y;
        snprintf(all->max_channel, sizeof all->max_channel, "%s", s->max_channel);
    }
}

static void print_row(FILE *out, const diff_stats *s, bool overall)
{
    fprintf(out, "%-10s", s->name);
    if (s->n == 0) {
        fprintf(out, " %12s %12s %12s %12s %12s %-16s %10s %12s %12s %10s", "-", "-", "-", "-",
                "-", "-", "-", "-", "-", "-");
    } else {
        diff_figures f = figures(s);
        char at[96];
        if (overall)
            snprintf(at, sizeof at, "(%d,%d,%s)", s->max_x, s->max_y, s->max_channel);
        else
            snprintf(at, sizeof at, "(%d,%d)", s->max_x, s->max_y);
        fprintf(out, " %12.6g %12.6g %12.6g %12.6g %12.6g %-16s %10.6g %12.6g %12.6g %10.6g", f.mse,
                f.rmse, f.relmse, f.mae, f.max, at, f.psnr, f.mean_a, f.mean_b, f.rel_mean);
    }
    fprintf(out, " %9zu %9zu\n", s->bad_a, s->bad_b);
}

/* --------------------------------------------------------------- heatmap */

static bool ends_with_png(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && !strcasecmp(path + n - 4, ".png");
}

static hz_status write_heatmap(const char *path, const exr_image *a, const diff_stats *st, int nc,
                               hz_error *err)
{
    exr_image h;
    if (exr_image_alloc(&h, a->width, a->height, 1, err) != HZ_OK)
        return HZ_ERROR;
    h.data_x0 = a->data_x0;
    h.data_y0 = a->data_y0;
    h.display_width = a->display_width;
    h.display_height = a->display_height;
    snprintf(h.channels[0].name, sizeof h.channels[0].name, "Y");
    h.channels[0].half = false;
    float *px = h.channels[0].pixels;
    size_t npix = (size_t)a->width * (size_t)a->height;
    float peak = 0.0f;
    for (size_t i = 0; i < npix; i++) {
        double sum = 0.0;
        int n = 0;
        for (int c = 0; c < nc; c++) {
            float va = st[c].a[i], vb = st[c].b[i];
            if (isfinite(va) && isfinite(vb)) {
                sum += fabs((double)va - (double)vb);
                n++;
            }
        }
        px[i] = n ? (float)(sum / n) : NAN;
        if (n && px[i] > peak)
            peak = px[i];
    }
    hz_status rc;
    if (!ends_with_png(path)) {
        rc = exr_write(path, &h, err);
    } else {
        uint8_t *rgb = malloc(npix * 3);
        if (!rgb) {
            exr_image_free(&h);
            return hz_fail(err, "%s: out of memory for the heatmap", path);
        }
        for (size_t i = 0; i < npix; i++) {
            if (isnan(px[i])) { /* no finite pair: red */
                rgb[3 * i] = 255;
                rgb[3 * i + 1] = rgb[3 * i + 2] = 0;
                continue;
            }
            double v = peak > 0.0f ? px[i] / peak : 0.0;
            uint8_t g = (uint8_t)(v >= 1.0 ? 255 : v * 255.0 + 0.5);
            rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = g;
        }
        rc = png_out_write_rgb8(path, a->width, a->height, rgb, err);
        free(rgb);
    }
    exr_image_free(&h);
    return rc;
}

/* ------------------------------------------------------------------ run */

/* Fills st[0..*nc) with the chosen channels; st has room for a's channel count. */
static hz_status choose_channels(const diff_options *opt, const exr_image *a, const exr_image *b,
                                 diff_stats *st, int *nc, hz_error *err)
{
    *nc = 0;
    if (!opt->channels) {
        for (int c = 0; c < a->channel_count; c++) {
            const exr_channel *cb = exr_find_channel(b, a->channels[c].name);
            if (!cb)
                continue;
            stats_init(&st[*nc], a->channels[c].name);
            st[*nc].a = a->channels[c].pixels;
            st[*nc].b = cb->pixels;
            ++*nc;
        }
        if (*nc == 0)
            return hz_fail(err, "%s and %s have no channel in common", opt->a, opt->b);
        return HZ_OK;
    }
    const char *p = opt->channels;
    for (;;) {
        size_t len = strcspn(p, ",");
        char name[64];
        if (len == 0 || len >= sizeof name)
            return hz_fail(err, "--channels: bad channel list '%s'", opt->channels);
        memcpy(name, p, len);
        name[len] = '\0';
        const exr_channel *ca = exr_find_channel(a, name);
        const exr_channel *cb = exr_find_channel(b, name);
        if (!ca || !cb)
            return hz_fail(err, "%s: no channel \"%s\"", ca ? opt->b : opt->a, name);
        for (int c = 0; c < *nc; c++)
            if (!strcmp(st[c].name, name))
                return hz_fail(err, "--channels: \"%s\" is listed twice", name);
        if (*nc >= a->channel_count)
            return hz_fail(err, "--channels: bad channel list '%s'", opt->channels);
        stats_init(&st[*nc], name);
        st[*nc].a = ca->pixels;
        st[*nc].b = cb->pixels;
        ++*nc;
        if (p[len] == '\0')
            break;
        p += len + 1;
    }
    return HZ_OK;
}

static hz_status compare(const diff_options *opt, const exr_image *a, const exr_image *b, FILE *out,
                         bool *passed, hz_error *err)
{
    if (a->width != b->width || a->height != b->height)
        return hz_fail(err, "%s is %d x %d but %s is %d x %d: sizes differ", opt->a, a->width,
                       a->height, opt->b, b->width, b->height);
    if (a->data_x0 != b->data_x0 || a->data_y0 != b->data_y0)
        return hz_fail(err, "data windows differ: (%d, %d) .. (%d, %d) in %s, (%d, %d) .. (%d, %d) in %s",
                       a->data_x0, a->data_y0, a->data_x0 + a->width - 1,
                       a->data_y0 + a->height - 1, opt->a, b->data_x0, b->data_y0,
                       b->data_x0 + b->width - 1, b->data_y0 + b->height - 1, opt->b);
    diff_stats *st = calloc((size_t)(a->channel_count > 0 ? a->channel_count : 1), sizeof *st);
    if (!st)
        return hz_fail(err, "out of memory");
    int nc = 0;
    if (choose_channels(opt, a, b, st, &nc, err) != HZ_OK) {
        free(st);
        return HZ_ERROR;
    }
    diff_stats all;
    stats_init(&all, "all");
    for (int c = 0; c < nc; c++) {
        accumulate(&st[c], a);
        merge(&all, &st[c]);
    }

    fprintf(out, "A: %s\nB: %s (reference)\n", opt->a, opt->b);
    fprintf(out, "%d x %d pixels, data window (%d, %d) .. (%d, %d), %d channel%s:", a->width,
            a->height, a->data_x0, a->data_y0, a->data_x0 + a->width - 1,
            a->data_y0 + a->height - 1, nc, nc == 1 ? "" : "s");
    for (int c = 0; c < nc; c++)
        fprintf(out, " %s", st[c].name);
    fprintf(out, "\nPSNR with peak 1; relMSE = mean (a-b)^2/(b+0.01)^2; "
                 "rel diff = (mean A - mean B)/|mean B|; NaN/Inf values are counted and excluded\n\n");
    fprintf(out, "%-10s %12s %12s %12s %12s %12s %-16s %10s %12s %12s %10s %9s %9s\n", "channel",
            "MSE", "RMSE", "relMSE", "MAE", "max", "max at", "PSNR", "mean A", "mean B",
            "rel diff", "NaN/Inf A", "NaN/Inf B");
    for (int c = 0; c < nc; c++)
        print_row(out, &st[c], false);
    print_row(out, &all, true);
    fprintf(out, "\n");

    size_t total = (size_t)a->width * (size_t)a->height * (size_t)nc;
    if (all.n < total)
        fprintf(out, "%zu of %zu value pairs excluded (NaN/Inf in A or B)\n", total - all.n, total);
    if (all.n)
        fprintf(out, "max abs error %.9g at pixel (%d, %d) channel %s\n", all.max_abs, all.max_x,
                all.max_y, all.max_channel);

    *passed = true;
    if (opt->metric != DIFF_METRIC_NONE) {
        const char *name = metric_name(opt->metric);
        if (all.n == 0) {
            *passed = false;
            fprintf(out, "FAIL: %s: no finite value pairs to compare\n", name);
        } else {
            diff_figures f = figures(&all);
            double v = figure_of(&f, opt->metric);
            bool psnr = opt->metric == DIFF_METRIC_PSNR;
            *passed = psnr ? v >= opt->threshold : v <= opt->threshold;
            fprintf(out, "%s: %s %.9g %s threshold %.9g\n", *passed ? "PASS" : "FAIL", name, v,
                    *passed ? (psnr ? ">=" : "<=") : (psnr ? "<" : ">"), opt->threshold);
        }
    }

    hz_status rc = HZ_OK;
    if (opt->heatmap) {
        rc = write_heatmap(opt->heatmap, a, st, nc, err);
        if (rc == HZ_OK)
            fprintf(out, "heatmap: %s\n", opt->heatmap);
    }
    free(st);
    return rc;
}

hz_status diff_run(const diff_options *opt, FILE *out, bool *passed, hz_error *err)
{
    exr_image a, b;
    *passed = false;
    if (exr_read(opt->a, &a, err) != HZ_OK)
        return HZ_ERROR;
    if (exr_read(opt->b, &b, err) != HZ_OK) {
        exr_image_free(&a);
        return HZ_ERROR;
    }
    hz_status rc = compare(opt, &a, &b, out, passed, err);
    exr_image_free(&a);
    exr_image_free(&b);
    return rc;
}

int diff_command(int argc, char **argv, FILE *out, FILE *errs)
{
    diff_options opt;
    bool help = false;
    hz_error err = {{0}};
    if (diff_parse_args(argc, argv, &opt, &help, &err) != HZ_OK) {
        fprintf(errs, "haze: %s\nTry 'haze diff --help'.\n", err.message);
        return 2;
    }
    if (help) {
        fputs(diff_usage, out);
        return 0;
    }
    /* The report goes to a memory stream first, so a failure halfway (a
     * heatmap that cannot be written) prints just the one error line. */
    char *buf = NULL;
    size_t size = 0;
    FILE *mem = open_memstream(&buf, &size);
    if (!mem) {
        fprintf(errs, "haze: out of memory\n");
        return 2;
    }
    bool passed = false;
    hz_status rc = diff_run(&opt, mem, &passed, &err);
    fclose(mem);
    if (rc != HZ_OK) {
        free(buf);
        fprintf(errs, "haze: %s\n", err.message);
        return 2;
    }
    fwrite(buf, 1, size, out);
    free(buf);
    fflush(out);
    return passed ? 0 : 1;
}
