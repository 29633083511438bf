/* What the interface does the same for every kind (the kinds' table and
 * medium_create are in medium_kinds.c). */
#include "media/medium.h"


void medium_destroy(medium *m)
{
    if (!m || !m->ops)
        return;
    if (m->ops->destroy)
        m->ops->destroy(m);
    m->state = NULL;
}

medium_memory medium_bytes(const medium *m)
{
    return m->ops && m->ops->memory ? m->ops->memory(m) : (medium_memory){0.0, 0.0};
}

medium_work medium_work_done(const medium *m)
{
    return m->ops && m->ops->work ? m->ops->work(m) : (medium_work){0, 0.0};
}

/* The lanes of coefficient v (RGB), a multiple of spectrum s as given: s's
 * own spectrum when the scene gave one, else v's RGB spectrum. */
static rgb spectral_coefficient(const spectral_ctx *sp, rgb v, const spectrum_value *s,
                                const spectral_color *prepared, spectral_use use)
{
    if (s->kind == SPECTRUM_VALUE_RGB)
        return prepared->ready ? spectral_eval(sp, prepared) : spectral_from_rgb(sp, v, use);
    double m = rgb_max(s->rgb);
    return m > 0.0 ? rgb_scale(spectral_from_value(sp, s), rgb_max(v) / m) : rgb_grey(0.0);
}

void medium_prepare_spectral(medium *m, const rgb2spec_table *t)
{
    if (!m->ops)
        return;
    m->prepared.sigma_a = spectral_prepare(t, m->sigma_a, SPECTRAL_UNBOUNDED);
    m->prepared.sigma_s = spectral_prepare(t, m->sigma_s, SPECTRAL_UNBOUNDED);
    m->prepared.Le = spectral_prepare(t, m->Le, SPECTRAL_ILLUMINANT);
}

const medium *medium_spectral(const medium *m, const spectral_ctx *sp, medium *copy)
{
    if (!sp || !m->ops)
        return m;
    *copy = *m;
    copy->spectral = sp;
    copy->sigma_a = spectral_coefficient(sp, m->sigma_a, &m->sigma_a_spec, &m->prepared.sigma_a,
                                         SPECTRAL_UNBOUNDED);
    copy->sigma_s = spectral_coefficient(sp, m->sigma_s, &m->sigma_s_spec, &m->prepared.sigma_s,
                                         SPECTRAL_UNBOUNDED);
    copy->Le =
        spectral_coefficient(sp, m->Le, &m->Le_spec, &m->prepared.Le, SPECTRAL_ILLUMINANT);
    /* Coefficients looked up per voxel as RGB bound the majorant by their
     * largest channel; as unbounded spectra they reach up to twice that. */
    if (m->ops->rgb_coefficients)
        copy->sigma_s = rgb_scale(copy->sigma_s, 2.0);
    return copy;
}

bool medium_is_chromatic(const medium *m)
{
    rgb a = m->sigma_a, s = m->sigma_s;
    return m->ops &&
           (m->ops->rgb_coefficients || m->coloured || a.r != a.g || a.g != a.b || s.r != s.g ||
            s.g != s.b || !spectrum_value_is_constant(&m->sigma_a_spec) ||
            !spectrum_value_is_constant(&m->sigma_s_spec));
}

bool medium_clip(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1)
{
    if (!(*t0 <= *t1)) /* also NaN */
        return false;
    return !m->ops->clip || m->ops->clip(m, o, d, time, t0, t1);
}

bool medium_support(const medium *m, vec3 corners[8], double *voxel)
{
    return m->ops->support && m->ops->support(m, corners, voxel);
}

double medium_density_max(const medium *m)
{
    return m->ops->density_max ? m->ops->density_max(m) : 0.0;
}

bool media_clear_along(const medium *media, size_t n, vec3 o, vec3 d, double t0, double t1,
                       double time, uint64_t *cells)
{
    for (size_t i = 0; i < n; ++i) {
        const medium *m = &media[i];
        if (!m->ops->clear_along || !m->ops->clear_along(m, o, d, t0, t1, time, cells))
            return false;
    }
    return true;
}
