#include "integrator/singlescatter_media.h"

#include <math.h>
#include <string.h>

#include "core/ray.h"
#include "core/phase.h"
#include "integrator/equiangular.h"
#include "integrator/singlescatter_grid.h"
#include "integrator/singlescatter_light.h"

/* ---- homogeneous media: distance sampling ---- */

/* Exponential distance sampling on [0, len) (len may be INFINITY), one channel
 * picked uniformly among those that attenuate; the pdf is the mixture over them. */
typedef struct {
    rgb sigma_t;
    double len;
    int active[WAVELENGTH_LANES], n_active;
} exp_sampler;

/* Over `lanes` lanes: 3 in RGB, WAVELENGTH_LANES in spectral rendering. */
static exp_sampler exp_sampler_make(rgb sigma_t, double len, int lanes)
{
    exp_sampler e = {sigma_t, len, {0}, 0};
    for (int c = 0; c < lanes; ++c)
        if (rgb_ch(sigma_t, c) > 0.0)
            e.active[e.n_active++] = c;
    return e;
}

static double exp_channel_pdf(double sigma, double len, double s)
{
    if (isinf(len))
        return sigma * exp(-sigma * s);
    double mass = -expm1(-sigma * len); /* 1 - e^{-sigma len} */
    if (mass < 1e-12)
        return 1.0 / len; /* vanishing optical depth: uniform */
    return sigma * exp(-sigma * s) / mass;
}

static double exp_pdf(const exp_sampler *e, double s)
{
    if (e->n_active == 0)
        return 0.0;
    double p = 0.0;
    for (int k = 0; k < e->n_active; ++k)
        p += exp_channel_pdf(rgb_ch(e->sigma_t, e->active[k]), e->len, s);
    return p / e->n_active;
}

static double exp_sample(const exp_sampler *e, double u)
{
    int k = (int)(u * e->n_active);
    if (k >= e->n_active)
        k = e->n_active - 1;
    u = u * e->n_active - k;
    double sigma = rgb_ch(e->sigma_t, e->active[k]);
    double s;
    if (isinf(e->len)) {
        s = -log1p(-u) / sigma;
    } else {
        double mass = -expm1(-sigma * e->len);
        s = mass < 1e-12 ? u * e->len : -log1p(-u * mass) / sigma;
    }
    return fmin(s, nextafter(e->len, 0.0));
}

/* Light of one lamp scattered toward wo at distance s (T(0, s) σ_s applied). */
static rgb scatter_at(const singlescatter_scene *vs, int mi, const light *l, vec3 o, vec3 w,
                      double s, sampler_state *u, media_walk *walk)
{
    medium copy;
    const medium *m = walk_medium(&vs->in, mi, walk, &copy);
    rgb Ls = singlescatter_light_inscattered(vs, mi, l, v3_add(o, v3_scale(w, s)), v3_neg(w), u,
                                             walk);
    return rgb_mul(rgb_mul(m->sigma_s, rgb_exp_neg(medium_sigma_t(m), s)), Ls);
}

/* Emission gathered over a homogeneous segment of length len, exactly:
 * the integral of T(s) sigma_a Le over [0, len] = sigma_a Le (1 - e^{-sigma_t len}) / sigma_t
 * per channel (a channel that does not attenuate does not absorb: 0). */
static rgb homogeneous_emission(const medium *m, rgb sigma_t, double len)
{
    rgb e = rgb_grey(0.0);
    for (int c = 0; c < 4; ++c) { /* every lane: w copies g in RGB */
        double st = rgb_ch(sigma_t, c), sa = rgb_ch(m->sigma_a, c);
        rgb_set_ch(&e, c, st > 0.0 ? sa * rgb_ch(m->Le, c) * -expm1(-st * len) / st : 0.0);
    }
    return e;
}

static void homogeneous_segment(const singlescatter_scene *vs, int mi, vec3 o, vec3 w, double t0,
                                double t1, rgb *beta, rgb *L, sampler_state *u,
                                media_walk *walk)
{
    medium copy;
    const medium *m = walk_medium(&vs->in, mi, walk, &copy);
    rgb sigma_t = medium_sigma_t(m);
    double len = t1 - t0;
    vec3 a = v3_add(o, v3_scale(w, t0)); /* the segment starts at s = 0 */
    if (!rgb_is_black(m->sigma_s) && len > 0.0) {
        exp_sampler es = exp_sampler_make(sigma_t, len, walk->sp ? WAVELENGTH_LANES : 3);
        rgb Lseg = rgb_grey(0.0);
        for (size_t i = 0; i < vs->in.light_count; ++i) {
            const light *l = &vs->in.lights[i];
            equiangular eq = light_equiangular(l, a, w, len);
            /* One sample per strategy, combined with the balance heuristic:
             * f / (p_exp + p_eq) for each. */
            if (es.n_active > 0) {
                double s = exp_sample(&es, sampler_1d(u));
                double p = exp_pdf(&es, s) + equiangular_pdf(&eq, s);
                if (p > 0.0)
                    Lseg =
                        rgb_add(Lseg, rgb_scale(scatter_at(vs, mi, l, a, w, s, u, walk), 1.0 / p));
            }
            if (eq.valid) {
                double s = equiangular_sample(&eq, sampler_1d(u));
                if (s >= eq.lo && s < eq.hi && s < len) {
                    double p = exp_pdf(&es, s) + equiangular_pdf(&eq, s);
                    if (p > 0.0 && isfinite(p))
                        Lseg = rgb_add(Lseg,
                                       rgb_scale(scatter_at(vs, mi, l, a, w, s, u, walk), 1.0 / p));
                }
            }
        }
        *L = rgb_add(*L, rgb_mul(*beta, Lseg));
    }
    if (m->emissive && len > 0.0)
        *L = rgb_add(*L, rgb_mul(*beta, homogeneous_emission(m, sigma_t, len)));
    *beta = rgb_mul(*beta, rgb_exp_neg(sigma_t, len));
}

void singlescatter_segment(const singlescatter_scene *vs, int m, vec3 o, vec3 w, double t0,
                           double t1, rgb *beta, rgb *L, sampler_state *u, media_walk *walk)
{
    if (!(t1 > t0))
        return;
    /* The scene build refused media that are neither (volpath's only). */
    if (medium_is_homogeneous(&vs->in.media[m]))
        homogeneous_segment(vs, m, o, w, t0, t1, beta, L, u, walk);
    else
        singlescatter_grid_segment(vs, m, o, w, t0, t1, beta, L, u, walk);
}
