/* The bare-Embree yardstick of `make bench` (bench/README.md): builds a
 * surfaces-only scene through haze's own scene code (parser, camera, sampler,
 * Embree geometry, lights), then traces the camera rays haze traces (the same
 * sampler and pixel filter give the same rays) and one shadow ray per light
 * per hit (haze's direct lighting with delta lights) with plain
 * rtcIntersect1/rtcOccluded1, shading trivially (Lambert with one albedo, no
 * materials, no film). What haze spends beyond this loop is its own overhead.
 *
 * Usage: embree_loop SCENE.pbrt [--spp N] [--threads N] [--packet N] [--camera-only]
 * --packet 4, 8 or 16 traces the camera rays of that many neighbouring pixels
 * of a row (the same sample index) as one packet (rtcIntersect4/8/16) instead
 * of one by one (1, the default); the shadow rays stay single.
 * --camera-only traces no shadow rays.
 * Prints one line: wall time of the loop, rays traced, and the image mean (so
 * the work cannot be optimised away). */
#define _POSIX_C_SOURCE 200809L

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "geometry/geometry.h"
#include "lights/lights.h"
#include "render/render_scene.h"
#include "render/renderer.h"
#include "sampler/sampler.h"
#include "scene/scene_desc.h"

typedef struct {
    const render_scene *rs;
    RTCScene scene;
    int spp, width, height;
    int packet;       /* camera rays per rtcIntersectN: 1, 4, 8 or 16 */
    bool camera_only; /* no shadow rays */
    atomic_int next_row;
} loop_job;

typedef struct {
    loop_job *job;
    double sum;
    unsigned long long camera_rays, shadow_rays;
} loop_worker;

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A camera ray's hit: its distance (INFINITY: none) and Embree's normal. */
typedef struct {
    float t;
    vec3 ng;
} loop_hit;

static loop_hit trace1(loop_worker *w, const ray *r)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = (float)r->o.x, rh.ray.org_y = (float)r->o.y, rh.ray.org_z = (float)r->o.z;
    rh.ray.dir_x = (float)r->d.x, rh.ray.dir_y = (float)r->d.y, rh.ray.dir_z = (float)r->d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.time = 0.0f; /* static scenes only: no time steps */
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(w->job->scene, &ctx, &rh);
    w->camera_rays++;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return (loop_hit){INFINITY, v3(0.0, 0.0, 0.0)};
    return (loop_hit){rh.ray.tfar, v3((double)rh.hit.Ng_x, (double)rh.hit.Ng_y, (double)rh.hit.Ng_z)};
}

/* rays[0..n) (n <= 16; valid[k] false: no ray) as one packet of `size`
 * (4, 8 or 16). The SoA layouts of RTCRayHit4/8/16 are the same up to the
 * width: one generic one of 16 lanes, passed with its width. */
static void trace_packet(loop_worker *w, const ray *rays, const bool *valid, int n, int size,
                         loop_hit *out)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTC_ALIGN(64) int lanes[16];
    RTC_ALIGN(64) struct RTCRayHit16 rh16;
    RTC_ALIGN(64) struct RTCRayHit8 rh8;
    RTC_ALIGN(64) struct RTCRayHit4 rh4;
    /* fill through pointers to the fields of the chosen width */
#define FILL(RH)                                                                    \
    for (int k = 0; k < size; ++k) {                                                \
        bool on = k < n && valid[k];                                                \
        lanes[k] = on ? -1 : 0;                                                     \
        const ray *r = &rays[on ? k : 0];                                           \
        RH.ray.org_x[k] = (float)r->o.x, RH.ray.org_y[k] = (float)r->o.y;           \
        RH.ray.org_z[k] = (float)r->o.z;                                            \
        RH.ray.dir_x[k] = (float)r->d.x, RH.ray.dir_y[k] = (float)r->d.y;           \
        RH.ray.dir_z[k] = (float)r->d.z;                                            \
        RH.ray.tnear[k] = 0.0f, RH.ray.tfar[k] = INFINITY, RH.ray.time[k] = 0.0f;   \
        RH.ray.mask[k] = 0xFFFFFFFFu, RH.ray.id[k] = 0, RH.ray.flags[k] = 0;        \
        RH.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                                 \
        RH.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;                              \
    }
#define READ(RH)                                                                    \
    for (int k = 0; k < n; ++k)                                                     \
        out[k] = !valid[k] || RH.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID           \
                     ? (loop_hit){INFINITY, v3(0.0, 0.0, 0.0)}                      \
                     : (loop_hit){RH.ray.tfar[k], v3((double)RH.hit.Ng_x[k],       \
                                                     (double)RH.hit.Ng_y[k],       \
                                                     (double)RH.hit.Ng_z[k])};
    switch (size) {
    case 4:
        FILL(rh4)
        rtcIntersect4(lanes, w->job->scene, &ctx, &rh4);
        READ(rh4)
        break;
    case 8:
        FILL(rh8)
        rtcIntersect8(lanes, w->job->scene, &ctx, &rh8);
        READ(rh8)
        break;
    default:
        FILL(rh16)
        rtcIntersect16(lanes, w->job->scene, &ctx, &rh16);
        READ(rh16)
        break;
    }
#undef FILL
#undef READ
    for (int k = 0; k < n; ++k)
        w->camera_rays += valid[k];
}

static double shade(loop_worker *w, const ray *r, loop_hit h)
{
    loop_job *job = w->job;
    if (!(h.t < INFINITY) || job->camera_only)
        return isfinite(h.t) ? 1.0 : 0.0;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    vec3 p = ray_at(r, (double)h.t);
    /* Embree's unnormalised normal (object space under instances: enough for
     * trivial shading), turned toward the camera. haze's spheres leave it 0
     * (it computes their normals in double afterwards): face the camera. */
    vec3 ng = h.ng;
    vec3 n = v3_dot(ng, ng) > 0.0 ? v3_normalize(ng) : v3_neg(r->d);
    if (v3_dot(n, r->d) > 0.0)
        n = v3_neg(n);
    double L = 0.0;
    size_t nl = render_scene_light_count(job->rs);
    const light *lights = render_scene_lights(job->rs);
    for (size_t i = 0; i < nl; ++i) {
        light_sample ls;
        if (!light_sample_li(&lights[i], p, n, r->time, v2(0.5, 0.5), &ls))
            continue;
        double cos_theta = v3_dot(n, ls.wi);
        if (cos_theta <= 0.0 || ls.pdf <= 0.0)
            continue;
        vec3 o = geometry_offset_origin(p, n, ls.wi);
        struct RTCRay sr;
        memset(&sr, 0, sizeof sr);
        sr.org_x = (float)o.x, sr.org_y = (float)o.y, sr.org_z = (float)o.z;
        sr.dir_x = (float)ls.wi.x, sr.dir_y = (float)ls.wi.y, sr.dir_z = (float)ls.wi.z;
        sr.tnear = 0.0f;
        sr.tfar = ls.infinite || !isfinite(ls.dist)
                      ? INFINITY
                      : (float)(ls.dist * (1.0 - GEOMETRY_SHADOW_EPSILON));
        sr.time = 0.0f;
        sr.mask = 0xFFFFFFFFu;
        rtcOccluded1(job->scene, &ctx, &sr);
        w->shadow_rays++;
        if (sr.tfar >= 0.0f) /* not occluded (Embree sets tfar to -inf on a hit) */
            L += 0.5 / 3.14159265358979 * (ls.L.r + ls.L.g + ls.L.b) / 3.0 * cos_theta / ls.pdf;
    }
    return L;
}

static void *worker_main(void *p)
{
    loop_worker *w = p;
    loop_job *job = w->job;
    const camera *cam = render_scene_camera(job->rs);
    const sampler *smp = render_scene_sampler(job->rs);
    const filter *flt = render_scene_filter(job->rs);
    for (;;) {
        int y = atomic_fetch_add(&job->next_row, 1);
        if (y >= job->height)
            break;
        if (job->packet <= 1) {
            for (int x = 0; x < job->width; ++x)
                for (int i = 0; i < job->spp; ++i) {
                    sampler_state st;
                    sampler_start(smp, x, y, i, &st);
                    camera_sample cs = renderer_camera_sample(flt, &st, x, y);
                    ray r;
                    if (camera_generate_ray(cam, cs, &r))
                        w->sum += shade(w, &r, trace1(w, &r)) * cs.filter_weight;
                }
            continue;
        }
        for (int x0 = 0; x0 < job->width; x0 += job->packet)
            for (int i = 0; i < job->spp; ++i) {
                ray rays[16];
                bool valid[16];
                double weight[16];
                loop_hit hits[16];
                int n = job->width - x0 < job->packet ? job->width - x0 : job->packet;
                for (int k = 0; k < n; ++k) {
                    sampler_state st;
                    sampler_start(smp, x0 + k, y, i, &st);
                    camera_sample cs = renderer_camera_sample(flt, &st, x0 + k, y);
                    weight[k] = cs.filter_weight;
                    valid[k] = camera_generate_ray(cam, cs, &rays[k]);
                }
                trace_packet(w, rays, valid, n, job->packet, hits);
                for (int k = 0; k < n; ++k)
                    if (valid[k])
                        w->sum += shade(w, &rays[k], hits[k]) * weight[k];
            }
    }
    return NULL;
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    int spp = 0, threads = 1, packet = 1;
    bool camera_only = false;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--spp") == 0 && i + 1 < argc)
            spp = atoi(argv[++i]);
        else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (strcmp(argv[i], "--packet") == 0 && i + 1 < argc)
            packet = atoi(argv[++i]);
        else if (strcmp(argv[i], "--camera-only") == 0)
            camera_only = true;
        else if (!path && argv[i][0] != '-')
            path = argv[i];
        else {
            fprintf(stderr, "usage: embree_loop SCENE.pbrt [--spp N] [--threads N] "
                            "[--packet 1|4|8|16] [--camera-only]\n");
            return 2;
        }
    }
    if (!path || threads < 1 || threads > 256 || spp < 0 ||
        (packet != 1 && packet != 4 && packet != 8 && packet != 16)) {
        fprintf(stderr, "usage: embree_loop SCENE.pbrt [--spp N] [--threads N] [--packet 1|4|8|16] "
                        "[--camera-only]\n");
        return 2;
    }
    hz_error err = {0};
    scene_desc sd;
    if (scene_parse_file(path, &sd, &err) != HZ_OK) {
        fprintf(stderr, "embree_loop: %s\n", err.message);
        return 1;
    }
    render_options ro = {.seed = 0, .spp = spp, .output = NULL};
    render_scene *rs = NULL;
    if (render_scene_create(&sd, &ro, stderr, &rs, &err) != HZ_OK) {
        fprintf(stderr, "embree_loop: %s\n", err.message);
        scene_desc_free(&sd);
        return 1;
    }
    const film_params *fp = film_get_params(render_scene_film(rs));
    loop_job job = {.rs = rs,
                    .scene = geometry_embree_scene(render_scene_geometry(rs)),
                    .spp = render_scene_sampler(rs)->spp,
                    .width = fp->xres,
                    .height = fp->yres,
                    .packet = packet,
                    .camera_only = camera_only};
    atomic_init(&job.next_row, 0);
    loop_worker *w = calloc((size_t)threads, sizeof *w);
    pthread_t *tid = calloc((size_t)threads, sizeof *tid);
    if (!w || !tid) {
        fprintf(stderr, "embree_loop: out of memory\n");
        return 1;
    }
    double t0 = seconds();
    for (int i = 0; i < threads; ++i) {
        w[i].job = &job;
        pthread_create(&tid[i], NULL, worker_main, &w[i]);
    }
    double sum = 0.0;
    unsigned long long cam = 0, shadow = 0;
    for (int i = 0; i < threads; ++i) {
        pthread_join(tid[i], NULL);
        sum += w[i].sum;
        cam += w[i].camera_rays;
        shadow += w[i].shadow_rays;
    }
    double t1 = seconds();
    printf("embree_loop: %dx%d, %d spp, %d threads, loop %.3f s, %llu camera + %llu shadow "
           "rays, mean %.6g\n",
           job.width, job.height, job.spp, threads, t1 - t0, cam, shadow,
           sum / ((double)job.width * job.height * job.spp));
    free(w);
    free(tid);
    render_scene_destroy(rs);
    scene_desc_free(&sd);
    return 0;
}
