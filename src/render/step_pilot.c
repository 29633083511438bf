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
    /* STEP_PILOT_PIXELS, or on small images a 1/STEP_PILOT_SHARE_OF_IMAGE of
     * theirs, so that a pilot of a few renders costs a small part of one
     * sample per pixel; but at least STEP_PILOT_MIN_PIXELS, for an estimate. */
    double n = fmin(STEP_PILOT_PIXELS, fmax(STEP_PILOT_MIN_PIXELS, (double)w * (double)h /
                                                                       STEP_PILOT_SHARE_OF_IMAGE));
    int stride = (int)ceil(sqrt((double)w * (double)h / n));
    if (stride < 1)
        stride = 1;
    pilot_grid g = {fp->bounds.x0 + stride / 2, fp->bounds.y0 + stride / 2, stride, 0, 0};
    g.nx = (fp->bounds.x1 - g.x0 + stride - 1) / stride;
    g.ny = (fp->bounds.y1 - g.y0 + stride - 1) / stride;
    return g;
}

/* The order the pilot takes the grid's pixels in: pixel q of it is grid
 * cell (q * A) mod n, A the integer nearest the golden section of n that is
 * prime to n (n >= 1), so that every prefix is spread over the image. */
static int *pilot_order(int n)
{
    int *order = malloc((size_t)n * sizeof *order);
    if (!order)
        return NULL;
    int a = (int)lround(0.6180339887498949 * n);
    for (;; ++a) { /* Euclid: a prime to n (a = 1 is, for n = 1 and 2) */
        int x = a, y = n;
        while (y) {
            int t = x % y;
            x = y;
            y = t;
        }
        if (x == 1)
            break;
    }
    for (int q = 0; q < n; ++q)
        order[q] = (int)(((long long)q * a) % n);
    return order;
}

typedef struct {
    render_scene *rs;
    const pilot_grid *g;
    const int *order;
    int last; /* the order's pixels to render: up to this one */
    const sampler *smp; /* the scene's, with at least k samples a pixel */
    int k;
    rgb *out;
    const volatile sig_atomic_t *cancel; /* NULL, or a signal's flag: stop */
    atomic_int next; /* the next pixel of the order to take */
    atomic_uint_fast64_t lookups; /* density lookups made (a sum: the same on any threads) */
} pilot_job;

enum { PILOT_PIXELS_PER_TAKE = 16 };

static void *pilot_worker(void *arg)
{
    pilot_job *job = arg;
    const pilot_grid *g = job->g;
    const camera *cam = render_scene_camera(job->rs);
    const sampler *smp = job->smp;
    integrator_counters counters = {0};
    int n = job->last;
    for (;;) {
        int p0 = atomic_fetch_add(&job->next, PILOT_PIXELS_PER_TAKE);
        if (p0 >= n)
            break;
        int p1 = p0 + PILOT_PIXELS_PER_TAKE < n ? p0 + PILOT_PIXELS_PER_TAKE : n;
        for (int p = p0; p < p1; ++p) {
            int cell = job->order[p];
            int x = g->x0 + (cell % g->nx) * g->stride, y = g->y0 + (cell / g->nx) * g->stride;
            camera_sample cs = {v2(x + 0.5, y + 0.5), v2(0.5, 0.5), 0.5, 1.0};
            ray_differential rd;
            bool ray = camera_generate_ray_differential(cam, cs, &rd);
            for (int s = 0; s < job->k; ++s) {
                rgb L = rgb_grey(0.0);
                if (job->cancel && *job->cancel) /* a signal: the image is dropped */
                    return NULL;
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
    atomic_fetch_add(&job->lookups, counters.density_lookups);
    return NULL;
}

/* Pixels first .. last - 1 (of `order`) of the pilot image at `step`: the
 * scene's estimators at each pixel centre, samples 0 .. k - 1 of it
 * (out[pixel * k + sample]), on `threads` threads (each value depends only
 * on its pixel and sample). Returns the density lookups it made. */
static uint64_t pilot_render(render_scene *rs, const render_marching *base, double step,
                         double shadow_ratio, double cache_ratio, const pilot_grid *g,
                         const int *order, int first, int last, const sampler *smp, int k,
                         int threads, const volatile sig_atomic_t *cancel, rgb *out)
{
    render_marching m = *base;
    m.step = step;
    m.shadow_step = step * shadow_ratio;
    m.shadow_cache = step * cache_ratio;
    render_scene_set_marching(rs, &m);
    pilot_job job = {.rs = rs, .g = g, .order = order, .last = last,
                     .smp = smp, .k = k, .out = out, .cancel = cancel};
    atomic_init(&job.next, first);
    atomic_init(&job.lookups, 0);
    hz_parallel_run(threads, pilot_worker, &job);
    return atomic_load(&job.lookups);
}

/* haze diff's relMSE of the expected image a against b, mean of (a -
 * b)^2 / (b + 0.01)^2 over pixels and channels, from k paired samples of
 * each pixel (the same sample indices: their noise is correlated): per pixel
 * and channel the squared mean difference less its variance (s^2 / k of the
 * differences), at least 0. The cut at 0 reads some noise as bias, which
 * errs toward finer steps: without it, the ratio to each pixel's own mean
 * made the bench cloud's estimate for step 2 negative (-1.6e-4 +- 0.8e-4
 * over 512 pixels, where its bias is 1.2e-4) and the pilot chose it at
 * 1e-4. With k = 1 (deterministic estimators) the plain relMSE. *se: the
 * standard error of that mean over the n pixels. */
static double bias_rel_mse(const rgb *a, const rgb *b, int n, int k, double *se, int *differ)
{
    double sum = 0.0, sum2 = 0.0;
    *differ = 0;
    for (int i = 0; i < n; ++i) {
        double pixel = 0.0;
        bool differs = false;
        for (int c = 0; c < 3; ++c) {
            double md = 0.0, mb = 0.0;
            for (int s = 0; s < k; ++s) {
                differs |= rgb_ch(a[(size_t)i * k + s], c) != rgb_ch(b[(size_t)i * k + s], c);
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
            pixel += isfinite(e) ? e / 3.0 : 0.0;
        }
        *differ += differs;
        sum += pixel;
        sum2 += pixel * pixel;
    }
    double mean = n > 0 ? sum / n : 0.0;
    *se = n > 1 ? sqrt(fmax(0.0, sum2 / n - mean * mean) / (n - 1)) : INFINITY;
    return mean;
}

/* A pilot image: pixels 0 .. m - 1 of the order at `step`, and their cost:
 * samples plus density lookups. */
typedef struct {
    rgb *px;
    double step;
    int m;
    double cost;
} pilot_image;

/* What the pilot renders of one choice share. */
typedef struct {
    render_scene *rs;
    const render_marching *base;
    double shadow_ratio, cache_ratio; /* of the shadow step and cache to the step */
    const pilot_grid *g;
    const int *order;
    const sampler *smp;
    int n, k, threads; /* pixels, samples of each, threads */
    int start;         /* pixels a comparison starts with */
    double pixels_img; /* of the image */
    double first_spp, max_spp; /* of the render's first pass; its cap */
    double target;     /* E */
    double cost;       /* samples and density lookups rendered so far */
    int renders;       /* made so far */
    double finest;     /* the finest step rendered */
    int pixels;        /* the most a comparison took */
    double max_step;   /* the coarsest step tried */
    const volatile sig_atomic_t *cancel;
} pilot;

static bool cancelled(const pilot *p) { return p->cancel && *p->cancel; }

/* img's pixels up to m rendered. */
static void pilot_extend(pilot *p, pilot_image *img, int m)
{
    if (img->m >= m)
        return;
    double cost = (double)(m - img->m) * p->k +
                  (double)pilot_render(p->rs, p->base, img->step, p->shadow_ratio,
                                       p->cache_ratio, p->g, p->order, img->m, m, p->smp, p->k,
                                       p->threads, p->cancel, img->px);
    p->cost += cost;
    img->cost += cost;
    img->m = m;
}

/* A new pilot image at `step`, its first p->start pixels rendered. */
static void pilot_at(pilot *p, double step, pilot_image *img)
{
    img->step = step;
    img->m = 0;
    img->cost = 0.0;
    pilot_extend(p, img, p->start);
    ++p->renders;
    p->finest = step < p->finest ? step : p->finest;
}

/* What taking both images to m pixels would add to the pilot's cost, at
 * each image's cost a pixel so far. */
static double cost_to(const pilot_image *a, const pilot_image *b, int m)
{
    return (m > a->m ? m - a->m : 0) * (a->cost / a->m) +
           (m > b->m ? m - b->m : 0) * (b->cost / b->m);
}

/* The relMSE of one sample of `img` (its pixels' sample variance over
 * (mean + 0.01)^2, haze diff's weighting; 0 with one sample a pixel): the
 * noise of a pixel centre's estimate, a lower bound of a pixel's. */
static double one_sample_rel_mse(const pilot_image *img, int k)
{
    if (k < 2 || img->m < 1)
        return 0.0;
    double sum = 0.0;
    for (int i = 0; i < img->m; ++i)
        for (int c = 0; c < 3; ++c) {
            double mean = 0.0, var = 0.0;
            for (int s = 0; s < k; ++s)
                mean += rgb_ch(img->px[(size_t)i * k + s], c);
            mean /= k;
            for (int s = 0; s < k; ++s) {
                double d = rgb_ch(img->px[(size_t)i * k + s], c) - mean;
                var += d * d;
            }
            double r = mean + 0.01, e = var / (k - 1) / (r * r);
            sum += isfinite(e) ? e : 0.0;
        }
    return sum / (3.0 * img->m);
}

/* The pilot's budget when it would choose the step of `coarse`: a share of
 * the render at that step, at the cost a sample the pilot measured there.
 * The render takes at least its first pass, and at least the samples that
 * bring the noise of `coarse`'s pixel centres down to E (fewer than it
 * will take: pixels vary over their area too, and the bias takes a share
 * of E), up to its cap. */
static double budget_at(const pilot *p, const pilot_image *coarse)
{
    double spp = fmin(p->max_spp, fmax(p->first_spp, one_sample_rel_mse(coarse, p->k) / p->target));
    return STEP_PILOT_BUDGET * p->pixels_img * spp * (coarse->cost / ((double)coarse->m * p->k));
}

/* The bias of the step of `coarse`, from its relMSE against the half step's
 * `fine` (midpoint marching: halving the step at least halves the error),
 * on as many pixels as the verdict against `goal` needs where it could be
 * wrong at a cost (doubling them, up to the whole grid, while the pilot's
 * cost stays within its budget, budget_at):
 * - a pass that ends the walk (`pass_ends`) chooses the coarse step: it
 *   takes pixels until it lies beyond STEP_PILOT_Z standard errors of the
 *   goal on at least STEP_PILOT_MIN_DIFFER pixels that tell the steps apart;
 * - a failure sends the walk one step finer: within STEP_PILOT_NEAR of the
 *   goal it takes pixels until it lies beyond Z standard errors (a false
 *   one would halve the step chosen); farther it stands as it is;
 * - a pass that does not end the walk changes nothing.
 * A verdict still close when the budget or the grid ends stands: either
 * step's bias is near the goal. */
static double pilot_bias(pilot *p, pilot_image *coarse, pilot_image *fine, double goal,
                         bool pass_ends)
{
    int m = coarse->m < fine->m ? coarse->m : fine->m; /* a new image: its first pixels */
    for (;;) {
        pilot_extend(p, coarse, m);
        pilot_extend(p, fine, m);
        if (cancelled(p)) /* the images are incomplete */
            return INFINITY;
        int differ;
        double se, bias = 2.0 * bias_rel_mse(coarse->px, fine->px, m, p->k, &se, &differ);
        p->pixels = m > p->pixels ? m : p->pixels;
        int more = 2 * m < p->n ? 2 * m : p->n;
        bool close = fabs(bias - goal) <= 2.0 * STEP_PILOT_Z * se;
        bool settled = bias <= goal ? !pass_ends || (!close && differ >= STEP_PILOT_MIN_DIFFER)
                                    : !close || !(bias <= STEP_PILOT_NEAR * goal);
        if (m >= p->n || settled || p->cost + cost_to(coarse, fine, more) > budget_at(p, coarse))
            return bias;
        m = more;
    }
}

static void swap_images(pilot_image **a, pilot_image **b)
{
    pilot_image *t = *a;
    *a = *b;
    *b = t;
}

/* From the coarsest step `top` down: x halves, each x compared with x / 2
 * (img[0] at x, img[1] at x / 2), until an x whose bias meets `goal` below
 * one whose bias did not: that x. A pass above every failure does not
 * count (two steps longer than every chord through the medium march it
 * alike and agree however biased they are), so the walk goes on down; when
 * every x passes down to 2 `floor_` (the scene's step), or down to the
 * finest (x / 2 at least STEP_PILOT_MIN_STEP), the steps agree all the way
 * and `top` is chosen. Below `floor_` only failures lead; at the finest the
 * last x is chosen, failing. *bias: that of the x chosen. The renders go
 * from the cheapest on, and the finest is half the step chosen (about as
 * costly as all the coarser ones together). */
static double go_down(pilot *p, pilot_image **img, double goal, double top, double floor_,
                      double *bias)
{
    double x = top, top_bias = INFINITY;
    bool failed = false;
    pilot_at(p, x, img[0]);
    for (;;) {
        bool finest = x / 2.0 < STEP_PILOT_MIN_STEP, last = finest || x <= 2.0 * floor_;
        pilot_at(p, x / 2.0, img[1]);
        double b = pilot_bias(p, img[0], img[1], goal, failed || last);
        if (x == top)
            top_bias = b;
        if (cancelled(p) || (b <= goal && failed) || (failed && finest)) {
            *bias = b;
            return x;
        }
        failed |= !(b <= goal);
        if (!failed && last) {
            *bias = top_bias;
            return top;
        }
        x /= 2.0;
        swap_images(&img[0], &img[1]);
    }
}

void step_pilot_choose(render_scene *rs, double target_error, int threads,
                       const volatile sig_atomic_t *cancel, step_choice *out)
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
    pilot_image slots[2] = {{malloc(bytes), 0.0, 0, 0.0}, {malloc(bytes), 0.0, 0, 0.0}};
    pilot_image *img[2] = {&slots[0], &slots[1]};
    int *order = n >= 1 ? pilot_order(n) : NULL;
    double goal = STEP_PILOT_SHARE * target_error;
    /* Under "auto" the steps start where it puts them: finer ones march as
     * coarsely as that. */
    double ratio = base.shadow_step / base.step, h = base.step * base.auto_scale;
    /* The shadow cache keeps the scene's ratio to the step, or where the
     * scene has none but could, the step's own spacing. */
    double cache_ratio = base.shadow_cache > 0.0     ? base.shadow_cache / base.step
                         : base.shadow_cache_possible ? 1.0
                                                      : 0.0;
    if (!slots[0].px || !slots[1].px || !order || n < 1) {
        for (int q = 0; q < 2; ++q) /* keep the scene's steps */
            free(slots[q].px);
        free(order);
        return;
    }
    /* The render's first pass takes two samples a pixel (at most spp). */
    const film_params *fp = film_get_params(render_scene_film(rs));
    double max_spp = render_scene_sampler(rs)->spp, first_spp = max_spp < 2 ? max_spp : 2;
    double pixels_img =
        (double)(fp->bounds.x1 - fp->bounds.x0) * (double)(fp->bounds.y1 - fp->bounds.y0);
    pilot p = {rs, &base, ratio, cache_ratio, &g, order, &smp, n, k, threads,
               STEP_PILOT_START_PIXELS < n ? STEP_PILOT_START_PIXELS : n,
               pixels_img, first_spp, max_spp, target_error, 0.0, 0, INFINITY, 0,
               STEP_PILOT_MAX_STEP * base.auto_scale, cancel};
    /* The lattice of steps h 2^j, from the coarsest within max_step down. */
    double top = h;
    while (2.0 * top <= p.max_step)
        top *= 2.0;
    double bias = INFINITY;
    h = go_down(&p, img, goal, top, h, &bias);
    if (cancelled(&p)) { /* the scene's own steps; the render stops at once */
        render_scene_set_marching(rs, &base);
        for (int q = 0; q < 2; ++q)
            free(slots[q].px);
        free(order);
        return;
    }
    render_marching m = base;
    m.step = h;
    m.shadow_step = h * ratio;
    m.shadow_cache = h * cache_ratio;
    render_scene_set_marching(rs, &m);
    render_scene_keep_current_cache(rs);
    render_marching set;
    render_scene_marching(rs, &set); /* 0 if the cache could not be built */
    *out = (step_choice){true,    m.step,   m.shadow_step, set.shadow_cache,
                         bias,    p.pixels, p.renders,     p.finest};
    for (int q = 0; q < 2; ++q)
        free(slots[q].px);
    free(order);
}
