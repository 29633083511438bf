/* `haze diff`: see diff.h. */
#define _POSIX_C_SOURCE 200809L
#include "cli/diff.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli/outputs.h"
#include "core/file.h"
#include "film/exr.h"
#include "film/png.h"

static const char diff_usage[] =
    "usage: haze diff A.exr B.exr [--channels R,G,B] [--metric NAME --threshold X]\n"
    "                 [--ztest [--alpha A] [--accept F]] [--heatmap OUT.exr|OUT.png]\n"
    "  compares A with the reference B over the channels both have (or --channels;\n"
    "  Variance.* and SampleCount.* only when named)\n"
    "  --channels LIST        comma-separated channel names, each present in both\n"
    "  --metric NAME          mse, rmse, relmse, mae, max or psnr (with --threshold):\n"
    "  --threshold X          exit 1 when the overall metric exceeds X (psnr: is below X)\n"
    "  --ztest                z-test A against B's mean and Variance.R/G/B per pixel,\n"
    "                         8x8 block and image (Sidak-corrected); exit 1 when it fails\n"
    "  --alpha A              family-wise significance level of --ztest (default 0.01)\n"
    "  --accept F             fraction of pixel and of block tests that must pass\n"
    "                         (default 0.999); every image test must pass\n"
    "  --heatmap FILE         write the per-pixel mean |A-B| over the channels (with\n"
    "                         --ztest: the largest |z|) as a one-channel EXR, or a\n"
    "                         PNG (max = white) for *.png\n"
    "  exit status: 0 compared (checks passed), 1 a check failed, 2 usage or file error\n";

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

/* A finite number, all of `val`. */
static hz_status parse_number(const char *opt, const char *val, double *x, hz_error *err)
{
    char *end;
    errno = 0;
    *x = strtod(val, &end);
    if (errno || end == val || *end != '\0' || !isfinite(*x))
        return hz_fail(err, "%s needs a finite number, not '%s'", opt, val);
    return HZ_OK;
}

hz_status diff_parse_args(int argc, char **argv, diff_options *opt, bool *help, hz_error *err)
{
    memset(opt, 0, sizeof *opt);
    opt->alpha = 0.01;
    opt->accept = 0.999;
    *help = false;
    bool have_threshold = false, have_alpha = false, have_accept = false;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            *help = true;
            return HZ_OK;
        }
        if (!strcmp(a, "--ztest")) {
            opt->ztest = true;
        } else if (!strcmp(a, "--alpha") || !strcmp(a, "--accept")) {
            if (!val)
                return hz_fail(err, "option %s needs a value", a);
            ++i;
            bool is_alpha = !strcmp(a, "--alpha");
            double x;
            if (parse_number(a, val, &x, err) != HZ_OK)
                return HZ_ERROR;
            if (is_alpha && !(x > 0.0 && x < 1.0))
                return hz_fail(err, "--alpha must lie strictly between 0 and 1, not %s", val);
            if (!is_alpha && !(x >= 0.0 && x <= 1.0))
                return hz_fail(err, "--accept must lie in [0, 1], not %s", val);
            *(is_alpha ? &opt->alpha : &opt->accept) = x;
            *(is_alpha ? &have_alpha : &have_accept) = true;
        } else if (!strcmp(a, "--channels") || !strcmp(a, "--metric") || !strcmp(a, "--threshold") ||
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
                if (parse_number("--threshold", val, &opt->threshold, err) != HZ_OK)
                    return HZ_ERROR;
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
    if ((have_alpha || have_accept) && !opt->ztest)
        return hz_fail(err, "%s needs --ztest", have_alpha ? "--alpha" : "--accept");
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
    size_t bad_only_a;                 /* NaN/Inf in A where B is finite */
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
        s->bad_only_a += !ok_a && ok_b;
        if (!ok_a || !ok_b)
            continue;
        double a = fa, b = fb, d = a - b, ad = fabs(d);
        s->n++;
        s->sum_sq += d * d;
        /* |b|: spectral images hold small negative values (colours beyond
         * sRGB), where b + 0.01 would vanish. */
        s->sum_rel += d * d / ((fabs(b) + 0.01) * (fabs(b) + 0.01));
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
    all->bad_only_a += s->bad_only_a;
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

/* The per-pixel mean over the chosen channels of |a-b| (NaN where no pair is
 * finite); NULL when out of memory. */
static float *mean_abs_heat(const exr_image *a, const diff_stats *st, int nc)
{
    size_t npix = (size_t)a->width * (size_t)a->height;
    float *px = malloc(npix * sizeof *px);
    if (!px)
        return NULL;
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
    }
    return px;
}

/* One-channel ("Y") float EXR in a's windows, or a grey PNG scaled so the
 * largest finite value is white (+inf white too, NaN red). */
static hz_status write_heatmap(const char *path, const exr_image *a, const float *values, hz_error *err)
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
    memcpy(px, values, npix * sizeof *px);
    float peak = 0.0f;
    for (size_t i = 0; i < npix; i++)
        if (isfinite(px[i]) && px[i] > peak)
            peak = px[i];
    hz_status rc;
    if (!file_has_suffix(path, ".png")) {
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
            double v = peak > 0.0f ? px[i] / peak : (px[i] > 0.0f ? 1.0 : 0.0);
            uint8_t g = (uint8_t)(v >= 1.0 ? 255 : v * 255.0 + 0.5);
            rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = g;
        }
        rc = png_out_write_rgb8(path, a->width, a->height, rgb, err);
        free(rgb);
    }
    exr_image_free(&h);
    return rc;
}

/* ---------------------------------------------------------------- z-test */

enum { ZT_BLOCK = 8, ZT_LIST = 10 };

typedef enum { ZT_PIXEL, ZT_BLOCKS, ZT_IMAGE } zt_scale_kind;

typedef struct {
    double z;           /* NaN: A is not finite (or has no sample) there: fails */
    int x0, y0, x1, y1; /* absolute pixel coordinates, inclusive */
    int channel;        /* index into the z-test channels */
    double d, sd;       /* a - b (blocks, image: the sum) and sqrt of its variance */
    double a, b;        /* pixel tests: the two values */
} zt_test;

typedef struct {
    size_t tests, failed, limit;
    bool have_worst;
    zt_test worst;
    int nlist;
    zt_test list[ZT_LIST]; /* the worst failing tests, worst first */
} zt_scale;

typedef struct {
    char name[64];
    const float *a, *b, *var_b;
    const float *var_a; /* A's own Variance.<c>, or NULL */
} zt_channel;

typedef struct {
    zt_channel ch[3];
    int nch;
    const float *count_a, *count_b; /* both, or neither */
    double level;                   /* Sidak per-test level */
    zt_scale scale[3];              /* indexed by zt_scale_kind */
    double image_z[3];
} ztest;

/* How bad a test is: |z|, NaN counting as infinite. */
static double zt_key(double z) { return isnan(z) ? INFINITY : fabs(z); }

static bool zt_fails(double z, double level)
{
    return isnan(z) || erfc(fabs(z) / sqrt(2.0)) < level;
}

/* The |z| above which a test fails: erfc(z / sqrt 2) = level, by bisection. */
static double zt_critical(double level)
{
    double lo = 0.0, hi = 50.0;
    for (int i = 0; i < 200 && hi - lo > 1e-12; i++) {
        double mid = 0.5 * (lo + hi);
        if (erfc(mid / sqrt(2.0)) >= level)
            lo = mid;
        else
            hi = mid;
    }
    return hi;
}

static void zt_record(zt_scale *s, const zt_test *t, double level)
{
    s->tests++;
    double key = zt_key(t->z);
    if (!s->have_worst || key > zt_key(s->worst.z)) {
        s->worst = *t;
        s->have_worst = true;
    }
    if (!zt_fails(t->z, level))
        return;
    s->failed++;
    int at = s->nlist;
    while (at > 0 && key > zt_key(s->list[at - 1].z))
        at--;
    if (at >= ZT_LIST)
        return;
    int last = s->nlist < ZT_LIST ? s->nlist : ZT_LIST - 1;
    memmove(&s->list[at + 1], &s->list[at], (size_t)(last - at) * sizeof s->list[0]);
    s->list[at] = *t;
    if (s->nlist < ZT_LIST)
        s->nlist++;
}

/* A reference statistic must be finite and not negative. */
static hz_status zt_check_values(const char *file, const char *channel, const float *v,
                                 const exr_image *img, bool sign_free, hz_error *err)
{
    size_t npix = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < npix; i++)
        if (!isfinite(v[i]) || (!sign_free && v[i] < 0.0f))
            return hz_fail(err, "--ztest: %s: %s is %g at pixel (%d, %d); the test needs %s values",
                           file, channel, (double)v[i], img->data_x0 + (int)(i % (size_t)img->width),
                           img->data_y0 + (int)(i / (size_t)img->width),
                           sign_free ? "finite" : "finite, non-negative");
    return HZ_OK;
}

/* Picks the channels and the source of A's variance; validates B. */
static hz_status zt_prepare(const diff_options *opt, const exr_image *a, const exr_image *b,
                            const diff_stats *st, int nc, ztest *zt, hz_error *err)
{
    /* A gbuffer film's Variance is pbrt-v4's, of the samples, not of their
     * mean: a z-test against it would pass anything. */
    if (exr_find_channel(b, "RelativeVariance.R") || exr_find_channel(a, "RelativeVariance.R"))
        return hz_fail(err, "--ztest: %s is a Film \"gbuffer\" image, whose Variance is of the "
                            "samples, not of their mean; render the reference with Film \"rgb\" "
                            "\"bool writevariance\" true",
                       exr_find_channel(b, "RelativeVariance.R") ? opt->b : opt->a);
    bool any_rgb = false;
    static const char *const order[] = {"R", "G", "B"}; /* whatever the file's order */
    for (int o = 0; o < 3; o++) {
        int c = 0;
        while (c < nc && strcmp(st[c].name, order[o]) != 0)
            c++;
        if (c == nc)
            continue;
        any_rgb = true;
        char vname[96];
        snprintf(vname, sizeof vname, "Variance.%s", st[c].name);
        const exr_channel *vb = exr_find_channel(b, vname);
        if (!vb)
            continue;
        zt_channel *z = &zt->ch[zt->nch++];
        snprintf(z->name, sizeof z->name, "%s", st[c].name);
        z->a = st[c].a;
        z->b = st[c].b;
        z->var_b = vb->pixels;
        if (zt_check_values(opt->b, st[c].name, z->b, b, true, err) != HZ_OK ||
            zt_check_values(opt->b, vname, z->var_b, b, false, err) != HZ_OK)
            return HZ_ERROR;
    }
    if (!any_rgb)
        return hz_fail(err, "--ztest tests R, G and B, and none of them is compared");
    if (zt->nch == 0)
        return hz_fail(err, "--ztest: the reference %s has no Variance.R, Variance.G or Variance.B "
                            "(render it with Film \"bool writevariance\" true)", opt->b);
    const exr_channel *ca = exr_find_channel(a, "SampleCount.Y");
    const exr_channel *cb = exr_find_channel(b, "SampleCount.Y");
    if (ca && cb) {
        zt->count_a = ca->pixels;
        zt->count_b = cb->pixels;
        if (zt_check_values(opt->a, "SampleCount.Y", ca->pixels, a, false, err) != HZ_OK ||
            zt_check_values(opt->b, "SampleCount.Y", cb->pixels, b, false, err) != HZ_OK)
            return HZ_ERROR;
    }
    for (int c = 0; c < zt->nch; c++) {
        char vname[96];
        snprintf(vname, sizeof vname, "Variance.%s", zt->ch[c].name);
        const exr_channel *va = exr_find_channel(a, vname);
        if (va && zt_check_values(opt->a, vname, va->pixels, a, false, err) != HZ_OK)
            return HZ_ERROR;
        if (!va && !zt->count_a)
            return hz_fail(err,
                           "--ztest: no variance for %s: %s has no SampleCount.Y and %s has no %s "
                           "(render both with Film \"bool writesamplecount\" true, or A with "
                           "\"bool writevariance\" true)",
                           opt->a, ca ? opt->b : opt->a, opt->a, vname);
        zt->ch[c].var_a = va ? va->pixels : NULL;
    }
    return HZ_OK;
}

/* Sums of a - b and of the variances over a block or the image; bad: some
 * pixel in it has no valid test. */
typedef struct {
    double d, var;
    bool bad;
} zt_sum;

/* A's variance at pixel i: the reference's per-sample variance `vb` scaled
 * to A's count (robust when A has few samples), or A's own variance when
 * larger: a rare event that A caught and the reference's samples missed
 * shows in A's own spread, not in B's. Sets *bad where A has no sample and
 * B has. */
static double zt_variance_a(const ztest *zt, const zt_channel *ch, size_t i, double vb,
                            bool *bad)
{
    double va = 0.0;
    if (zt->count_a) {
        if (zt->count_b[i] == 0.0f) {
            va = 0.0; /* B has no sample: its mean and variance are 0 */
        } else if (zt->count_a[i] == 0.0f) {
            va = NAN;
            *bad = true; /* A has no sample where B has */
        } else {
            va = vb * (double)zt->count_b[i] / (double)zt->count_a[i];
        }
    }
    if (ch->var_a && !*bad)
        va = fmax(va, ch->var_a[i]);
    return va;
}

/* The test of pixel (x, y) of channel c, recorded; heat[i] keeps the
 * pixel's largest |z|. Returns what the pixel adds to its block's and the
 * image's sums. */
static zt_sum zt_pixel_test(const exr_image *a, ztest *zt, int c, int x, int y, float *heat)
{
    const zt_channel *ch = &zt->ch[c];
    size_t i = (size_t)y * (size_t)a->width + (size_t)x;
    double vb = ch->var_b[i], av = ch->a[i], b = ch->b[i];
    bool bad = !isfinite(av);
    double va = zt_variance_a(zt, ch, i, vb, &bad);
    double d = av - b, floor_sd = 1e-5 * fmax(fabs(av), fabs(b));
    double var = va + vb + floor_sd * floor_sd;
    zt_test t = {0};
    t.z = bad ? NAN : (d == 0.0 ? 0.0 : d / sqrt(var));
    t.x0 = t.x1 = a->data_x0 + x;
    t.y0 = t.y1 = a->data_y0 + y;
    t.channel = c;
    t.d = d;
    t.sd = sqrt(var);
    t.a = av;
    t.b = b;
    zt_record(&zt->scale[ZT_PIXEL], &t, zt->level);
    float k = (float)zt_key(t.z);
    if (k > heat[i])
        heat[i] = k;
    return (zt_sum){d, var, bad};
}

static void zt_sum_add(zt_sum *s, zt_sum p)
{
    s->d += p.d;
    s->var += p.var;
    s->bad |= p.bad;
}

/* Records the test of a block or the image of channel c, pixels (x0, y0) ..
 * (x1, y1); returns its z. */
static double zt_record_sum(ztest *zt, zt_scale_kind k, int c, zt_sum s, int x0, int y0, int x1,
                            int y1)
{
    zt_test t = {0};
    t.z = s.bad ? NAN : (s.d == 0.0 ? 0.0 : s.d / sqrt(s.var));
    t.x0 = x0;
    t.y0 = y0;
    t.x1 = x1;
    t.y1 = y1;
    t.channel = c;
    t.d = s.d;
    t.sd = sqrt(s.var);
    zt_record(&zt->scale[k], &t, zt->level);
    return t.z;
}

/* The tests of one channel; heat[i] keeps the largest |z| of pixel i. */
static hz_status zt_channel_tests(const exr_image *a, ztest *zt, int c, float *heat, hz_error *err)
{
    int w = a->width, h = a->height;
    int bw = (w + ZT_BLOCK - 1) / ZT_BLOCK, bh = (h + ZT_BLOCK - 1) / ZT_BLOCK;
    size_t nblocks = (size_t)bw * (size_t)bh;
    zt_sum *blocks = calloc(nblocks, sizeof *blocks);
    if (!blocks)
        return hz_fail(err, "out of memory");
    zt_sum image = {0.0, 0.0, false};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            zt_sum p = zt_pixel_test(a, zt, c, x, y, heat);
            zt_sum_add(&blocks[(size_t)(y / ZT_BLOCK) * (size_t)bw + (size_t)(x / ZT_BLOCK)], p);
            zt_sum_add(&image, p);
        }
    for (size_t bi = 0; bi < nblocks; bi++) {
        int bx = (int)(bi % (size_t)bw), by = (int)(bi / (size_t)bw);
        zt_record_sum(zt, ZT_BLOCKS, c, blocks[bi], a->data_x0 + bx * ZT_BLOCK,
                      a->data_y0 + by * ZT_BLOCK,
                      a->data_x0 + ((bx + 1) * ZT_BLOCK < w ? (bx + 1) * ZT_BLOCK : w) - 1,
                      a->data_y0 + ((by + 1) * ZT_BLOCK < h ? (by + 1) * ZT_BLOCK : h) - 1);
    }
    zt->image_z[c] = zt_record_sum(zt, ZT_IMAGE, c, image, a->data_x0, a->data_y0,
                                   a->data_x0 + w - 1, a->data_y0 + h - 1);
    free(blocks);
    return HZ_OK;
}

/* "(x, y) G", "(x0, y0)..(x1, y1) G" or "G". */
static void zt_where(const ztest *zt, zt_scale_kind k, const zt_test *t, char *buf, size_t n)
{
    const char *name = zt->ch[t->channel].name;
    switch (k) {
    case ZT_PIXEL: snprintf(buf, n, "(%d, %d) %s", t->x0, t->y0, name); break;
    case ZT_BLOCKS: snprintf(buf, n, "(%d, %d)..(%d, %d) %s", t->x0, t->y0, t->x1, t->y1, name); break;
    case ZT_IMAGE: snprintf(buf, n, "%s", name); break;
    }
}

static void zt_print(const diff_options *opt, const ztest *zt, int bw, int bh, FILE *out)
{
    static const char *const labels[] = {"pixel", "block", "image"};
    size_t total = zt->scale[0].tests + zt->scale[1].tests + zt->scale[2].tests;
    fprintf(out, "\nz-test of A against the mean and variance of the reference B, channels");
    for (int c = 0; c < zt->nch; c++)
        fprintf(out, " %s", zt->ch[c].name);
    fprintf(out, "\nvariance of A: %s\n",
            zt->count_a ? (zt->ch[0].var_a ? "the larger of A's own Variance and B's Variance x "
                                             "SampleCount.Y of B / SampleCount.Y of A"
                                           : "B's Variance x SampleCount.Y of B / SampleCount.Y of A")
                        : "A's own Variance");
    fprintf(out, "%zu tests (pixels, %dx%d blocks of %dx%d, image), alpha %g, accept %g\n", total,
            bw, bh, ZT_BLOCK, ZT_BLOCK, opt->alpha, opt->accept);
    fprintf(out, "Sidak level per test %.17g: fails when |z| > %.4f\n", zt->level,
            zt_critical(zt->level));
    fprintf(out, "%-6s %9s %9s %9s %12s  %s\n", "scale", "tests", "failed", "limit", "worst z",
            "worst at");
    for (int k = 0; k < 3; k++) {
        const zt_scale *s = &zt->scale[k];
        char at[128];
        zt_where(zt, (zt_scale_kind)k, &s->worst, at, sizeof at);
        fprintf(out, "%-6s %9zu %9zu %9zu %12.4f  %s\n", labels[k], s->tests, s->failed, s->limit,
                s->worst.z, at);
    }
    fprintf(out, "image z:");
    for (int c = 0; c < zt->nch; c++)
        fprintf(out, " %s %.4f", zt->ch[c].name, zt->image_z[c]);
    fprintf(out, "\n");
    for (int k = 0; k < 2; k++) {
        const zt_scale *s = &zt->scale[k];
        if (s->failed == 0) {
            fprintf(out, "failing %ss: none\n", labels[k]);
            continue;
        }
        fprintf(out, "failing %ss: %zu%s\n", labels[k], s->failed,
                s->failed > (size_t)s->nlist ? ", the worst:" : ":");
        for (int i = 0; i < s->nlist; i++) {
            const zt_test *t = &s->list[i];
            char at[128];
            zt_where(zt, (zt_scale_kind)k, t, at, sizeof at);
            if (k == ZT_PIXEL)
                fprintf(out, "  %s: a %.9g b %.9g sd %.6g z %.4f\n", at, t->a, t->b, t->sd, t->z);
            else
                fprintf(out, "  %s: sum(a-b) %.9g sd %.6g z %.4f\n", at, t->d, t->sd, t->z);
        }
    }
}

/* Runs the z-test, prints its report, sets *passed; *heat_out (if not NULL)
 * receives the per-pixel |z| (caller frees). */
static hz_status run_ztest(const diff_options *opt, const exr_image *a, const exr_image *b,
                           const diff_stats *st, int nc, FILE *out, bool *passed, float **heat_out,
                           hz_error *err)
{
    ztest zt;
    memset(&zt, 0, sizeof zt);
    if (zt_prepare(opt, a, b, st, nc, &zt, err) != HZ_OK)
        return HZ_ERROR;
    size_t npix = (size_t)a->width * (size_t)a->height;
    int bw = (a->width + ZT_BLOCK - 1) / ZT_BLOCK, bh = (a->height + ZT_BLOCK - 1) / ZT_BLOCK;
    size_t n = (npix + (size_t)bw * (size_t)bh + 1) * (size_t)zt.nch;
    /* Sidak: 1 - (1 - alpha)^(1/N), without cancellation. */
    zt.level = -expm1(log1p(-opt->alpha) / (double)n);
    float *heat = calloc(npix, sizeof *heat);
    if (!heat)
        return hz_fail(err, "out of memory");
    for (int c = 0; c < zt.nch; c++)
        if (zt_channel_tests(a, &zt, c, heat, err) != HZ_OK) {
            free(heat);
            return HZ_ERROR;
        }
    for (int k = 0; k < 2; k++)
        zt.scale[k].limit = (size_t)floor((1.0 - opt->accept) * (double)zt.scale[k].tests);
    zt.scale[ZT_IMAGE].limit = 0;
    *passed = true;
    for (int k = 0; k < 3; k++)
        *passed = *passed && zt.scale[k].failed <= zt.scale[k].limit;
    zt_print(opt, &zt, bw, bh, out);
    fprintf(out, "%s: z-test: %zu of %zu pixel tests failed (limit %zu), %zu of %zu block tests "
                 "(limit %zu), %zu of %zu image tests (limit 0)\n",
            *passed ? "PASS" : "FAIL", zt.scale[0].failed, zt.scale[0].tests, zt.scale[0].limit,
            zt.scale[1].failed, zt.scale[1].tests, zt.scale[1].limit, zt.scale[2].failed,
            zt.scale[2].tests);
    if (heat_out)
        *heat_out = heat;
    else
        free(heat);
    return HZ_OK;
}

/* ------------------------------------------------------------------ run */

/* Fills st[0..*nc) with the chosen channels; st has room for a's channel count. */
static hz_status choose_channels(const diff_options *opt, const exr_image *a, const exr_image *b,
                                 diff_stats *st, int *nc, hz_error *err)
{
    *nc = 0;
    if (!opt->channels) {
        for (int c = 0; c < a->channel_count; c++) {
            const char *name = a->channels[c].name;
            const exr_channel *cb = exr_find_channel(b, name);
            /* The statistics layers describe the image; compared only on request. */
            if (!cb || !strncmp(name, "Variance.", 9) || !strncmp(name, "SampleCount.", 12))
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

/* A and B must cover the same pixels. */
static hz_status check_same_window(const diff_options *opt, const exr_image *a,
                                   const exr_image *b, hz_error *err)
{
    if (a->width != b->width || a->height != b->height)
        return hz_fail(err, "%s is %d x %d but %s is %d x %d: sizes differ", opt->a, a->width,
                       a->height, opt->b, b->width, b->height);
    if (a->data_x0 != b->data_x0 || a->data_y0 != b->data_y0)
        return hz_fail(err, "data windows differ: (%d, %d) .. (%d, %d) in %s, (%d, %d) .. (%d, %d) in %s",
                       a->data_x0, a->data_y0, a->data_x0 + a->width - 1,
                       a->data_y0 + a->height - 1, opt->a, b->data_x0, b->data_y0,
                       b->data_x0 + b->width - 1, b->data_y0 + b->height - 1, opt->b);
    return HZ_OK;
}

/* The table of the compared channels' figures, `all` their total, and
 * where the largest error is. */
static void print_figures(const diff_options *opt, const exr_image *a, const diff_stats *st,
                          int nc, const diff_stats *all, FILE *out)
{
    fprintf(out, "A: %s\nB: %s (reference)\n", opt->a, opt->b);
    fprintf(out, "%d x %d pixels, data window (%d, %d) .. (%d, %d), %d channel%s:", a->width,
            a->height, a->data_x0, a->data_y0, a->data_x0 + a->width - 1,
            a->data_y0 + a->height - 1, nc, nc == 1 ? "" : "s");
    for (int c = 0; c < nc; c++)
        fprintf(out, " %s", st[c].name);
    fprintf(out, "\nPSNR with peak 1; relMSE = mean (a-b)^2/(|b|+0.01)^2; "
                 "rel diff = (mean A - mean B)/|mean B|; NaN/Inf values are counted and excluded\n\n");
    fprintf(out, "%-10s %12s %12s %12s %12s %12s %-16s %10s %12s %12s %10s %9s %9s\n", "channel",
            "MSE", "RMSE", "relMSE", "MAE", "max", "max at", "PSNR", "mean A", "mean B",
            "rel diff", "NaN/Inf A", "NaN/Inf B");
    for (int c = 0; c < nc; c++)
        print_row(out, &st[c], false);
    print_row(out, all, true);
    fprintf(out, "\n");

    size_t total = (size_t)a->width * (size_t)a->height * (size_t)nc;
    if (all->n < total)
        fprintf(out, "%zu of %zu value pairs excluded (NaN/Inf in A or B)\n", total - all->n, total);
    if (all->n)
        fprintf(out, "max abs error %.9g at pixel (%d, %d) channel %s\n", all->max_abs, all->max_x,
                all->max_y, all->max_channel);
}

/* --metric against --threshold over every compared value; prints the
 * verdict and returns whether it passed. */
static bool metric_passes(const diff_options *opt, const diff_stats *all, FILE *out)
{
    const char *name = metric_name(opt->metric);
    if (all->n == 0) {
        fprintf(out, "FAIL: %s: no finite value pairs to compare\n", name);
        return false;
    }
    if (all->bad_only_a > 0) {
        /* Left out of the metric, a broken pixel would pass unseen. */
        fprintf(out, "FAIL: %s: %zu values are NaN/Inf in A where B is finite\n", name,
                all->bad_only_a);
        return false;
    }
    diff_figures f = figures(all);
    double v = figure_of(&f, opt->metric);
    bool psnr = opt->metric == DIFF_METRIC_PSNR;
    bool passed = psnr ? v >= opt->threshold : v <= opt->threshold;
    fprintf(out, "%s: %s %.9g %s threshold %.9g\n", passed ? "PASS" : "FAIL", name, v,
            passed ? (psnr ? ">=" : "<=") : (psnr ? "<" : ">"), opt->threshold);
    return passed;
}

/* --ztest (which clears *passed when it fails) and --heatmap: the z-test's
 * |z| when it ran, else the mean absolute difference. */
static hz_status ztest_and_heatmap(const diff_options *opt, const exr_image *a,
                                   const exr_image *b, const diff_stats *st, int nc, FILE *out,
                                   bool *passed, hz_error *err)
{
    hz_status rc = HZ_OK;
    float *heat = NULL;
    if (opt->ztest) {
        bool zpass = false;
        rc = run_ztest(opt, a, b, st, nc, out, &zpass, opt->heatmap ? &heat : NULL, err);
        *passed = *passed && zpass;
    }
    if (rc == HZ_OK && opt->heatmap) {
        if (!heat)
            heat = mean_abs_heat(a, st, nc);
        rc = heat ? write_heatmap(opt->heatmap, a, heat, err) : hz_fail(err, "out of memory");
        if (rc == HZ_OK)
            fprintf(out, "heatmap: %s\n", opt->heatmap);
    }
    free(heat);
    return rc;
}

static hz_status compare(const diff_options *opt, const exr_image *a, const exr_image *b, FILE *out,
                         bool *passed, hz_error *err)
{
    if (check_same_window(opt, a, b, err) != HZ_OK)
        return HZ_ERROR;
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
    print_figures(opt, a, st, nc, &all, out);
    *passed = opt->metric == DIFF_METRIC_NONE || metric_passes(opt, &all, out);
    hz_status rc = ztest_and_heatmap(opt, a, b, st, nc, out, passed, err);
    free(st);
    return rc;
}

hz_status diff_run(const diff_options *opt, FILE *out, bool *passed, hz_error *err)
{
    exr_image a, b;
    *passed = false;
    /* OpenEXR would wait for ever on a FIFO's open. */
    if (file_check_regular(opt->a, err) != HZ_OK || file_check_regular(opt->b, err) != HZ_OK)
        return HZ_ERROR;
    /* The heatmap replaces only a regular file, and never an input. */
    char heatmap[PATH_MAX];
    const char *inputs[2] = {opt->a, opt->b};
    if (opt->heatmap &&
        (outputs_check_path(opt->heatmap, file_has_suffix(opt->heatmap, ".png") ? ".png" : ".exr",
                            "heatmap", heatmap, sizeof heatmap, err) != HZ_OK ||
         outputs_refuse_inputs("heatmap", opt->heatmap, heatmap, inputs, 2, "the diff", err) !=
             HZ_OK))
        return HZ_ERROR;
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
    hz_error err = {0};
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
        hz_error_print(errs, &err);
        return 2;
    }
    fwrite(buf, 1, size, out);
    free(buf);
    fflush(out);
    return passed ? 0 : 1;
}
