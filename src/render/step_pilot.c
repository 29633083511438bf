#include "render/step_pilot.h"

#include <math.h>
#include <stdlib.h>

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

/* The pilot image at `step`: raymarch at each pixel centre, sample 0. */
static void pilot_render(render_scene *rs, const render_marching *base, double step,
                         double shadow_ratio, double cache_ratio, const pilot_grid *g, rgb *out)
{
    render_marching m = *base;
    m.mode = TRANSMITTANCE_RAYMARCH;
    m.shadow_mode = TRANSMITTANCE_RAYMARCH;
    m.step = step;
    m.shadow_step = step * shadow_ratio;
    m.shadow_cache = step * cache_ratio;
    render_scene_set_marching(rs, &m);
    const camera *cam = render_scene_camera(rs);
    const sampler *smp = render_scene_sampler(rs);
    integrator_counters counters = {0};
    for (int j = 0; j < g->ny; ++j)
        for (int i = 0; i < g->nx; ++i) {
            int x = g->x0 + i * g->stride, y = g->y0 + j * g->stride;
            camera_sample cs = {v2(x + 0.5, y + 0.5), v2(0.5, 0.5), 0.5, 1.0};
            ray_differential rd;
            rgb L = rgb_grey(0.0);
            if (camera_generate_ray_differential(cam, cs, &rd)) {
                sampler_state st;
                sampler_start(smp, x, y, 0, &st);
                double depth;
                L = render_scene_li(rs, &rd, &st, &depth, &counters);
            }
            out[j * g->nx + i] = L;
        }
}

/* haze diff's relMSE of a against b: mean of (a - b)^2 / (b + 0.01)^2 over
 * pixels and channels. */
static double rel_mse(const rgb *a, const rgb *b, int n)
{
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            double d = rgb_ch(a[i], c) - rgb_ch(b[i], c), r = rgb_ch(b[i], c) + 0.01;
            double e = d * d / (r * r);
            sum += isfinite(e) ? e : 0.0;
        }
    return n > 0 ? sum / (3.0 * n) : 0.0;
}

void step_pilot_choose(render_scene *rs, double target_error, step_choice *out)
{
    *out = (step_choice){0};
    render_marching base;
    if (!render_scene_marching(rs, &base))
        return;
    pilot_grid g = pilot_grid_make(film_get_params(render_scene_film(rs)));
    int n = g.nx * g.ny;
    rgb *img[3] = {malloc((size_t)n * sizeof(rgb)), malloc((size_t)n * sizeof(rgb)),
                   malloc((size_t)n * sizeof(rgb))};
    double goal = STEP_PILOT_SHARE * target_error;
    double ratio = base.shadow_step / base.step, h = base.step;
    /* The shadow cache keeps the scene's ratio to the step, or where the
     * scene has none but could, the step's own spacing. */
    double cache_ratio = base.shadow_cache > 0.0     ? base.shadow_cache / base.step
                         : base.shadow_cache_possible ? 1.0
                                                      : 0.0;
    if (!img[0] || !img[1] || !img[2] || n < 1) { /* keep the scene's steps */
        for (int k = 0; k < 3; ++k)
            free(img[k]);
        return;
    }
    /* Coarser first: twice the step's bias is estimated from it and h
     * (img[0]: at h, img[2]: at 2h), without a render finer than h. */
    int renders = 0;
    double bias = INFINITY;
    pilot_render(rs, &base, h, ratio, cache_ratio, &g, img[0]);
    ++renders;
    bool coarser = false;
    while (2.0 * h <= STEP_PILOT_MAX_STEP) {
        pilot_render(rs, &base, 2.0 * h, ratio, cache_ratio, &g, img[2]);
        ++renders;
        double coarse = 2.0 * rel_mse(img[2], img[0], n);
        if (!(coarse <= goal))
            break;
        coarser = true;
        h *= 2.0;
        bias = coarse;
        rgb *t = img[0];
        img[0] = img[2];
        img[2] = t;
    }
    if (!coarser) {
        /* h itself: finer until its bias (against h / 2 in img[1]) meets
         * the goal. */
        pilot_render(rs, &base, h / 2.0, ratio, cache_ratio, &g, img[1]);
        ++renders;
        bias = 2.0 * rel_mse(img[0], img[1], n);
        while (!(bias <= goal) && h / 2.0 >= STEP_PILOT_MIN_STEP) {
            h /= 2.0;
            rgb *t = img[0];
            img[0] = img[1];
            img[1] = t;
            pilot_render(rs, &base, h / 2.0, ratio, cache_ratio, &g, img[1]);
            ++renders;
            bias = 2.0 * rel_mse(img[0], img[1], n);
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
    for (int k = 0; k < 3; ++k)
        free(img[k]);
}
