/* haze merge: region renders into one image (cli/merge.h). */
#define _POSIX_C_SOURCE 200809L

#include "cli/merge.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cli/outputs.h"
#include "core/file.h"
#include "film/exr.h"

static const char merge_usage[] =
    "usage: haze merge PART.exr... -o FULL.exr\n"
    "\n"
    "Assembles region renders (haze render --pixelbounds / --cropwindow) into\n"
    "one image. The parts must share the display window, the channels (and\n"
    "their half/float types) and the header attributes, lie inside the display\n"
    "window, not overlap, and together cover it; interrupted (haze:partial)\n"
    "renders are refused. The result is byte-identical to a full render of the\n"
    "same scene, seed and spp. Parts of a --target-error render may differ in\n"
    "the samples they took and the marching step their pilot chose; the whole\n"
    "image's haze:spp, haze:passes (the most), haze:spp_mean, haze:estimated_error\n"
    "(means over its pixels) and haze:stepsize (each part's, when they differ)\n"
    "are written. The output must end in .exr and is never a part, a device, a\n"
    "FIFO or a directory. Exit 0 merged, 1 refused or unwritable, 2 usage.\n";

hz_status merge_parse_args(int argc, char **argv, merge_options *opt, bool *help, hz_error *err)
{
    memset(opt, 0, sizeof *opt);
    *help = false;
    opt->parts = calloc(argc > 0 ? (size_t)argc : 1, sizeof *opt->parts);
    if (!opt->parts)
        return hz_fail(err, "out of memory");
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            *help = true;
            return HZ_OK;
        }
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (i + 1 >= argc)
                return hz_fail(err, "merge: option %s needs a value", a);
            if (opt->output)
                return hz_fail(err, "merge: more than one output given ('%s')", argv[i + 1]);
            opt->output = argv[++i];
        } else if (a[0] == '-' && a[1] != '\0') {
            return hz_fail(err, "merge: unknown option '%s'", a);
        } else {
            opt->parts[opt->part_count++] = a;
        }
    }
    if (opt->part_count == 0)
        return hz_fail(err, "merge needs at least one part (haze merge PART.exr... -o FULL.exr)");
    if (!opt->output)
        return hz_fail(err, "merge needs an output: -o FULL.exr");
    return HZ_OK;
}

void merge_options_free(merge_options *opt)
{
    free(opt->parts);
    opt->parts = NULL;
    opt->part_count = 0;
}

/* ---- checks ---------------------------------------------------------- */

typedef struct {
    int x0, y0, x1, y1;
} merge_box;

static merge_box part_box(const exr_image *img)
{
    return (merge_box){img->data_x0, img->data_y0, img->data_x0 + img->width,
                       img->data_y0 + img->height};
}

/* "[x0,x1)x[y0,y1)", the notation of haze's messages and of --pixelbounds. */
static void format_box(merge_box b, char *buf, size_t n)
{
    snprintf(buf, n, "[%d,%d)x[%d,%d)", b.x0, b.x1, b.y0, b.y1);
}

/* "A,B,G,R (half)" or "A:half,B:half,Z:float" when the types are mixed. */
static void format_channels(const exr_image *img, char *buf, size_t n)
{
    bool mixed = false;
    for (int c = 1; c < img->channel_count; ++c)
        mixed |= img->channels[c].half != img->channels[0].half;
    size_t len = 0;
    buf[0] = '\0';
    for (int c = 0; c < img->channel_count && len < n; ++c)
        len += (size_t)snprintf(buf + len, n - len, "%s%s%s", c ? "," : "", img->channels[c].name,
                                mixed ? (img->channels[c].half ? ":half" : ":float") : "");
    if (!mixed && len < n)
        snprintf(buf + len, n - len, " (%s)", img->channels[0].half ? "half" : "float");
}

static const char *find_attribute(const exr_image *img, const char *name)
{
    for (int a = 0; a < img->attribute_count; ++a)
        if (!strcmp(img->attribute_names[a], name))
            return img->attribute_values[a];
    return NULL;
}

/* The attributes in which the regions of one --target-error render
 * (haze:target_error) differ: each region stops on its own estimate, and its
 * pilot picks the step for its own pixels (docs/regions.md). */
static const char *const per_region_names[] = {"haze:spp", "haze:passes", "haze:spp_mean",
                                               "haze:estimated_error", "haze:stepsize"};
enum { PER_REGION_COUNT = sizeof per_region_names / sizeof per_region_names[0] };

static bool adaptive_part(const exr_image *img)
{
    return find_attribute(img, "haze:target_error") != NULL;
}

static bool per_region_attribute(const char *name)
{
    for (int i = 0; i < PER_REGION_COUNT; ++i)
        if (!strcmp(name, per_region_names[i]))
            return true;
    return false;
}

/* The whole image's value of per-region attribute `name` (every part has
 * it): the most samples and passes, the means over the pixels of the mean
 * samples and of the estimated relMSE (a mean over pixels itself), and the
 * parts' distinct steps in part order, "; " between them. */
static void merged_attribute(const exr_image *parts, int n, const char *name, char *buf,
                             size_t size)
{
    if (!strcmp(name, "haze:stepsize")) {
        size_t len = 0;
        buf[0] = '\0';
        for (int i = 0; i < n; ++i) {
            const char *v = find_attribute(&parts[i], name);
            bool seen = false;
            for (int j = 0; j < i && !seen; ++j)
                seen = !strcmp(v, find_attribute(&parts[j], name));
            if (!seen && len < size)
                len += (size_t)snprintf(buf + len, size - len, "%s%s", len ? "; " : "", v);
        }
        return;
    }
    bool most = !strcmp(name, "haze:spp") || !strcmp(name, "haze:passes");
    double sum = 0.0, pixels = 0.0, top = 0.0;
    for (int i = 0; i < n; ++i) {
        double v = strtod(find_attribute(&parts[i], name), NULL),
               w = (double)parts[i].width * (double)parts[i].height;
        top = i == 0 || v > top ? v : top;
        sum += v * w;
        pixels += w;
    }
    if (most)
        snprintf(buf, size, "%.0f", top);
    else
        snprintf(buf, size, strcmp(name, "haze:spp_mean") ? "%.3g" : "%.3f",
                 pixels > 0.0 ? sum / pixels : 0.0);
}

/* The part `p` (file `pf`) against the first part `r` (file `rf`). */
static hz_status check_like_first(const exr_image *r, const char *rf, const exr_image *p,
                                  const char *pf, hz_error *err)
{
    if (p->display_width != r->display_width || p->display_height != r->display_height)
        return hz_fail(err, "merge: %s has a %dx%d display window but %s has %dx%d: parts of "
                            "different images",
                       pf, p->display_width, p->display_height, rf, r->display_width,
                       r->display_height);
    bool same = p->channel_count == r->channel_count;
    for (int c = 0; same && c < p->channel_count; ++c)
        same = !strcmp(p->channels[c].name, r->channels[c].name) &&
               p->channels[c].half == r->channels[c].half;
    if (!same) {
        char a[1024], b[1024];
        format_channels(p, a, sizeof a);
        format_channels(r, b, sizeof b);
        return hz_fail(err, "merge: %s has channels %s but %s has %s", pf, a, rf, b);
    }
    /* What identifies the render (main.c, outputs_render_id): the scene and
     * every file it reads, the sampler, the seed, the haze version. */
    const char *ip = find_attribute(p, "haze:render"), *ir = find_attribute(r, "haze:render");
    if (!ip || !ir)
        return hz_fail(err,
                       "merge: %s has no \"haze:render\" fingerprint (not rendered by this "
                       "haze): cannot tell that it belongs to the same render",
                       !ip ? pf : rf);
    if (strcmp(ip, ir) != 0)
        return hz_fail(err,
                       "merge: %s and %s are parts of different renders (their scene files, "
                       "samples per pixel or seed differ: haze:render %s vs %s)",
                       pf, rf, ip, ir);
    for (int i = 0; i < 2; ++i) { /* every attribute of each is in the other, equal */
        const exr_image *x = i ? r : p, *y = i ? p : r;
        const char *xf = i ? rf : pf, *yf = i ? pf : rf;
        for (int a = 0; a < x->attribute_count; ++a) {
            const char *v = find_attribute(y, x->attribute_names[a]);
            if (!v)
                return hz_fail(err, "merge: %s has header attribute \"%s\" but %s does not", xf,
                               x->attribute_names[a], yf);
            if (strcmp(v, x->attribute_values[a]) != 0 &&
                !(adaptive_part(x) && adaptive_part(y) && per_region_attribute(x->attribute_names[a])))
                return hz_fail(err, "merge: header attribute \"%s\" is \"%s\" in %s but \"%s\" in %s",
                               x->attribute_names[a], x->attribute_values[a], xf, v, yf);
        }
    }
    return HZ_OK;
}

static hz_status check_part(const exr_image *img, const char *file, hz_error *err)
{
    if (find_attribute(img, "haze:partial"))
        return hz_fail(err, "merge: %s is a partial render (interrupted: header attribute "
                            "haze:partial); render its region again",
                       file);
    merge_box b = part_box(img);
    if (b.x0 < 0 || b.y0 < 0 || b.x1 > img->display_width || b.y1 > img->display_height) {
        char s[96];
        format_box(b, s, sizeof s);
        return hz_fail(err, "merge: %s %s is not inside its %dx%d display window", file, s,
                       img->display_width, img->display_height);
    }
    return HZ_OK;
}

static bool boxes_overlap(merge_box a, merge_box b)
{
    return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
}

/* No overlap (every pair), then no gap: with no overlap and every part
 * inside, the parts cover the display window exactly when their areas add
 * up to its area; otherwise the first uncovered pixel (row by row) and the
 * widest then tallest uncovered rectangle from it are named. */
static hz_status check_tiling(const exr_image *parts, const char *const *files, int n,
                              hz_error *err)
{
    char s1[96], s2[96];
    int64_t area = 0;
    for (int i = 0; i < n; ++i) {
        merge_box bi = part_box(&parts[i]);
        for (int j = 0; j < i; ++j) {
            merge_box bj = part_box(&parts[j]);
            if (!strcmp(files[i], files[j]))
                return hz_fail(err, "merge: %s is given twice", files[i]);
            if (boxes_overlap(bi, bj)) {
                format_box(bj, s1, sizeof s1);
                format_box(bi, s2, sizeof s2);
                return hz_fail(err, "merge: %s %s overlaps %s %s", files[j], s1, files[i], s2);
            }
        }
        area += (int64_t)parts[i].width * parts[i].height;
    }
    int w = parts[0].display_width, h = parts[0].display_height;
    int64_t full = (int64_t)w * h;
    if (area == full)
        return HZ_OK;
    uint8_t *covered = full <= INT64_C(1) << 32 ? calloc((size_t)full, 1) : NULL;
    if (!covered)
        return hz_fail(err, "merge: the parts cover %lld of the %dx%d image's %lld pixels",
                       (long long)area, w, h, (long long)full);
    for (int i = 0; i < n; ++i) {
        merge_box b = part_box(&parts[i]);
        for (int y = b.y0; y < b.y1; ++y)
            memset(covered + (size_t)y * (size_t)w + (size_t)b.x0, 1, (size_t)(b.x1 - b.x0));
    }
    size_t first = 0;
    while (first < (size_t)full && covered[first])
        ++first;
    merge_box g = {(int)(first % (size_t)w), (int)(first / (size_t)w), 0, 0};
    g.x1 = g.x0;
    while (g.x1 < w && !covered[(size_t)g.y0 * (size_t)w + (size_t)g.x1])
        ++g.x1;
    g.y1 = g.y0 + 1;
    while (g.y1 < h) { /* grow downwards while the whole span is uncovered */
        const uint8_t *row = covered + (size_t)g.y1 * (size_t)w;
        int x = g.x0;
        while (x < g.x1 && !row[x])
            ++x;
        if (x < g.x1)
            break;
        ++g.y1;
    }
    free(covered);
    format_box(g, s1, sizeof s1);
    return hz_fail(err, "merge: no part covers pixels %s of the %dx%d image (the parts cover %lld "
                        "of %lld pixels)",
                   s1, w, h, (long long)area, (long long)full);
}

/* ---- the merge ------------------------------------------------------- */

/* Before any part is read: every part is a regular file (a FIFO would block
 * the read for ever), and the output is checked as haze render checks its -o:
 * a device such as /dev/null, a FIFO, a part (by device and inode: "./a.exr",
 * a link) or a name not ending in .exr is never replaced. `target` gets the
 * file to write: the output, or a symlink's target. */
static hz_status check_files(const merge_options *opt, char *target, size_t n, hz_error *err)
{
    hz_error e;
    for (int i = 0; i < opt->part_count; ++i)
        if (file_check_regular(opt->parts[i], &e) != HZ_OK)
            return hz_fail(err, "merge: %s", e.message);
    if (outputs_check_path(opt->output, ".exr", "output", target, n, &e) != HZ_OK ||
        outputs_refuse_inputs("output", opt->output, target, opt->parts,
                              (size_t)opt->part_count, "the merge", &e) != HZ_OK)
        return hz_fail(err, "merge: %s", e.message);
    return HZ_OK;
}

hz_status merge_run(const merge_options *opt, hz_error *err)
{
    char target[PATH_MAX];
    if (check_files(opt, target, sizeof target, err) != HZ_OK)
        return HZ_ERROR;
    int n = opt->part_count;
    exr_image *parts = calloc((size_t)n, sizeof *parts);
    if (!parts)
        return hz_fail(err, "merge: out of memory");
    hz_status st = HZ_OK;
    for (int i = 0; st == HZ_OK && i < n; ++i) {
        if (exr_read(opt->parts[i], &parts[i], err) != HZ_OK) {
            char msg[sizeof err->message];
            snprintf(msg, sizeof msg, "%s", err->message);
            st = hz_fail(err, "merge: %s", msg);
        } else if (check_part(&parts[i], opt->parts[i], err) != HZ_OK ||
                   (i > 0 && check_like_first(&parts[0], opt->parts[0], &parts[i], opt->parts[i],
                                              err) != HZ_OK)) {
            st = HZ_ERROR;
        }
    }
    if (st == HZ_OK)
        st = check_tiling(parts, opt->parts, n, err);
    exr_image full;
    memset(&full, 0, sizeof full);
    if (st == HZ_OK) {
        const exr_image *r = &parts[0];
        st = exr_image_alloc(&full, r->display_width, r->display_height, r->channel_count, err);
        for (int c = 0; st == HZ_OK && c < r->channel_count; ++c) {
            memcpy(full.channels[c].name, r->channels[c].name, sizeof full.channels[c].name);
            full.channels[c].half = r->channels[c].half;
        }
        for (int a = 0; st == HZ_OK && a < r->attribute_count; ++a) {
            const char *name = r->attribute_names[a], *value = r->attribute_values[a];
            char merged[4096];
            if (adaptive_part(r) && per_region_attribute(name)) {
                merged_attribute(parts, n, name, merged, sizeof merged);
                value = merged;
            }
            st = exr_image_add_attribute(&full, name, value, err);
        }
    }
    /* Copy each part into place (channel order is the same in every part). */
    for (int i = 0; st == HZ_OK && i < n; ++i) {
        const exr_image *p = &parts[i];
        for (int c = 0; c < p->channel_count; ++c)
            for (int y = 0; y < p->height; ++y)
                memcpy(full.channels[c].pixels +
                           (size_t)(p->data_y0 + y) * (size_t)full.width + (size_t)p->data_x0,
                       p->channels[c].pixels + (size_t)y * (size_t)p->width,
                       (size_t)p->width * sizeof(float));
        exr_image_free(&parts[i]);
    }
    if (st == HZ_OK)
        st = exr_write(target, &full, err);
    exr_image_free(&full);
    for (int i = 0; i < n; ++i)
        exr_image_free(&parts[i]);
    free(parts);
    return st;
}

int merge_command(int argc, char **argv, FILE *out, FILE *errs)
{
    merge_options opt;
    bool help = false;
    hz_error err = {0};
    if (merge_parse_args(argc, argv, &opt, &help, &err) != HZ_OK) {
        merge_options_free(&opt);
        fprintf(errs, "haze: %s\nTry 'haze merge --help'.\n", err.message);
        return 2;
    }
    if (help) {
        merge_options_free(&opt);
        fputs(merge_usage, out);
        return 0;
    }
    hz_status st = merge_run(&opt, &err);
    merge_options_free(&opt);
    if (st != HZ_OK) {
        hz_error_print(errs, &err);
        return 1;
    }
    return 0;
}
