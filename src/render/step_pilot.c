#include "render/step_pilot.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "core/parallel.h"
#include "sampler/sampler.h"

typedef struct {
    int x0, y0, stride, nx, ny;
} pilot_grid;

/* Every stride-th pixel of the film's data window, starting half a stride in. */
static pilot_grid pilot_grid_make(const film_params *fp)
{
    int w = fp->bounds.x1 - fp->bounds.x0, h = fp->bounds.y1 - fp->bounds.y0;
    int stride = (int)floor(sqrt((double)w * (double)h / STEP_PILOT_PIXELS));
    if (stride < 1)
        stride = 1;
    pilot_grid g = {fp->bounds.x0 + stride / 2, fp->bounds.y0 + stride / 2, stride, 0, 0};
    g.nx = (fp->bounds.x1 - g.x0 + stride - 1) / stride;
    g.ny = (fp->bounds.y1 - g.y0 + stride - 1) / stride;
    return g;
}

typedef struct {
    render_scene *rs;
    const pilot_grid *g;
    const sampler *smp; /* the scene's, with at least k samples a pixel */
    int k;
    rgb *out;
    atomic_int next; /* the next pixel of the grid to take */
} pilot_job;

enum { PILOT_PIXELS_PER_TAKE = 16 };

static void *pilot_worker(void *arg)
{
    pilot_job *job = arg;
    const pilot_grid *g = job->g;
    const camera *cam = render_scene_camera(job->rs);
    const sampler *smp = job->smp;
    integrator_counters counters = {0};
    int n = g->nx * g->ny;
    for (;;) {
        int p0 = atomic_fetch_add(&job->next, PILOT_PIXELS_PER_TAKE);
        if (p0 >= n)
            break;
        int p1 = p0 + PILOT_PIXELS_PER_TAKE < n ? p0 + PILOT_PIXELS_PER_TAKE : n;
        for (int p = p0; p < p1; ++p) {
            int x = g->x0 + (p % g->nx) * g->stride, y = g->y0 + (p / g->nx) * g->stride;
            camera_sample cs = {v2(x + 0.5, y + 0.5), v2(0.5, 0.5), 0.5, 1.0};
            ray_differential rd;
            bool ray = camera_generate_ray_differential(cam, cs, &rd);
            for (int s = 0; s < job->k; ++s) {
                rgb L = rgb_grey(0.0);
                if (ray) {
                    sampler_state st;
                    sampler_start(smp, x, y, s, &st);
                    double depth;
                    L = render_scene_li(job->rs, &rd, &st, &depth, &counters);
                }
                job->out[(size_t)p * (size_t)job->k + (size_t)s] = L;
            }
        }
    }
    return NULL;
}

/* The pilot image at `step`: the scene's estimators at each pixel centre,
 * samples 0 .. k - 1 of it (out[pixel * k + sample]), on `threads` threads
 * (each value depends only on its pixel and sample). */
static void pilot_render(render_scene *rs, const render_marching *base, double step,
                         double shadow_ratio, double cache_ratio, const pilot_grid *g,
                         const sampler *smp, int k, int threads, rgb *out)
{
    render_marching m = *base;
    m.step = step;
    m.shadow_step = step * shadow_ratio;
    m.shadow_cache = step * cache_ratio;
    render_scene_set_marching(rs, &m);
    pilot_job job = {.rs = rs, .g = g, .smp = smp, .k = k, .out = out};
    atomic_init(&job.next, 0);
    hz_parallel_run(threads, pilot_worker, &job);
}

/* haze diff's relMSE of the expected image a against b, mean of (a -
 * b)^2 / (b + 0.01)^2 over pixels and channels, from k paired samples of
 * each pixel (the same sample indices: their noise is correlated): per pixel
 * and channel the squared mean difference less its variance (s^2 / k of the
 * differences), at least 0. With k = 1 (deterministic estimators) the plain
 * relMSE. */
static double bias_rel_mse(const rgb *a, const rgb *b, int n, int k)
{
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            double md = 0.0, mb = 0.0;
            for (int s = 0; s < k; ++s) {
                md += rgb_ch(a[(size_t)i * k + s], c) - rgb_ch(b[(size_t)i * k + s], c);
                mb += rgb_ch(b[(size_t)i * k + s], c);
            }
            md /= k;
            mb /= k;
            double var = 0.0;
            for (int s = 0; k > 1 && s < k; ++s) {
                double d = rgb_ch(a[(size_t)i * k + s], c) - rgb_ch(b[(size_t)i * k + s], c) - md;
                var += d * d;
            }
            double sq = k > 1 ? md * md - var / ((double)k * (k - 1)) : md * md;
            double r = mb + 0.01, e = sq > 0.0 ? sq / (r * r) : 0.0;
            sum += isfinite(e) ? e : 0.0;
        }
    return n > 0 ? sum / (3.0 * n) : 0.0;
}

void step_pilot_choose(render_scene *rs, double target_error, int threads, step_choice *out)
{
    *out = (step_choice){0};
    render_marching base;
    if (!render_scene_marching(rs, &base))
        return;
    pilot_grid g = pilot_grid_make(film_get_params(render_scene_film(rs)));
    int n = g.nx * g.ny;
    /* Jittered marching (or tracked shadows) is random: several samples of
     * each pixel centre, so that the noise can be told from the bias. */
    int k = base.mode == TRANSMITTANCE_RAYMARCH && base.shadow_mode == TRANSMITTANCE_RAYMARCH
                ? 1
                : STEP_PILOT_SAMPLES;
    /* The pilot's samples are its own: a render capped at fewer samples
     * (--spp 2) still gets k of them, not a noisier estimate (with k = 2 on
     * the bench cloud at E = 1e-4 that read as bias and chose step 0.125
     * instead of 1: 9 s instead of 0.35 s). */
    sampler smp = *render_scene_sampler(rs);
    if (smp.spp < k)
        sampler_set_spp(&smp, k);
    size_t bytes = (size_t)n * (size_t)k * sizeof(rgb);
    rgb *img[3] = {malloc(bytes), malloc(bytes), malloc(bytes)};
    double goal = STEP_PILOT_SHARE * target_error;
    double ratio = base.shadow_step / base.step, h = base.step;
    /* The shadow cache keeps the scene's ratio to the step, or where the
     * scene has none but could, the step's own spacing. */
    double cache_ratio = base.shadow_cache > 0.0     ? base.shadow_cache / base.step
                         : base.shadow_cache_possible ? 1.0
                                                      : 0.0;
    if (!img[0] || !img[1] || !img[2] || n < 1) { /* keep the scene's steps */
        for (int q = 0; q < 3; ++q)
            free(img[q]);
        return;
    }
    /* Coarser first, and cheapest first: the bias of 2x is estimated from x
     * and 2x (img[0]: at x, img[2]: at 2x), starting at x = 2h, so a scene
     * whose step goes coarser never renders its own; only when twice its step
     * fails is h rendered (img[1]), for the bias of 2h. Nothing finer than h
     * is rendered unless h fails. */
    int renders = 0;
    double bias = INFINITY, x = 4.0 * h <= STEP_PILOT_MAX_STEP ? 2.0 * h : h;
    pilot_render(rs, &base, x, ratio, cache_ratio, &g, &smp, k, threads, img[0]);
    ++renders;
    bool coarser = false;
    while (2.0 * x <= STEP_PILOT_MAX_STEP) {
        pilot_render(rs, &base, 2.0 * x, ratio, cache_ratio, &g, &smp, k, threads, img[2]);
        ++renders;
        double coarse = 2.0 * bias_rel_mse(img[2], img[0], n, k);
        if (!(coarse <= goal))
            break;
        coarser = true;
        x *= 2.0;
        bias = coarse;
        rgb *t = img[0];
        img[0] = img[2];
        img[2] = t;
    }
    if (coarser) {
        h = x;
    } else if (x > h) {
        pilot_render(rs, &base, h, ratio, cache_ratio, &g, &smp, k, threads, img[1]);
        ++renders;
        double coarse = 2.0 * bias_rel_mse(img[0], img[1], n, k);
        if (coarse <= goal) {
            coarser = true;
            h = x;
            bias = coarse;
        } else { /* img[0]: at h */
            rgb *t = img[0];
            img[0] = img[1];
            img[1] = t;
        }
    }
    if (!coarser) {
        /* h itself: finer until its bias (against h / 2 in img[1]) meets
         * the goal. */
        pilot_render(rs, &base, h / 2.0, ratio, cache_ratio, &g, &smp, k, threads, img[1]);
        ++renders;
        bias = 2.0 * bias_rel_mse(img[0], img[1], n, k);
        while (!(bias <= goal) && h / 2.0 >= STEP_PILOT_MIN_STEP) {
            h /= 2.0;
            rgb *t = img[0];
            img[0] = img[1];
            img[1] = t;
            pilot_render(rs, &base, h / 2.0, ratio, cache_ratio, &g, &smp, k, threads, img[1]);
            ++renders;
            bias = 2.0 * bias_rel_mse(img[0], img[1], n, k);
        }
    }
    render_marching m = base;
    m.step = h;
    m.shadow_step = h * ratio;
    m.shadow_cache = h * cache_ratio;
    render_scene_set_marching(rs, &m);
    render_scene_keep_current_cache(rs);
    render_marching set;
    render_scene_marching(rs, &set); /* 0 if the cache could not be built */
    *out = (step_choice){true, m.step, m.shadow_step, set.shadow_cache, bias, n, renders};
    for (int q = 0; q < 3; ++q)
        free(img[q]);
}
