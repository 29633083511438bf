/* Helpers shared by the media render tests (test_media.c, test_extremes_media.c):
 * scene text (printf strings, closed box meshes), the camera ray through a pixel and
 * per-pixel sample statistics (mean, standard error, finiteness) of render_scene_li,
 * Henyey–Greenstein and the airlight quadrature.
 * Set HAZE_MEDIA_VERBOSE=1 to print the measured errors. */
#ifndef HAZE_TESTS_RENDER_MEDIA_TEST_UTIL_H
#define HAZE_TESTS_RENDER_MEDIA_TEST_UTIL_H

#include <stdarg.h>

#include "render_test_util.h"

#define VOLUMES HAZE_SCENES "/../volumes"

static inline bool verbose(void)
{
    const char *v = getenv("HAZE_MEDIA_VERBOSE");
    return v && v[0] && v[0] != '0';
}

#define note(...)                                                                                  \
    do {                                                                                           \
        if (verbose())                                                                             \
            fprintf(stderr, __VA_ARGS__);                                                          \
    } while (0)

/* ---- scene text ---------------------------------------------------------- */

/* printf into a new string (free it). */
static inline char *sfmt(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    assert_true(n >= 0);
    char *s = malloc((size_t)n + 1);
    assert_non_null(s);
    va_start(ap, fmt);
    vsnprintf(s, (size_t)n + 1, fmt, ap);
    va_end(ap);
    return s;
}

/* A closed box [lo, hi] as one triangle mesh whose normals (pbrt-v4:
 * n = cross(p0 - p2, p1 - p2)) all point out of the box, so a MediumInterface's
 * "inside" is the box's interior. Returns a new "Shape ..." line (free it). */
static inline char *box_mesh(vec3 lo, vec3 hi)
{
    vec3 v[8];
    for (int i = 0; i < 8; ++i)
        v[i] = v3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    int idx[36], k = 0;
    for (int a = 0; a < 3; ++a)
        for (int s = 0; s < 2; ++s) {
            int b = (a + 1) % 3, c = (a + 2) % 3;
            int q[4];
            const int cyc[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
            for (int j = 0; j < 4; ++j)
                q[j] = (s << a) | (cyc[j][0] << b) | (cyc[j][1] << c);
            vec3 n = v3_cross(v3_sub(v[q[0]], v[q[2]]), v3_sub(v[q[1]], v[q[2]]));
            double out_dir = (a == 0 ? n.x : a == 1 ? n.y : n.z) * (s ? 1.0 : -1.0);
            if (out_dir < 0.0) {
                int t = q[1];
                q[1] = q[3];
                q[3] = t;
            }
            const int tri[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
            for (int j = 0; j < 6; ++j)
                idx[k++] = tri[j];
        }
    char pts[1024], ids[512];
    int n = 0;
    for (int i = 0; i < 8; ++i)
        n +=
            snprintf(pts + n, sizeof pts - (size_t)n, "%.17g %.17g %.17g ", v[i].x, v[i].y, v[i].z);
    n = 0;
    for (int i = 0; i < 36; ++i)
        n += snprintf(ids + n, sizeof ids - (size_t)n, "%d ", idx[i]);
    return sfmt("Shape \"trianglemesh\" \"point3 P\" [%s] \"integer indices\" [%s]\n", pts, ids);
}

/* ---- pixel evaluation ---------------------------------------------------- */

/* The camera ray through (fx, fy) with the camera sample eval_pixel uses, in
 * world space (unit direction). */
static inline void camera_ray_world(const render_scene *rs, double fx, double fy, vec3 *o, vec3 *d)
{
    const camera *cam = render_scene_camera(rs);
    camera_sample cs = {v2(fx, fy), v2(0.5, 0.5), 0.5, 1.0};
    ray_differential rd;
    assert_true(camera_generate_ray_differential(cam, cs, &rd));
    *o = transform_point(&cam->world_from_render, rd.r.o);
    *d = v3_normalize(transform_vector(&cam->world_from_render, rd.r.d));
}

typedef struct {
    rgb mean, se; /* sample mean and its standard error, per channel */
    bool finite; /* every sample finite */
    double min; /* smallest channel of any sample */
    uint64_t lookups; /* density lookups of all the samples */
    double max; /* largest channel of any sample */
} pstat;

static inline double ch(rgb c, int i) { return i == 0 ? c.r : i == 1 ? c.g : c.b; }

/* `spp` samples of the camera ray through the centre of pixel (px, py); no
 * cmocka calls (used from worker threads). */
static inline pstat pixel_stats_raw(const render_scene *rs, int px, int py, int spp)
{
    pstat out = {rgb_grey(0.0), rgb_grey(0.0), true, INFINITY, 0, -INFINITY};
    const camera *cam = render_scene_camera(rs);
    camera_sample cs = {v2(px + 0.5, py + 0.5), v2(0.5, 0.5), 0.5, 1.0};
    ray_differential rd;
    if (!camera_generate_ray_differential(cam, cs, &rd)) {
        out.finite = false;
        return out;
    }
    integrator_counters counters = {0};
    double s[3] = {0, 0, 0}, s2[3] = {0, 0, 0};
    /* The scene's sampler with this sample count (sample indices must stay
     * below it). */
    sampler smp = *render_scene_sampler(rs);
    sampler_set_spp(&smp, spp);
    for (int i = 0; i < spp; ++i) {
        sampler_state st;
        sampler_start(&smp, px, py, i, &st);
        double depth;
        rgb L = render_scene_li(rs, &rd, &st, &depth, &counters);
        for (int c = 0; c < 3; ++c) {
            double v = ch(L, c);
            if (!isfinite(v))
                out.finite = false;
            out.min = fmin(out.min, v);
            out.max = fmax(out.max, v);
            s[c] += v;
            s2[c] += v * v;
        }
    }
    double m[3], e[3];
    for (int c = 0; c < 3; ++c) {
        m[c] = s[c] / spp;
        double var = spp > 1 ? fmax(s2[c] - spp * m[c] * m[c], 0.0) / (spp - 1) : 0.0;
        e[c] = sqrt(var / spp);
    }
    out.mean = rgb_make(m[0], m[1], m[2]);
    out.se = rgb_make(e[0], e[1], e[2]);
    out.lookups = counters.density_lookups;
    return out;
}

typedef struct {
    const render_scene *rs;
    int w, spp;
    pstat *out;
} image_job;

static inline void image_pixel(void *ctx, int x, int y)
{
    image_job *j = ctx;
    j->out[y * j->w + x] = pixel_stats_raw(j->rs, x, y, j->spp);
}

/* Statistics of every pixel of a w x h image (row-major), on two threads. */
static inline pstat *image_stats(const render_scene *rs, int w, int h, int spp)
{
    pstat *out = calloc((size_t)w * h, sizeof *out);
    assert_non_null(out);
    image_job job = {rs, w, spp, out};
    for_each_pixel_parallel(w, h, image_pixel, &job);
    for (int i = 0; i < w * h; ++i)
        if (!out[i].finite) {
            print_error("pixel (%d, %d) has a non-finite sample\n", i % w, i / w);
            fail();
        }
    return out;
}

/* Mean and standard error of the mean over a w x h image's pixels. */
static inline void image_mean_se(const render_scene *rs, int w, int h, int spp, rgb *mean, rgb *se)
{
    pstat *px = image_stats(rs, w, h, spp);
    int n = w * h;
    double m[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            m[c] += ch(px[i].mean, c) / n;
            v[c] += ch(px[i].se, c) * ch(px[i].se, c) / ((double)n * n);
        }
    free(px);
    *mean = rgb_make(m[0], m[1], m[2]);
    *se = rgb_make(sqrt(v[0]), sqrt(v[1]), sqrt(v[2]));
}

/* An image mean within noise of `want`, per channel: within four standard
 * errors plus `slack` (rounding, for estimates without noise), and the
 * standard error itself under 1% of `want`. */
static inline void expect_within_noise(rgb mean, rgb se, rgb want, double slack,
                                       const char *what)
{
    for (int c = 0; c < 3; ++c) {
        if (verbose())
            print_message("%s c%d: %.5f +- %.5f, want %.5f\n", what, c, ch(mean, c), ch(se, c),
                          ch(want, c));
        assert_true(ch(se, c) < 0.01 * ch(want, c));
        assert_true(fabs(ch(mean, c) - ch(want, c)) < 4.0 * ch(se, c) + slack);
    }
}

static inline render_scene *build(const char *text) { return build_scene_or_fail(text, NULL); }

/* Henyey–Greenstein with pbrt-v4's convention: cos_theta = dot(wo, wi), both
 * pointing away from the scattering point, forward scattering at -1. */
static inline double hg(double cos_theta, double g)
{
    double denom = 1.0 + g * g + 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * HZ_PI * denom * sqrt(denom));
}

/* Single scattering of an isotropic point light of intensity I at distance D
 * from the ray origin, seen along a ray at angle γ to the light, in a
 * homogeneous medium, over t in [0, tmax]:
 *   L = ∫ σ_s p(wo, wi) I e^{-σ_t t} e^{-σ_t d(t)} / d(t)² dt,
 *   d(t)² = D² + t² - 2 D t cos γ.
 * With h = D sin γ and t = D cos γ + h tan θ, dt / d² = dθ / h, d = h / cos θ
 * and dot(wo, wi) = sin θ, so
 *   L = σ_s I / h ∫_{θa}^{θb} p(sin θ) e^{-σ_t (t(θ) + h / cos θ)} dθ,
 * θa = atan(-D cos γ / h), θb = atan((tmax - D cos γ) / h) (π/2 for tmax = ∞):
 * a smooth integrand on a finite interval, integrated by adaptive Simpson. */
typedef struct {
    double sigma_t, a, h, g; /* a = D cos γ */
} air;

static inline double air_f(const air *p, double theta)
{
    double c = cos(theta);
    if (!(c > 0.0))
        return 0.0;
    double t = p->a + p->h * tan(theta);
    return hg(sin(theta), p->g) * exp(-p->sigma_t * (t + p->h / c));
}

static inline double simpson(const air *p, double a, double b, double fa, double fm, double fb,
                      double whole, double eps, int depth)
{
    double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
    double flm = air_f(p, lm), frm = air_f(p, rm);
    double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    double delta = left + right - whole;
    if (depth <= 0 || fabs(delta) <= 15.0 * eps)
        return left + right + delta / 15.0;
    return simpson(p, a, m, fa, flm, fm, left, 0.5 * eps, depth - 1) +
           simpson(p, m, b, fm, frm, fb, right, 0.5 * eps, depth - 1);
}

static inline double airlight(double sigma_s, double sigma_t, double g, double I, vec3 o, vec3 d,
                       vec3 light, double tmax)
{
    vec3 oc = v3_sub(light, o);
    air p = {sigma_t, v3_dot(oc, d), 0.0, g};
    p.h = v3_length(v3_sub(oc, v3_scale(d, p.a)));
    double ta = atan2(-p.a, p.h);
    double tb = isinf(tmax) ? HZ_PI / 2 : atan2(tmax - p.a, p.h);
    /* Panels first, so a narrow phase peak is not stepped over. */
    double sum = 0.0;
    const int panels = 64;
    for (int i = 0; i < panels; ++i) {
        double a = ta + (tb - ta) * i / panels, b = ta + (tb - ta) * (i + 1) / panels;
        double fa = air_f(&p, a), fb = air_f(&p, b), fm = air_f(&p, 0.5 * (a + b));
        sum += simpson(&p, a, b, fa, fm, fb, (b - a) / 6.0 * (fa + 4.0 * fm + fb), 1e-13, 40);
    }
    return sigma_s * I / p.h * sum;
}

#endif
