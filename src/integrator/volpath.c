#define _POSIX_C_SOURCE 200809L
#include "integrator/volpath.h"
#include "integrator/visible_surface.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <embree3/rtcore.h>

#include "camera/footprint.h"
#include "core/clock.h"
#include "core/ray.h"
#include "core/phase.h"
#include "materials/bsdf.h"
#include "integrator/equiangular.h"
#include "integrator/volpath_media.h"
#include "integrator/walk.h"

/* ---- settings and scene ---- */

hz_status volpath_settings_from_entity(scene_entity *e, FILE *warn, volpath_settings *out,
                                       hz_error *err)
{
    (void)err;
    param_list *pl = &e->params;
    out->max_depth = params_int(pl, "maxdepth", 5);
    if (out->max_depth < 0)
        params_reject(pl, "maxdepth", "\"maxdepth\" must be >= 0");
    out->regularize = params_bool(pl, "regularize", false);
    if (params_has(pl, "rrthreshold")) {
        /* pbrt-v3's Russian roulette threshold: `pbrt --upgrade` drops it
         * (roulette changes only the noise); today's pbrt-v4 refuses it. */
        (void)params_float(pl, "rrthreshold", 1.0);
        hz_warn_at(warn, params_loc(pl, "rrthreshold"),
                   "\"rrthreshold\" is pbrt-v3's (Russian roulette changes only the noise; "
                   "pbrt-v4's --upgrade drops it): not used");
    }
    out->force_diffuse = false; /* an Option, set by the scene */
    out->shadow_cache = shadow_cache_spacing_param(pl, 0.0);
    out->step = params_float(pl, "stepsize", 0.0);
    if (!(out->step >= 0.0 && isfinite(out->step)))
        params_reject(pl, "stepsize",
                      "\"stepsize\" must be a number of voxels >= 0 (0: tracking, unbiased)");
    out->medium_splits = params_int(pl, "mediumsplits", 1);
    if (out->medium_splits < 1 || out->medium_splits > VOLPATH_MAX_SPLITS)
        params_reject(pl, "mediumsplits",
                      "\"mediumsplits\" must be an integer from 1 (no splitting) to %d",
                      VOLPATH_MAX_SPLITS);
    out->light_sampler = LIGHT_SAMPLER_BVH;
    const char *ls = params_string(pl, "lightsampler", "bvh");
    if (strcmp(ls, "uniform") == 0) {
        out->light_sampler = LIGHT_SAMPLER_UNIFORM;
    } else if (strcmp(ls, "power") == 0) {
        out->light_sampler = LIGHT_SAMPLER_POWER;
    } else if (strcmp(ls, "exhaustive") == 0) {
        /* pbrt-v4's exhaustive sampler weighs every light by its BVH
         * importance at the point; the BVH sampler is its nearest. */
        hz_warn_at(warn, params_loc(pl, "lightsampler"),
                   "Integrator \"volpath\" \"lightsampler\" \"exhaustive\" is not supported; "
                   "using \"bvh\"");
    } else if (strcmp(ls, "bvh") != 0) {
        params_reject(pl, "lightsampler",
                      "\"lightsampler\" \"%s\" is not one of \"uniform\", \"power\", \"bvh\", "
                      "\"exhaustive\"",
                      ls);
    }
    return HZ_OK;
}

/* Radius of the bounding sphere of the scene's surfaces (0 without any). */
static double scene_radius(const geometry *geom)
{
    struct RTCBounds b;
    rtcGetSceneBounds(geometry_embree_scene(geom), &b);
    vec3 d = v3((double)b.upper_x - b.lower_x, (double)b.upper_y - b.lower_y,
                (double)b.upper_z - b.lower_z);
    double r = 0.5 * v3_length(d);
    return isfinite(r) && r > 0.0 ? r : 0.0;
}

hz_status volpath_scene_init(volpath_scene *out, const integrator_inputs *in,
                             volpath_settings settings, hz_error *err)
{
    *out = (volpath_scene){*in, settings, {0}, rgb_grey(0.0), false, -1, false, NULL, 0, NULL};
    for (size_t i = 0; in->medium_count > 0 && i < in->light_count; ++i)
        if (in->lights[i].kind == LIGHT_POINT || in->lights[i].kind == LIGHT_SPOT) {
            if (!out->eq_lights && !(out->eq_lights = malloc(in->light_count * sizeof(size_t))))
                return hz_fail(err, "out of memory");
            out->eq_lights[out->eq_light_count++] = i;
        }
    for (size_t i = 0; i < in->light_count; ++i)
        if (in->lights[i].kind == LIGHT_INFINITE && !light_is_image(&in->lights[i])) {
            out->sky = rgb_add(out->sky, in->lights[i].emit);
            out->sky_lights_many = out->sky_light >= 0;
            if (out->sky_light < 0)
                out->sky_light = (int)i;
        } else if (light_is_image(&in->lights[i]))
            out->image_lights = true;
    if (light_sampler_create(settings.light_sampler, in->lights, in->light_count,
                             scene_radius(in->geom), &out->sampler, err) != HZ_OK) {
        free(out->eq_lights);
        out->eq_lights = NULL;
        return HZ_ERROR;
    }
    return HZ_OK;
}

void volpath_scene_free(volpath_scene *sc)
{
    light_sampler_free(&sc->sampler);
    free(sc->eq_lights);
    sc->eq_lights = NULL;
}

/* ---- path state ---- */

/* Spectral rendering: the media at the path's wavelengths, one copy for the
 * path's rays and one for shadow rays (which start while the path's walk is
 * under way); index -1 when not made yet. Kept out of `path`, whose
 * initialiser would clear them for every camera ray in RGB too. */
typedef struct {
    medium ray, shadow;
    int ray_index, shadow_index;
} path_media;

typedef struct {
    const volpath_scene *sc;
    const spectral_ctx *sp; /* NULL: RGB */
    path_media *media;      /* spectral only */
    sampler_state *st;
    media_walk walk;
    integrator_counters *counters;
    int hero;
    int lanes; /* 3 (RGB) or WAVELENGTH_LANES (spectral): what MIS averages over */
    rgb L, beta, r_u, r_l;
    /* pbrt-v4's etaScale: the squared relative indices the path crossed by
     * transmission. Radiance through a dielectric is divided by eta^2 going
     * in (beta ~ 1/2.25 inside glass of 1.5) and multiplied coming out; the
     * roulette weighs beta times this, so paths inside glass are not cut for
     * a loss they get back on leaving. */
    double eta_scale;
    int depth;
    bool specular, any_non_specular;
    vec3 prev_p, prev_n; /* the last scattering point and its shading normal
                          * (zero in a medium): light densities for MIS */
    /* The ray being walked: its segment's medium is the one tracked. Hits
     * before its t_fill lie behind the medium point it leaves (the walk
     * steps over them; interfaces there only switch the medium). */
    ray_walk ray;
    bool scattered, terminated;
    /* The ray's differentials (pbrt-v4's RayDifferential): the camera ray's,
     * carried through specular bounces (specular_differentials); none after
     * any other scattering, where hits estimate their footprint from the
     * camera (camera_approximate_dpdxy). */
    bool diff;
    vec3 rx_o, rx_d, ry_o, ry_d;
    /* Spectral: the path met a dispersive dielectric, so only the hero's
     * lane counts (material_disperse). */
    bool one_lane;
    /* While the path tracks a segment of a homogeneous medium that the
     * equiangular strategy light-samples (equiangular_ld): the segment
     * (start point, direction, length) and the path's r_u at its start,
     * for the MIS weight of the light samples of its scattering points. */
    bool eq_on;
    vec3 eq_o, eq_w;
    double eq_len;
    rgb eq_r_u;
    /* "mediumsplits" > 1: where the path's first scattering point in a
     * medium is to be saved for its other continuations (volpath_li); NULL
     * once saved, and without splitting. */
    struct path_split *split;
} path;

/* A path as it stood at its first scattering point in a medium, after the
 * light sample there and before the phase function's direction: each
 * continuation starts from here with its own sampler scramble. */
typedef struct path_split {
    path at;
    sampler_state st;
    vec3 x, wo;
    double g;
} path_split;

/* Medium i of the scene at the path's wavelengths (itself in RGB). */
static const medium *path_medium(path *pa, int i, bool shadow)
{
    const medium *m = &pa->sc->in.media[i];
    if (!pa->sp)
        return m;
    medium *copy = shadow ? &pa->media->shadow : &pa->media->ray;
    int *index = shadow ? &pa->media->shadow_index : &pa->media->ray_index;
    if (*index != i) {
        medium_spectral(m, pa->sp, copy);
        *index = i;
    }
    return copy;
}

/* ---- rays ---- */

/* Starts the path's next ray, o + t d: surfaces are searched from tmin on,
 * media fill it from t_fill on. `flags`: walk_start's beyond the path's own. */
static void path_ray(path *pa, vec3 o, vec3 d, double tmin, double t_fill, int medium,
                     unsigned flags)
{
    const integrator_inputs *in = &pa->sc->in;
    unsigned exact = in->medium_count > 0 ? WALK_EXACT_ENDS : 0u;
    walk_start(&pa->ray, in->geom, o, d, tmin, t_fill, INFINITY, pa->walk.time, medium,
               exact | WALK_PASS_BEHIND | flags);
}

/* Leaving surface hit h along w. With media, the medium also fills the bit
 * between the surface and the offset origin (as the single-scattering
 * integrator's shadow rays): the ray starts e behind the offset origin, where
 * its line crosses the tangent plane. */
static void ray_from_surface(path *pa, const geom_hit *h, vec3 w)
{
    vec3 o = geometry_leave_origin(h, w);
    int after = geometry_medium_after(h, w, pa->ray.medium);
    if (pa->sc->in.medium_count == 0) {
        path_ray(pa, o, w, 0.0, 0.0, after, 0u);
        return;
    }
    vec3 off = v3_sub(o, h->p);
    double wn = fabs(v3_dot(w, h->ng));
    double e = v3_length(off) * 16.0;
    if (wn * e > fabs(v3_dot(off, h->ng)))
        e = fabs(v3_dot(off, h->ng)) / wn;
    path_ray(pa, v3_sub(o, v3_scale(w, e)), w, e, 0.0, after, 0u);
}

/* Leaving the medium point x along w: Embree sees x rounded to float, which
 * can put it past its medium's boundary; so surfaces are searched from e
 * behind x (integrator/path.h, PATH_SHADOW_BACKOFF) and the medium fills the
 * ray from x on. */
static void ray_from_medium(path *pa, vec3 x, vec3 w, int medium)
{
    double e = PATH_SHADOW_BACKOFF * fmax(fmax(fabs(x.x), fabs(x.y)), fabs(x.z));
    path_ray(pa, v3_sub(x, v3_scale(w, e)), w, 0.0, e, medium, WALK_CONVEX_START);
}

static inline rgb rgb_div(rgb a, double s) { return rgb_scale(a, 1.0 / s); }

/* ---- shadow rays: ratio tracking with pbrt-v4's r_u, r_l ---- */

typedef struct {
    path *pa;
    rgb T, r_u, r_l;
} shadow_state;

/* The mean of x over the path's lanes (pbrt-v4's SampledSpectrum::Average). */
static inline double lane_avg(const path *pa, rgb x) { return rgb_lanes_avg(x, pa->lanes); }

static double nonnegative(double x) { return fmax(0.0, x); }
/* sigma_n = sigma_maj - sigma_t, per lane, at least 0. */
static rgb sigma_null(const volpath_event *ev)
{
    return rgb_map(rgb_sub(rgb_sub(ev->sigma_maj, ev->sigma_a), ev->sigma_s), nonnegative);
}

static bool shadow_event(void *ctx, const volpath_event *ev)
{
    shadow_state *s = ctx;
    int h = s->pa->hero;
    rgb sigma_n = sigma_null(ev);
    double pdf = rgb_ch(ev->T_maj, h) * rgb_ch(ev->sigma_maj, h);
    rgb tn = rgb_div(rgb_mul(ev->T_maj, sigma_n), pdf);
    s->T = rgb_mul(s->T, tn);
    s->r_l = rgb_mul(s->r_l, rgb_div(rgb_mul(ev->T_maj, ev->sigma_maj), pdf));
    s->r_u = rgb_mul(s->r_u, tn);
    double estimate = rgb_max(s->T) / lane_avg(s->pa, rgb_add(s->r_l, s->r_u));
    s->T = rgb_scale(s->T, volpath_shadow_roulette(estimate, &s->pa->walk.r));
    return !rgb_is_black(s->T);
}

/* The walk of singlescatter_light.c's shadow rays (interfaces switch the medium,
 * opaque surfaces block unless they lie before t_fill), with tracking in
 * media. False when the ray is blocked or its estimate is 0. */
static bool shadow_walk(shadow_state *s, vec3 o, vec3 w, double tmin, double t_fill, double tmax,
                        int mi)
{
    path *pa = s->pa;
    const volpath_scene *sc = pa->sc;
    pa->walk.shadow_rays++;
    ray_walk rw;
    walk_start(&rw, sc->in.geom, o, w, tmin, t_fill, tmax, pa->walk.time, mi,
               WALK_EXACT_ENDS | WALK_CONVEX_START);
    for (walk_segment seg; walk_next(&rw, &seg);) {
        if (seg.opaque) {
            if (seg.h.t >= t_fill)
                return false;
            walk_step_over(&rw);
            continue;
        }
        mi = seg.medium;
        double t_start = seg.t0, t_end = seg.t1;
        const medium *m = mi >= 0 ? path_medium(pa, mi, true) : NULL;
        if (m && sc->settings.step > 0.0 && volpath_marches(m)) {
            double D, t, d;
            (void)volpath_march(m, o, w, t_start, t_end, sc->settings.step, INFINITY, &pa->walk,
                                &D, &t, &d);
            s->T = rgb_mul(s->T, rgb_exp_neg(medium_sigma_t(m), D));
            if (rgb_is_black(s->T))
                return false;
        } else if (m && volpath_grey(m)) {
            double ft, fu;
            if (!volpath_grey_ratio(m, o, w, t_start, t_end, &pa->walk, rgb_max(s->T),
                                    lane_avg(pa, s->r_l), lane_avg(pa, s->r_u), &ft, &fu))
                return false;
            s->T = rgb_scale(s->T, ft);
            s->r_u = rgb_scale(s->r_u, fu);
        } else if (m) {
            rgb T_maj = volpath_track(m, o, w, t_start, t_end, pa->hero, false, -1.0,
                                      &pa->walk, shadow_event, s);
            double th = rgb_ch(T_maj, pa->hero);
            if (rgb_is_black(s->T) || !(th > 0.0))
                return false;
            s->T = rgb_mul(s->T, rgb_div(T_maj, th));
            s->r_u = rgb_mul(s->r_u, rgb_div(T_maj, th));
            s->r_l = rgb_mul(s->r_l, rgb_div(T_maj, th));
        }
        if (!seg.hit)
            return true;
    }
    pa->walk.lost++; /* the walk ends early only at the crossing limit */
    return false;
}

/* A scattering point for light sampling: a surface hit with its BSDF, or a
 * medium point with its phase function. */
typedef struct {
    vec3 p, wo;
    const bsdf *b;      /* NULL at a medium point */
    const geom_hit *h;  /* surface only */
    double g;           /* medium only */
    int medium;         /* the medium the point is in (surface: the ray's, before it) */
    /* A scattering point of a segment under equiangular sampling (eq_on):
     * its distance from the segment's start and the hero's density of
     * sampling it there (T_maj sigma_s). */
    double eq_s, eq_pdf;
} vertex;

/* Transmittance estimate (with r_u, r_l) of the shadow ray of light sample ls
 * of light li from v; false when blocked. A medium point whose medium and
 * light have a shadow cache reads it instead. */
static bool shadow(path *pa, const vertex *v, const light_sample *ls, size_t li, shadow_state *s)
{
    const volpath_scene *sc = pa->sc;
    const shadow_cache *cache =
        v->b || !sc->caches ? NULL : shadow_caches_get(sc->caches, v->medium, li);
    if (cache) {
        s->T = shadow_cache_transmittance(cache, v->p, pa->sp);
        return !rgb_is_black(s->T);
    }
    if (v->b) {
        const geom_hit *h = v->h;
        path_shadow_ray sr = path_surface_shadow_ray(h, ls);
        int start = sc->in.medium_count == 0 ? -1 : geometry_medium_after(h, sr.w, v->medium);
        /* An occlusion test leaves r_u and r_l as they are. */
        if (path_shadow_ray_unattenuated(&sc->in, start, &sr, pa->walk.time,
                                         &pa->walk.majorant_steps)) {
            pa->counters->shadow_rays++;
            return !geometry_occluded(sc->in.geom, sr.o, sr.w, sr.tmax, pa->walk.time);
        }
        double e;
        if (!path_shadow_ray_for_media(h, ls, &sr, &e))
            return false;
        return shadow_walk(s, v3_sub(sr.o, v3_scale(sr.w, e)), sr.w, e, 0.0, sr.tmax + e, start);
    }
    double tmax = ls->infinite                       ? INFINITY
                  : v3_length_sq(ls->n_light) > 0.0 ? ls->dist * (1.0 - GEOMETRY_SHADOW_EPSILON)
                                                    : ls->dist;
    vec3 x = v->p, w = ls->wi;
    double e = PATH_SHADOW_BACKOFF * fmax(fmax(fabs(x.x), fabs(x.y)), fabs(x.z));
    return shadow_walk(s, v3_sub(x, v3_scale(w, e)), w, 0.0, e, tmax + e, v->medium);
}

/* The equiangular strategy's density of choosing light l and distance s on
 * the path's current segment (equiangular_ld): a point or spot light picked
 * uniformly, then s toward it. */
static double equiangular_light_pdf(const path *pa, const light *l, double s)
{
    equiangular e = light_equiangular(l, pa->eq_o, pa->eq_w, pa->eq_len);
    return equiangular_pdf(&e, s) / (double)pa->sc->eq_light_count;
}

/* pbrt-v4's SampleLd: one light chosen by the light sampler, one point of
 * it, MIS-weighted against BSDF / phase sampling (delta lights: light
 * sampling only). */
static rgb sample_ld(path *pa, const vertex *v)
{
    const volpath_scene *sc = pa->sc;
    double u = sampler_1d(pa->st);
    vec2 ul = sampler_2d(pa->st);
    size_t li;
    double pmf;
    vec3 n = v->b ? v->b->n : v3(0.0, 0.0, 0.0);
    if (!light_sampler_sample(&sc->sampler, v->p, n, u, &li, &pmf))
        return rgb_grey(0.0);
    const light *l = &sc->in.lights[li];
    light_sample ls;
    if (!light_sample_li(l, v->p, n, pa->walk.time, ul, &ls) || !(ls.pdf > 0.0) ||
        rgb_is_black(ls.L))
        return rgb_grey(0.0);
    ls.L = light_spectral(l, ls.L, pa->sp);
    rgb f_hat;
    double scatter_pdf;
    if (v->b) {
        f_hat = rgb_scale(bsdf_f(v->b, v->wo, ls.wi), fabs(v3_dot(ls.wi, v->b->n)));
        scatter_pdf = bsdf_pdf(v->b, v->wo, ls.wi);
    } else {
        scatter_pdf = hg_phase(v3_dot(v->wo, ls.wi), v->g);
        f_hat = rgb_grey(scatter_pdf);
    }
    if (rgb_is_black(f_hat))
        return rgb_grey(0.0);
    shadow_state s = {pa, rgb_grey(1.0), rgb_grey(1.0), rgb_grey(1.0)};
    bool timed = v->b && pa->counters->timed && sc->in.medium_count > 0;
    uint64_t t0 = timed ? hz_clock_ns() : 0;
    bool lit = shadow(pa, v, &ls, li, &s);
    if (timed)
        pa->counters->media_ns += hz_clock_ns() - t0;
    if (!lit)
        return rgb_grey(0.0);
    rgb r_l = rgb_scale(rgb_mul(s.r_l, pa->r_u), pmf * ls.pdf);
    /* In a segment that equiangular_ld light-samples, this point could have
     * come from there too: the balance heuristic adds its density. */
    if (!v->b && pa->eq_on && (l->kind == LIGHT_POINT || l->kind == LIGHT_SPOT))
        r_l = rgb_add(r_l, rgb_scale(rgb_mul(s.r_l, pa->eq_r_u),
                                     equiangular_light_pdf(pa, l, v->eq_s) / v->eq_pdf));
    rgb r_u = rgb_scale(rgb_mul(s.r_u, pa->r_u), scatter_pdf);
    rgb c = rgb_mul(rgb_mul(rgb_mul(pa->beta, f_hat), s.T), ls.L);
    double den = light_only_sampled(l) ? lane_avg(pa, r_l) : lane_avg(pa, rgb_add(r_l, r_u));
    return den > 0.0 ? rgb_div(c, den) : rgb_grey(0.0);
}

/* ---- media events of the path ---- */

/* The path leaves medium point x (where it arrived from -wo) in the
 * direction the phase function (asymmetry g) samples. */
static void scatter_on(path *pa, vec3 x, vec3 wo, double g)
{
    double p_pdf;
    vec3 wi = hg_sample(wo, g, sampler_2d(pa->st), &p_pdf);
    if (!(p_pdf > 0.0)) {
        pa->terminated = true;
        return;
    }
    /* hg_sample draws exactly the density it returns: p / pdf = 1. */
    pa->r_l = rgb_div(pa->r_u, p_pdf);
    pa->diff = false;
    pa->prev_p = x;
    pa->prev_n = v3(0.0, 0.0, 0.0);
    pa->scattered = true;
    ray_from_medium(pa, x, wi, pa->ray.medium);
    pa->specular = false;
    pa->any_non_specular = true;
}

/* A real scattering event at ev->t of the current ray: light sampling, then
 * the phase function chooses the next direction. The first one in a medium
 * saves the path for its other continuations ("mediumsplits"). */
static void scatter(path *pa, const volpath_event *ev)
{
    const volpath_scene *sc = pa->sc;
    int h = pa->hero;
    double pdf = rgb_ch(ev->T_maj, h) * rgb_ch(ev->sigma_s, h);
    rgb ratio = rgb_div(rgb_mul(ev->T_maj, ev->sigma_s), pdf);
    pa->beta = rgb_mul(pa->beta, ratio);
    pa->r_u = rgb_mul(pa->r_u, ratio);
    if (rgb_is_black(pa->beta) || rgb_is_black(pa->r_u))
        return;
    const medium *m = &sc->in.media[pa->ray.medium];
    vec3 x = v3_add(pa->ray.o, v3_scale(pa->ray.d, ev->t));
    vec3 wo = v3_neg(pa->ray.d);
    vertex v = {x, wo, NULL, NULL, m->g, pa->ray.medium, 0.0, 0.0};
    if (pa->eq_on) {
        v.eq_s = v3_dot(v3_sub(x, pa->eq_o), pa->eq_w);
        v.eq_pdf = pdf;
    }
    pa->L = rgb_add(pa->L, sample_ld(pa, &v));
    if (pa->split) {
        path_split *sp = pa->split;
        pa->split = NULL;
        *sp = (path_split){*pa, *pa->st, x, wo, m->g};
    }
    scatter_on(pa, x, wo, m->g);
}

static bool path_event(void *ctx, const volpath_event *ev)
{
    path *pa = ctx;
    if (rgb_is_black(pa->beta)) {
        pa->terminated = true;
        return false;
    }
    int h = pa->hero;
    double sm = rgb_ch(ev->sigma_maj, h);
    /* Medium emission at every tentative collision (pbrt-v4's estimator:
     * beta T_maj sigma_a Le / (T_maj sigma_maj) in the hero channel, MIS
     * over the channels through r_e). */
    if (pa->depth < pa->sc->settings.max_depth && !rgb_is_black(ev->emission)) {
        double pdf = rgb_ch(ev->T_maj, h) * sm;
        rgb betap = rgb_div(rgb_mul(pa->beta, ev->T_maj), pdf);
        rgb r_e = rgb_div(rgb_mul(pa->r_u, rgb_mul(ev->sigma_maj, ev->T_maj)), pdf);
        double r = lane_avg(pa, r_e);
        if (r > 0.0)
            pa->L = rgb_add(pa->L, rgb_div(rgb_mul(betap, ev->emission), r));
    }
    double p_absorb = rgb_ch(ev->sigma_a, h) / sm, p_scatter = rgb_ch(ev->sigma_s, h) / sm;
    double p_null = fmax(0.0, 1.0 - p_absorb - p_scatter);
    double u = rng_uniform(&pa->walk.r) * (p_absorb + p_scatter + p_null);
    if (u < p_absorb) {
        pa->terminated = true;
        return false;
    }
    if (u < p_absorb + p_scatter) {
        if (pa->depth++ >= pa->sc->settings.max_depth)
            pa->terminated = true;
        else
            scatter(pa, ev);
        return false;
    }
    rgb sigma_n = sigma_null(ev);
    double pdf = rgb_ch(ev->T_maj, h) * rgb_ch(sigma_n, h);
    if (!(pdf > 0.0)) {
        pa->beta = rgb_grey(0.0);
        return false;
    }
    rgb tn = rgb_div(rgb_mul(ev->T_maj, sigma_n), pdf);
    pa->beta = rgb_mul(pa->beta, tn);
    pa->r_u = rgb_mul(pa->r_u, tn);
    pa->r_l = rgb_mul(pa->r_l, rgb_div(rgb_mul(ev->T_maj, ev->sigma_maj), pdf));
    return !rgb_is_black(pa->beta) && !rgb_is_black(pa->r_u);
}

/* ---- surfaces ---- */

/* Emission of the area light at hit h, reached along the path. */
static void add_emission(path *pa, const geom_hit *h, vec3 wo)
{
    const volpath_scene *sc = pa->sc;
    int li = h->shape->area_light;
    const light *l = &sc->in.lights[li];
    rgb Le = light_spectral(l, light_area_le(l, h->ng, wo, v2(h->u, h->v), h->p), pa->sp);
    if (rgb_is_black(Le))
        return;
    if (pa->depth == 0 || pa->specular) {
        pa->L = rgb_add(pa->L, rgb_div(rgb_mul(pa->beta, Le), lane_avg(pa, pa->r_u)));
        return;
    }
    double p_l = light_sampler_pmf(&sc->sampler, pa->prev_p, pa->prev_n, (size_t)li) *
                 light_pdf_li(l, pa->prev_p, pa->walk.time, h->p, h->ng);
    rgb den = rgb_add(pa->r_u, rgb_scale(pa->r_l, p_l));
    pa->L = rgb_add(pa->L, rgb_div(rgb_mul(pa->beta, Le), lane_avg(pa, den)));
}

/* The image infinite lights seen by a path leaving the scene along w,
 * MIS-weighted against their light samples (as add_emission). */
static void add_image_lights(path *pa, vec3 o, vec3 w)
{
    const volpath_scene *sc = pa->sc;
    for (size_t i = 0; i < sc->in.light_count; ++i) {
        const light *l = &sc->in.lights[i];
        if (!light_is_image(l))
            continue;
        rgb Le = light_spectral(l, light_infinite_le(l, o, w), pa->sp);
        if (rgb_is_black(Le))
            continue;
        rgb den = pa->r_u;
        if (pa->depth > 0 && !pa->specular) {
            double p_l = light_sampler_pmf(&sc->sampler, pa->prev_p, pa->prev_n, i) *
                         light_infinite_pdf(l, w);
            den = rgb_add(den, rgb_scale(pa->r_l, p_l));
        }
        pa->L = rgb_add(pa->L, rgb_div(rgb_mul(pa->beta, Le), lane_avg(pa, den)));
    }
}

/* pbrt-v4's forcediffuse: the BSDF's directional albedo at wo, from one
 * sample, as the reflectance of a diffuse BSDF in its place. */
static void force_diffuse(bsdf *b, vec3 wo, sampler_state *st)
{
    double uc = sampler_1d(st);
    vec2 u = sampler_2d(st);
    bsdf_sample s;
    rgb r = bsdf_sample_f(b, wo, uc, u, &s) && s.pdf > 0.0
                ? rgb_scale(s.f, fabs(v3_dot(s.wi, b->n)) / s.pdf)
                : rgb_grey(0.0);
    b->kind = BSDF_DIFFUSE;
    b->reflectance = r;
}

/* pbrt-v4's ComputeDifferentials at opaque hit h, where a texture or the
 * ray's differentials need it: where the differentials meet the tangent
 * plane, else the camera's estimate (in scenes with textures: a footprint
 * scale). */
static void hit_footprint(path *pa, geom_hit *h)
{
    const integrator_inputs *in = &pa->sc->in;
    if (!h->shape->textured && !pa->diff)
        return;
    vec3 dpdx, dpdy;
    if (!pa->diff || !geometry_hit_dpdxy(h, pa->rx_o, pa->rx_d, pa->ry_o, pa->ry_d, &dpdx, &dpdy)) {
        if (!in->camera || !(in->footprint_scale > 0.0))
            return;
        camera_approximate_dpdxy(in->camera, h->p, h->ng, pa->walk.time, in->footprint_scale,
                                 &dpdx, &dpdy);
    }
    geometry_hit_set_footprint(h, dpdx, dpdy);
}

/* The differentials of the ray a specular bounce at h sends along wi (pbrt-
 * v4's SurfaceInteraction::SpawnRay): the offset rays leave the footprint's
 * corners, turned by the same mirror or refraction, to first order in the
 * change of wo (the shading normal is taken as constant over the
 * footprint). Any other bounce drops them. */
static void specular_differentials(path *pa, const geom_hit *h, vec3 n, vec3 wo,
                                   const bsdf_sample *bs)
{
    if (!pa->diff)
        return;
    if (!bs->specular) {
        pa->diff = false;
        return;
    }
    const vec3 wi = bs->wi;
    const vec3 rd[2] = {pa->rx_d, pa->ry_d};
    const vec3 dp[2] = {h->dpdx, h->dpdy};
    vec3 o[2], d[2];
    if (bs->transmission && v3_dot(wo, n) < 0.0)
        n = v3_neg(n);
    for (int k = 0; k < 2; ++k) {
        vec3 dwo = v3_sub(v3_neg(rd[k]), wo);
        double dcos = v3_dot(dwo, n);
        o[k] = v3_add(h->p, dp[k]);
        if (!bs->transmission) {
            d[k] = v3_add(v3_sub(wi, dwo), v3_scale(n, 2.0 * dcos));
        } else {
            double eta = bs->eta;
            double dmu = dcos * (1.0 / eta + v3_dot(wo, n) / (eta * eta * v3_dot(wi, n)));
            d[k] = v3_add(v3_sub(wi, v3_scale(dwo, eta)), v3_scale(n, dmu));
        }
    }
    pa->rx_o = o[0];
    pa->ry_o = o[1];
    pa->rx_d = d[0];
    pa->ry_d = d[1];
    /* pbrt-v4 drops differentials that blew up. */
    pa->diff = v3_length_sq(d[0]) <= 1e16 && v3_length_sq(d[1]) <= 1e16 &&
               v3_length_sq(o[0]) <= 1e16 && v3_length_sq(o[1]) <= 1e16 &&
               v3_is_finite(d[0]) && v3_is_finite(d[1]);
}

/* The bounce at opaque hit h: light sampling, BSDF sampling, roulette.
 * False when the path ends. */
static bool bounce(path *pa, const geom_hit *h)
{
    const volpath_scene *sc = pa->sc;
    vec3 wo = v3_neg(pa->ray.d);
    if (h->shape->area_light >= 0)
        add_emission(pa, h, wo);
    bsdf b;
    material scratch;
    const material *mat = geometry_material_at(h, wo, &scratch);
    vec3 ns = geometry_shading_normal(h, mat);
    mat = material_spectral(mat, pa->sp, &scratch);
    if (pa->sp && mat->dispersive) { /* material_spectral copied it to scratch */
        material_disperse(&scratch, pa->sp, pa->hero);
        pa->one_lane = true;
    }
    if (!bsdf_from_material(mat, ns, h->dpdu, h->v, &b))
        return false;
    if (pa->depth++ >= sc->settings.max_depth)
        return false;
    if (sc->settings.regularize && pa->any_non_specular)
        bsdf_regularize(&b);
    if (sc->settings.force_diffuse && b.kind != BSDF_DIFFUSE)
        force_diffuse(&b, wo, pa->st);
    if (bsdf_is_non_specular(&b)) {
        vertex v = {h->p, wo, &b, h, 0.0, pa->ray.medium, 0.0, 0.0};
        pa->L = rgb_add(pa->L, sample_ld(pa, &v));
    }
    pa->prev_p = h->p;
    pa->prev_n = b.n;
    double uc = sampler_1d(pa->st);
    vec2 u = sampler_2d(pa->st);
    bsdf_sample bs;
    if (!bsdf_sample_f(&b, wo, uc, u, &bs))
        return false;
    specular_differentials(pa, h, b.n, wo, &bs);
    pa->beta = rgb_mul(pa->beta, rgb_scale(bs.f, fabs(v3_dot(bs.wi, b.n)) / bs.pdf));
    /* A layered BSDF's sampled pdf is only proportional: MIS uses its pdf
     * estimate (pbrt-v4's pdfIsProportional). */
    pa->r_l = rgb_div(pa->r_u, bs.pdf_proportional ? bsdf_pdf(&b, wo, bs.wi) : bs.pdf);
    pa->specular = bs.specular;
    pa->any_non_specular |= !bs.specular;
    if (bs.transmission)
        pa->eta_scale *= bs.eta * bs.eta;
    ray_from_surface(pa, h, bs.wi);
    if (rgb_is_black(pa->beta))
        return false;
    rgb rr = rgb_scale(rgb_div(pa->beta, lane_avg(pa, pa->r_u)), pa->eta_scale);
    double u_rr = sampler_1d(pa->st);
    if (rgb_max(rr) < 1.0 && pa->depth > 1) {
        double q = fmax(0.0, 1.0 - rgb_max(rr));
        if (u_rr < q)
            return false;
        pa->beta = rgb_div(pa->beta, 1.0 - q);
    }
    return true;
}

/* ---- the path ---- */

/* The second strategy for light scattered on the current segment [t_start,
 * t_hit] of a homogeneous medium m toward point and spot lights
 * (Kulla & Fajardo 2012): a light picked uniformly, a distance s sampled
 * equiangularly toward it, its light sample there; combined by the balance
 * heuristic with the light samples of the points distance sampling
 * scatters at (sample_ld), both weighed by the densities of both ways to
 * the same point and light. Distance sampling alone has unbounded variance
 * near a point light in a scattering medium: its estimate grows as 1 / r^2
 * where the density of points within r falls only as r^3. */
static void equiangular_ld(path *pa, const medium *m, double t_start, double t_hit)
{
    const volpath_scene *sc = pa->sc;
    pa->eq_on = true;
    pa->eq_o = v3_add(pa->ray.o, v3_scale(pa->ray.d, t_start));
    pa->eq_w = pa->ray.d;
    pa->eq_len = t_hit - t_start;
    pa->eq_r_u = pa->r_u;
    vec2 u = sampler_2d(pa->st); /* the light, the distance */
    double ul = u.x, us = u.y;
    size_t n = sc->eq_light_count, k = (size_t)(ul * (double)n);
    size_t li = sc->eq_lights[k < n ? k : n - 1];
    const light *l = &sc->in.lights[li];
    equiangular e = light_equiangular(l, pa->eq_o, pa->eq_w, pa->eq_len);
    if (!e.valid)
        return;
    double s = equiangular_sample(&e, us);
    double p_eq = equiangular_pdf(&e, s) / (double)n;
    if (!(s >= e.lo && s < e.hi && s < pa->eq_len) || !(p_eq > 0.0) || !isfinite(p_eq))
        return;
    vec3 x = v3_add(pa->eq_o, v3_scale(pa->eq_w, s));
    light_sample ls;
    if (!light_sample_li(l, x, v3(0.0, 0.0, 0.0), pa->walk.time, v2(0.5, 0.5), &ls) ||
        rgb_is_black(ls.L))
        return;
    ls.L = light_spectral(l, ls.L, pa->sp);
    double phase = hg_phase(v3_dot(v3_neg(pa->eq_w), ls.wi), m->g);
    /* Distance sampling's density of scattering at s, per lane. */
    rgb p_dist = rgb_mul(m->sigma_s, rgb_exp_neg(medium_sigma_t(m), s));
    if (!(phase > 0.0) || rgb_is_black(p_dist))
        return;
    vertex v = {x, v3_neg(pa->eq_w), NULL, NULL, m->g, pa->ray.medium, 0.0, 0.0};
    shadow_state st = {pa, rgb_grey(1.0), rgb_grey(1.0), rgb_grey(1.0)};
    if (!shadow(pa, &v, &ls, li, &st))
        return;
    double pmf = light_sampler_pmf(&sc->sampler, x, v3(0.0, 0.0, 0.0), li);
    rgb den = rgb_mul(rgb_mul(st.r_l, pa->r_u),
                      rgb_add(rgb_scale(p_dist, pmf), rgb_grey(p_eq)));
    rgb c = rgb_scale(rgb_mul(rgb_mul(rgb_mul(pa->beta, p_dist), st.T), ls.L), phase);
    double d = lane_avg(pa, den);
    if (d > 0.0)
        pa->L = rgb_add(pa->L, rgb_div(c, d));
}

/* volpath_track with path_event over [t_start, t_hit] of grey medium m
 * (volpath_grey): the null collisions change no weight, so the walk itself
 * decides them and path_event sees the real collision alone (sigma_maj
 * there = sigma_t, no null share). The majorant transmittance to the end:
 * 1 in every lane (its ratios are what counts), 0 when opaque. */
static rgb grey_flight(path *pa, const medium *m, double t_start, double t_hit, double u)
{
    double t, d;
    switch (volpath_grey_flight(m, pa->ray.o, pa->ray.d, t_start, t_hit, u, &pa->walk, &t, &d)) {
    case VOLPATH_PASSED:
        break;
    case VOLPATH_REAL: {
        volpath_event ev = {t, rgb_scale(m->sigma_a, d), rgb_scale(m->sigma_s, d), rgb_grey(0.0),
                            rgb_grey(1.0), rgb_grey(0.0)};
        ev.sigma_maj = rgb_add(ev.sigma_a, ev.sigma_s);
        path_event(pa, &ev);
        break;
    }
    case VOLPATH_OPAQUE:
        return rgb_grey(0.0);
    }
    return rgb_grey(1.0);
}

/* A marched flight (volpath_march) over [t_start, t_hit] of medium m: the
 * distance in the hero channel, a real collision to path_event with the
 * lanes' transmittances to it (sigma_maj = sigma_t there: no null share).
 * The lanes' transmittance to the end when the flight passes. */
static rgb march_flight(path *pa, const medium *m, double t_start, double t_hit, double u)
{
    rgb sigma_t = medium_sigma_t(m);
    double sh = rgb_ch(sigma_t, pa->hero);
    double stop = sh > 0.0 ? -log(1.0 - u) / sh : INFINITY;
    double D, t, d;
    volpath_flight f = volpath_march(m, pa->ray.o, pa->ray.d, t_start, t_hit,
                                     pa->sc->settings.step, stop, &pa->walk, &D, &t, &d);
    rgb T = rgb_exp_neg(sigma_t, D);
    if (f != VOLPATH_REAL)
        return T;
    volpath_event ev = {t, rgb_scale(m->sigma_a, d), rgb_scale(m->sigma_s, d), rgb_scale(sigma_t, d),
                        T, rgb_grey(0.0)};
    path_event(pa, &ev);
    return rgb_grey(1.0);
}

/* Tracks the current ray's medium over [t_start, t_hit]. False when the
 * path ended there; pa->scattered when it scattered. */
static bool cross_medium(path *pa, double t_start, double t_hit)
{
    pa->scattered = pa->terminated = false;
    uint64_t t0 = pa->counters->timed ? hz_clock_ns() : 0;
    const medium *m = path_medium(pa, pa->ray.medium, false);
    pa->eq_on = false;
    if (pa->sc->eq_light_count > 0 && medium_is_homogeneous(m) &&
        pa->depth < pa->sc->settings.max_depth && !rgb_is_black(m->sigma_s) && t_hit > t_start)
        equiangular_ld(pa, m, t_start, t_hit);
    double u = sampler_1d(pa->st); /* the first collision's (volpath_track) */
    rgb T_maj = pa->sc->settings.step > 0.0 && volpath_marches(m)
                    ? march_flight(pa, m, t_start, t_hit, u)
                : volpath_grey(m) ? grey_flight(pa, m, t_start, t_hit, u)
                                  : volpath_track(m, pa->ray.o, pa->ray.d, t_start, t_hit, pa->hero,
                                                true, u, &pa->walk, path_event, pa);
    pa->eq_on = false;
    if (pa->counters->timed)
        pa->counters->media_ns += hz_clock_ns() - t0;
    if (pa->terminated || rgb_is_black(pa->beta) || rgb_is_black(pa->r_u))
        return false;
    if (pa->scattered)
        return true;
    double th = rgb_ch(T_maj, pa->hero);
    if (!(th > 0.0))
        return false;
    rgb ratio = rgb_div(T_maj, th);
    pa->beta = rgb_mul(pa->beta, ratio);
    pa->r_u = rgb_mul(pa->r_u, ratio);
    pa->r_l = rgb_mul(pa->r_l, ratio);
    return true;
}

/* The constant sky's radiance at the path's wavelengths. */
static rgb sky_radiance(const path *pa)
{
    const volpath_scene *sc = pa->sc;
    if (!pa->sp)
        return sc->sky;
    rgb L = light_emit_spectral(&sc->in.lights[sc->sky_light], pa->sp);
    for (size_t i = (size_t)sc->sky_light + 1; sc->sky_lights_many && i < sc->in.light_count; ++i)
        if (sc->in.lights[i].kind == LIGHT_INFINITE && !light_is_image(&sc->in.lights[i]))
            L = rgb_add(L, light_emit_spectral(&sc->in.lights[i], pa->sp));
    return L;
}

/* A path that leaves the scene: the infinite lights it sees. */
static void add_escaped(path *pa)
{
    const volpath_scene *sc = pa->sc;
    /* A constant sky is never light-sampled (light_sampler.h): full weight. */
    if (!rgb_is_black(sc->sky))
        pa->L = rgb_add(pa->L, rgb_div(rgb_mul(pa->beta, sky_radiance(pa)), lane_avg(pa, pa->r_u)));
    if (sc->image_lights)
        add_image_lights(pa, pa->ray.o, pa->ray.d);
}

/* Follows the path from its current ray until it ends. `camera_ray`: the
 * ray is the camera's (depth, vs and the rng's seed dimension, seed_dim >= 0,
 * are set on its way). */
static void trace(path *pa, const ray_differential *rd, bool camera_ray, int seed_dim,
                  double *depth, film_surface *vs)
{
    const ray *r = &rd->r;
    sampler_state *st = pa->st;
    /* Every scattering and bounce starts a new walk (its crossings anew). */
    for (walk_segment seg;;) {
        ray_walk *ray = &pa->ray;
        if (!walk_next(ray, &seg)) { /* lost: the walk that leaves the scene ends the path */
            pa->walk.lost++;
            break;
        }
        if (seed_dim >= 0 && (seg.hit || seg.medium >= 0)) {
            pa->walk.r = rng_seeded(sampler_stream_seed_at(st, seed_dim));
            seed_dim = -1;
        }
        double t_start = seg.t0, t_hit = seg.t1;
        if (ray->medium >= 0) {
            if (!cross_medium(pa, t_start, t_hit))
                break;
            if (pa->scattered) {
                camera_ray = false;
                continue;
            }
        }
        if (!seg.hit) {
            add_escaped(pa);
            break;
        }
        if (!seg.opaque)
            continue;
        geom_hit *h = &seg.h;
        hit_footprint(pa, h);
        if (camera_ray) {
            *depth = v3_length(v3_sub(h->p, r->o));
            camera_ray = false;
            if (vs && pa->depth == 0)
                visible_surface_at(h, rd, vs);
        }
        if (!bounce(pa, h))
            break;
    }
}

/* The radiance the path gathered. Spectral paths that met a dispersive
 * dielectric count the hero's wavelength alone, times the lanes (its share
 * of them). */
static rgb path_radiance(const path *pa)
{
    if (!pa->one_lane)
        return pa->L;
    rgb L = rgb_grey(0.0);
    rgb_set_ch(&L, pa->hero, WAVELENGTH_LANES * rgb_ch(pa->L, pa->hero));
    return L;
}

static void add_walk_counters(integrator_counters *c, const media_walk *w)
{
    c->shadow_rays += w->shadow_rays;
    c->density_lookups += w->lookups;
    c->majorant_steps += w->majorant_steps;
    c->lost_paths += w->lost;
}

rgb volpath_li(const volpath_scene *sc, const ray_differential *rd, const spectral_ctx *sp,
               sampler_state *st,
               double *depth, film_surface *vs, integrator_counters *counters)
{
    const ray *r = &rd->r;
    counters->camera_rays++;
    *depth = INFINITY;
    bool media = sc->in.medium_count > 0;
    path pa = {.sc = sc, .sp = sp, .st = st, .walk = {.time = r->time, .sp = sp},
               .counters = counters,
               .L = rgb_grey(0.0), .beta = rgb_grey(1.0), .r_u = rgb_grey(1.0),
               .r_l = rgb_grey(1.0), .eta_scale = 1.0, .lanes = sp ? WAVELENGTH_LANES : 3};
    path_media spectral_media;
    if (sp) {
        spectral_media.ray_index = spectral_media.shadow_index = -1;
        pa.media = &spectral_media;
    }
    path_ray(&pa, r->o, r->d, 0.0, 0.0, r->medium, 0u);
    pa.diff = rd->has_differentials;
    if (pa.diff) {
        pa.rx_o = rd->rx_o;
        pa.rx_d = rd->rx_d;
        pa.ry_o = rd->ry_o;
        pa.ry_d = rd->ry_d;
    }
    /* As singlescatter_li: the rng is seeded once the ray meets something. */
    int seed_dim = -1;
    if (media) {
        seed_dim = sampler_reserve_dim(st);
        pa.hero = (int)fmin(pa.lanes - 1.0, floor(pa.lanes * sampler_1d(st)));
    }
    int splits = media ? sc->settings.medium_splits : 1;
    path_split split;
    if (splits > 1)
        pa.split = &split;
    trace(&pa, rd, true, seed_dim, depth, vs);
    add_walk_counters(counters, &pa.walk);
    rgb L = path_radiance(&pa);
    if (splits <= 1 || pa.split) /* no splitting, or no scattering in a medium */
        return L;
    /* The other continuations from the first scattering point in a medium,
     * each from its own scramble of the sampler's later dimensions and its
     * own rng stream: k estimates of the path sharing their start. */
    for (int k = 1; k < splits; ++k) {
        pa = split.at;
        pa.eq_on = false; /* the segment it scattered on is behind it */
        pa.walk.lookups = pa.walk.shadow_rays = pa.walk.majorant_steps = pa.walk.lost = 0;
        *st = split.st;
        sampler_fork(st, k);
        pa.walk.r = rng_seeded(sampler_stream_seed_at(st, sampler_reserve_dim(st)));
        scatter_on(&pa, split.x, split.wo, split.g);
        if (!pa.terminated)
            trace(&pa, rd, false, -1, depth, vs);
        add_walk_counters(counters, &pa.walk);
        L = rgb_add(L, path_radiance(&pa));
    }
    return rgb_scale(L, 1.0 / splits);
}
