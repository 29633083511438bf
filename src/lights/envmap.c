/* The images of lights (envmap.h): an image infinite light's equal-area
 * octahedral square map of the sphere of directions (pbrt-v4's
 * ImageInfiniteLight), looked up at the nearest texel and importance sampled
 * by the piecewise-constant density of its texels' channel average; the same
 * image serves goniometric, projection and image area lights. */
#include "lights/envmap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/sampling.h"
#include "film/exr.h"

struct light_image {
    int w, h;
    float *rgb;      /* w * h texels of 3 floats, row-major, top row (v = 0) first */
    double *row_cdf; /* h + 1: the marginal over rows, cdf[0] = 0, cdf[h] = 1 */
    double *cdf;     /* h rows of w + 1: the conditional cdf within each row */
    double *func;    /* w * h: the sampling function (channel average, >= 0) */
    double mean;     /* of func over the texels; 0: sampled uniformly */
    size_t negative; /* texels that had a negative channel (read as 0) */
};

void light_image_destroy(light_image *m)
{
    if (!m)
        return;
    free(m->rgb);
    free(m->row_cdf);
    free(m->cdf);
    free(m->func);
    free(m);
}

/* Cumulative sums of f[0..n) normalised to end at 1 (uniform when f sums to
 * 0); returns the sum. */
static double build_cdf(const double *f, int n, double *cdf)
{
    cdf[0] = 0.0;
    for (int i = 0; i < n; ++i)
        cdf[i + 1] = cdf[i] + f[i];
    double sum = cdf[n];
    for (int i = 1; i <= n; ++i)
        cdf[i] = sum > 0.0 ? cdf[i] / sum : (double)i / n;
    cdf[n] = 1.0;
    return sum;
}

/* The map of w x h texels from three channel planes (negative values read
 * as 0), with its sampling tables; `what` names it in errors. */
static hz_status image_build(int w, int h, const float *const ch[3], const char *what,
                             light_image **out, hz_error *err)
{
    size_t n = (size_t)w * (size_t)h;
    light_image *m = calloc(1, sizeof *m);
    double *rows = malloc((size_t)h * sizeof *rows);
    if (m) {
        m->w = w;
        m->h = h;
        m->rgb = malloc(n * 3 * sizeof *m->rgb);
        m->func = malloc(n * sizeof *m->func);
        m->cdf = malloc((size_t)h * (size_t)(w + 1) * sizeof *m->cdf);
        m->row_cdf = malloc((size_t)(h + 1) * sizeof *m->row_cdf);
    }
    if (!m || !rows || !m->rgb || !m->func || !m->cdf || !m->row_cdf) {
        light_image_destroy(m);
        free(rows);
        return hz_fail(err, "%s: out of memory for a light's image", what);
    }
    for (size_t i = 0; i < n; ++i) {
        double sum = 0.0;
        bool negative = false;
        for (int c = 0; c < 3; ++c) { /* negative radiance is none (pbrt-v4 clamps) */
            float v = ch[c][i] > 0.0f ? ch[c][i] : 0.0f;
            negative |= ch[c][i] < 0.0f;
            m->rgb[3 * i + (size_t)c] = v;
            sum += v;
        }
        m->func[i] = sum / 3.0;
        m->negative += negative;
    }
    double total = 0.0;
    for (int y = 0; y < h; ++y) {
        rows[y] = build_cdf(m->func + (size_t)y * w, w, m->cdf + (size_t)y * (w + 1));
        total += rows[y];
    }
    build_cdf(rows, h, m->row_cdf);
    m->mean = total / (double)n;
    free(rows);
    *out = m;
    return HZ_OK;
}

hz_status light_image_from_exr(const char *path, bool square, light_image **out, hz_error *err)
{
    *out = NULL;
    exr_image img;
    hz_error e;
    if (exr_read(path, &img, &e) != HZ_OK)
        return hz_fail(err, "%s", e.message);
    const exr_channel *ch[3] = {exr_find_channel(&img, "R"), exr_find_channel(&img, "G"),
                                exr_find_channel(&img, "B")};
    const exr_channel *y = exr_find_channel(&img, "Y");
    if (!ch[0] && !ch[1] && !ch[2] && y) /* a luminance map: grey */
        ch[0] = ch[1] = ch[2] = y;
    hz_status st = HZ_OK;
    if (!ch[0] || !ch[1] || !ch[2])
        st = hz_fail(err, "%s: a light's image needs R, G and B channels (or Y alone)", path);
    else if (square && img.width != img.height)
        st = hz_fail(err,
                     "%s: %dx%d is not square: a light's image is an equal-area octahedral "
                     "map of directions (pbrt-v4's imgtool makeequiarea converts others)",
                     path, img.width, img.height);
    int w = img.width;
    size_t n = (size_t)w * (size_t)img.height;
    for (size_t i = 0; st == HZ_OK && i < n; ++i)
        for (int c = 0; c < 3; ++c)
            if (!isfinite(ch[c]->pixels[i])) {
                st = hz_fail(err, "%s: texel (%zu, %zu) is not finite: not usable as a light",
                             path, i % (size_t)w, i / (size_t)w);
                break;
            }
    if (st == HZ_OK) {
        const float *const planes[3] = {ch[0]->pixels, ch[1]->pixels, ch[2]->pixels};
        st = image_build(w, img.height, planes, path, out, err);
    }
    exr_image_free(&img);
    return st;
}

hz_status light_image_white(light_image **out, hz_error *err)
{
    const float one = 1.0f;
    const float *const planes[3] = {&one, &one, &one};
    return image_build(1, 1, planes, "a constant sky", out, err);
}

size_t light_image_negative_texels(const light_image *m) { return m->negative; }

void light_image_size(const light_image *m, int *w, int *h)
{
    *w = m->w;
    *h = m->h;
}

static size_t texel_of(const light_image *m, vec2 uv)
{
    int x = (int)(uv.x * m->w), y = (int)(uv.y * m->h);
    x = x < 0 ? 0 : x >= m->w ? m->w - 1 : x;
    y = y < 0 ? 0 : y >= m->h ? m->h - 1 : y;
    return (size_t)y * (size_t)m->w + (size_t)x;
}

rgb light_image_bilerp(const light_image *m, vec2 uv)
{
    double x = uv.x * m->w - 0.5, y = uv.y * m->h - 0.5;
    double fx = floor(x), fy = floor(y), dx = x - fx, dy = y - fy;
    rgb sum = rgb_grey(0.0);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            int tx = (int)fx + i, ty = (int)fy + j;
            tx = tx < 0 ? 0 : tx >= m->w ? m->w - 1 : tx;
            ty = ty < 0 ? 0 : ty >= m->h ? m->h - 1 : ty;
            const float *t = m->rgb + 3 * ((size_t)ty * (size_t)m->w + (size_t)tx);
            double wgt = (i ? dx : 1.0 - dx) * (j ? dy : 1.0 - dy);
            sum = rgb_add(sum, rgb_scale(rgb_make(t[0], t[1], t[2]), wgt));
        }
    return sum;
}

rgb light_image_lookup(const light_image *m, vec2 uv)
{
    const float *t = m->rgb + 3 * texel_of(m, uv);
    return rgb_make(t[0], t[1], t[2]);
}

double light_image_value(const light_image *m, vec2 uv) { return m->func[texel_of(m, uv)]; }

double light_image_pdf(const light_image *m, vec2 uv)
{
    return m->mean > 0.0 ? m->func[texel_of(m, uv)] / m->mean : 1.0;
}

/* The index i with cdf[i] <= u < cdf[i + 1] among n intervals, skipping
 * empty ones. */
static int find_interval(const double *cdf, int n, double u)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (cdf[mid] <= u)
            lo = mid;
        else
            hi = mid - 1;
    }
    while (lo < n - 1 && !(cdf[lo + 1] > cdf[lo])) /* an empty interval at u */
        ++lo;
    return lo;
}

vec2 light_image_sample(const light_image *m, vec2 u, double *pdf)
{
    int y = find_interval(m->row_cdf, m->h, u.y);
    double dy = m->row_cdf[y + 1] - m->row_cdf[y];
    double fy = dy > 0.0 ? (u.y - m->row_cdf[y]) / dy : 0.5;
    const double *c = m->cdf + (size_t)y * (m->w + 1);
    int x = find_interval(c, m->w, u.x);
    double dx = c[x + 1] - c[x];
    double fx = dx > 0.0 ? (u.x - c[x]) / dx : 0.5;
    vec2 uv = v2((x + fmin(fmax(fx, 0.0), 0x1.fffffffffffffp-1)) / m->w,
                 (y + fmin(fmax(fy, 0.0), 0x1.fffffffffffffp-1)) / m->h);
    *pdf = light_image_pdf(m, uv);
    return uv;
}

double light_image_mean(const light_image *m) { return m->mean; }

double light_image_luminance(const light_image *m)
{
    size_t n = (size_t)m->w * (size_t)m->h;
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i)
        sum += 0.2126 * m->rgb[3 * i] + 0.7152 * m->rgb[3 * i + 1] + 0.0722 * m->rgb[3 * i + 2];
    return sum / (double)n;
}

rgb light_image_average(const light_image *m)
{
    size_t n = (size_t)m->w * (size_t)m->h;
    double s[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
            s[c] += m->rgb[3 * i + (size_t)c];
    return rgb_make(s[0] / n, s[1] / n, s[2] / n);
}

/* pbrt-v4's "illuminance" of an image map: the sum over texels whose centre
 * is in the upper hemisphere (+z in the light's space) of luminance (sRGB
 * weights) times cos theta, times 2 pi / texels (pbrt-v4's factor; the
 * solid angle of a texel is 4 pi / texels, so this is half the illuminance of
 * the map, and pbrt-v4's maps come out twice as bright as asked: haze
 * matches its images). */
double light_image_illuminance(const light_image *m)
{
    double sum = 0.0;
    for (int y = 0; y < m->h; ++y)
        for (int x = 0; x < m->w; ++x) {
            vec3 w = equal_area_square_to_sphere(v2((x + 0.5) / m->w, (y + 0.5) / m->h));
            if (w.z <= 0.0)
                continue;
            const float *t = m->rgb + 3 * ((size_t)y * (size_t)m->w + (size_t)x);
            sum += (0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2]) * w.z;
        }
    return sum * 2.0 * HZ_PI / ((double)m->w * (double)m->h);
}
