/* Helpers shared by the analytic render tests: join scene text, build a
 * render_scene from it and evaluate the integrator for the camera ray through a
 * pixel centre, returning the radiance and the world-space point it hit. */
#ifndef HAZE_TESTS_RENDER_TEST_UTIL_H
#define HAZE_TESTS_RENDER_TEST_UTIL_H

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "render/render_scene.h"
#include "render/renderer.h"

/* a, b and c joined into a new string (free it). */
static inline char *cat(const char *a, const char *b, const char *c)
{
    size_t n = strlen(a) + strlen(b) + strlen(c) + 1;
    char *s = malloc(n);
    assert_non_null(s);
    snprintf(s, n, "%s%s%s", a, b, c);
    return s;
}

static inline render_scene *build_scene_or_fail(const char *text, render_options *opt)
{
    scene_desc sd;
    hz_error err = {0};
    if (scene_parse_string(text, "test.pbrt", &sd, &err) != HZ_OK) {
        print_error("parse: %s\n", err.message);
        fail();
    }
    /* RGB unless asked: these tests check RGB's closed forms (test_spectral
     * asks for the other modes). */
    render_options def = {.seed = 0, .color = RENDER_COLOR_RGB};
    render_scene *rs = NULL;
    hz_status st = render_scene_create(&sd, opt ? opt : &def, NULL, &rs, &err);
    scene_desc_free(&sd);
    if (st != HZ_OK) {
        print_error("build: %s\n", err.message);
        fail();
    }
    return rs;
}

/* Copies the string `src` into dst[n], truncated. */
static inline void copy_text(char *dst, size_t n, const char *src)
{
    size_t len = strlen(src);
    if (len >= n)
        len = n - 1;
    memcpy(dst, src, len);
    dst[len] = '\0';
}

/* Builds and expects failure; returns the message in `msg`. */
static inline void build_scene_expect_error(const char *text, char *msg, size_t n)
{
    scene_desc sd;
    hz_error err = {0};
    msg[0] = '\0';
    if (scene_parse_string(text, "test.pbrt", &sd, &err) != HZ_OK) {
        copy_text(msg, n, err.message);
        return;
    }
    render_options def = {.seed = 0};
    render_scene *rs = NULL;
    hz_status st = render_scene_create(&sd, &def, NULL, &rs, &err);
    scene_desc_free(&sd);
    if (st == HZ_OK) {
        render_scene_destroy(rs);
        print_error("expected an error, scene built fine\n");
        fail();
    }
    copy_text(msg, n, err.message);
}

typedef struct {
    rgb L;
    bool hit;
    vec3 p_world;  /* hit point (world space) when hit */
    double depth;
} pixel_eval;

/* Mean of `spp` samples of the ray through the centre of pixel (px, py). */
static inline pixel_eval eval_pixel(const render_scene *rs, double fx, double fy, int spp)
{
    const camera *cam = render_scene_camera(rs);
    camera_sample cs = {v2(fx, fy), v2(0.5, 0.5), 0.5, 1.0};
    ray_differential rd;
    pixel_eval out = {rgb_grey(0.0), false, v3(0, 0, 0), INFINITY};
    if (!camera_generate_ray_differential(cam, cs, &rd)) {
        print_error("no camera ray at %g %g\n", fx, fy);
        fail();
    }
    integrator_counters counters = {0};
    rgb sum = rgb_grey(0.0);
    /* The scene's sampler with this sample count (indices stay below it). */
    sampler smp = *render_scene_sampler(rs);
    sampler_set_spp(&smp, spp);
    for (int i = 0; i < spp; ++i) {
        sampler_state st;
        sampler_start(&smp, (int)fx, (int)fy, i, &st);
        double depth;
        rgb L = render_scene_li(rs, &rd, &st, &depth, &counters);
        sum = rgb_add(sum, L);
        out.depth = depth;
    }
    out.L = rgb_scale(sum, 1.0 / spp);
    out.hit = isfinite(out.depth);
    if (out.hit) {
        vec3 d = v3_normalize(rd.r.d);
        vec3 p_render = v3_add(rd.r.o, v3_scale(d, out.depth));
        out.p_world = transform_point(&cam->world_from_render, p_render);
    }
    return out;
}

/* Renders the whole film of `rs` on two threads and requires that no sample
 * was non-finite (the film counts and drops them). */
static inline void render_expect_finite(render_scene *rs)
{
    renderer_options opt = {.threads = 2, .progress = NULL};
    render_stats stats;
    hz_error err = {0};
    if (renderer_run(rs, &opt, &stats, &err) != HZ_OK)
        fail_msg("render: %s", err.message);
    assert_int_equal(film_nonfinite_count(render_scene_film(rs)), 0);
}

/* Calls fn(ctx, x, y) for every pixel of a w x h image on two threads (pixels
 * interleaved). fn must not call cmocka (it is not thread-safe). */
typedef void (*pixel_fn)(void *ctx, int x, int y);

typedef struct {
    pixel_fn fn;
    void *ctx;
    int w, h, first, stride;
} pixel_job;

static inline void *pixel_job_run(void *p)
{
    pixel_job *j = p;
    for (int i = j->first; i < j->w * j->h; i += j->stride)
        j->fn(j->ctx, i % j->w, i / j->w);
    return NULL;
}

static inline void for_each_pixel_parallel(int w, int h, pixel_fn fn, void *ctx)
{
    enum { THREADS = 2 };
    pthread_t th[THREADS];
    pixel_job jobs[THREADS];
    for (int t = 0; t < THREADS; ++t) {
        jobs[t] = (pixel_job){fn, ctx, w, h, t, THREADS};
        assert_int_equal(pthread_create(&th[t], NULL, pixel_job_run, &jobs[t]), 0);
    }
    for (int t = 0; t < THREADS; ++t)
        pthread_join(th[t], NULL);
}

static inline void expect_close(double got, double want, double rel, double abs_tol,
                                const char *what, double fx, double fy)
{
    double tol = fmax(rel * fabs(want), abs_tol);
    if (!(fabs(got - want) <= tol)) {
        print_error("%s at pixel (%g, %g): got %.9g, want %.9g (tolerance %.3g)\n", what, fx, fy,
                    got, want, tol);
        fail();
    }
}

static inline void expect_rgb_close(rgb got, rgb want, double rel, double abs_tol,
                                    const char *what, double fx, double fy)
{
    expect_close(got.r, want.r, rel, abs_tol, what, fx, fy);
    expect_close(got.g, want.g, rel, abs_tol, what, fx, fy);
    expect_close(got.b, want.b, rel, abs_tol, what, fx, fy);
}

/* The fog sphere grid (volumes/fog_sphere.vdb) under a distant light, 32x32:
 * singlescatter with `estimator` at `step` voxels, shadow rays at
 * `shadow_step`, the shadow cache at `cache` (0: none). Free it. */
static inline char *fog_sphere_scene(const char *estimator, double step, double shadow_step,
                                     double cache)
{
    char *s = malloc(4096);
    assert_non_null(s);
    snprintf(s, 4096,
             "LookAt 0 0.3 -4  0 0 0  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 35\n"
             "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
             "Integrator \"singlescatter\" \"string transmittance\" \"%s\"\n"
             "    \"float stepsize\" %g \"float shadowstepsize\" %g \"float shadowcache\" %g\n"
             "WorldBegin\n"
             "LightSource \"distant\" \"point3 from\" [1 3 -2] \"point3 to\" [0 0 0]"
             " \"rgb L\" [3 3 3]\n"
             "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"%s\"\n"
             "    \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [12 12 12]\n"
             "AttributeBegin\n  Material \"interface\"\n  MediumInterface \"m\" \"\"\n"
             "  Shape \"sphere\" \"float radius\" 1.1\nAttributeEnd\n",
             estimator, step, shadow_step, cache, HAZE_SCENES "/../volumes/fog_sphere.vdb");
    return s;
}

/* haze diff's relMSE over a w x h image at pixel centres of a (the mean of
 * samples 0 .. a_spp - 1) against b (sample 0); *b_mean (may be NULL) gets
 * b's mean over pixels and channels. */
static inline double centre_rel_mse(const render_scene *a, const render_scene *b, int w, int h,
                                    int a_spp, double *b_mean)
{
    double sum = 0.0, mean = 0.0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            rgb la = eval_pixel(a, x + 0.5, y + 0.5, a_spp).L;
            rgb lb = eval_pixel(b, x + 0.5, y + 0.5, 1).L;
            for (int c = 0; c < 3; ++c) {
                double d = rgb_ch(la, c) - rgb_ch(lb, c), r = rgb_ch(lb, c) + 0.01;
                sum += d * d / (r * r);
                mean += rgb_ch(lb, c);
            }
        }
    if (b_mean)
        *b_mean = mean / (3.0 * w * h);
    return sum / (3.0 * w * h);
}

#endif
