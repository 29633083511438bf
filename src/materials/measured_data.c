#include "materials/measured_data.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/vec.h"
#include "scene/spectrum.h"

enum { F_THETA, F_PHI, F_NDF, F_SIGMA, F_VNDF, F_LUM, F_SPECTRA, F_LAMBDA, F_DESC, F_JAC, F_N };

static const struct {
    const char *name;
    int rank;
    tensor_dtype dtype;
} field_specs[F_N] = {
    {"theta_i", 1, TENSOR_F32},   {"phi_i", 1, TENSOR_F32},       {"ndf", 2, TENSOR_F32},
    {"sigma", 2, TENSOR_F32},     {"vndf", 4, TENSOR_F32},        {"luminance", 4, TENSOR_F32},
    {"spectra", 5, TENSOR_F32},   {"wavelengths", 1, TENSOR_F32}, {"description", 1, TENSOR_U8},
    {"jacobian", 1, TENSOR_U8},
};

static hz_status find_fields(const tensor_file *t, const tensor_field *f[F_N], hz_error *err)
{
    for (int i = 0; i < F_N; ++i) {
        f[i] = tensor_file_field(t, field_specs[i].name);
        if (!f[i])
            return hz_fail(err, "no field \"%s\": not a measured BRDF (RGL's .bsdf files have "
                                "theta_i, phi_i, ndf, sigma, vndf, luminance, spectra, "
                                "wavelengths, description and jacobian)",
                           field_specs[i].name);
        if (f[i]->dtype != field_specs[i].dtype || f[i]->ndim != field_specs[i].rank)
            return hz_fail(err, "field \"%s\" is %s of rank %d; a measured BRDF's is %s of "
                                "rank %d",
                           field_specs[i].name, tensor_dtype_name(f[i]->dtype), f[i]->ndim,
                           tensor_dtype_name(field_specs[i].dtype), field_specs[i].rank);
    }
    return HZ_OK;
}

static void shape_text(const tensor_field *f, char *out, size_t n)
{
    size_t used = (size_t)snprintf(out, n, "[");
    for (int i = 0; i < f->ndim && used < n; ++i)
        used += (size_t)snprintf(out + used, n - used, "%s%llu", i ? ", " : "",
                                 (unsigned long long)f->shape[i]);
    if (used < n)
        snprintf(out + used, n - used, "]");
}

static hz_status bad_shape(const tensor_field *f, const char *want, hz_error *err)
{
    char got[160];
    shape_text(f, got, sizeof got);
    return hz_fail(err, "field \"%s\" has shape %s; it must be %s", f->name, got, want);
}

/* The shapes agree with each other (as pbrt-v4 checks them), and every 2D
 * table has at least 2 x 2 values. */
static hz_status check_shapes(const tensor_field *f[F_N], hz_error *err)
{
    uint64_t T = f[F_THETA]->shape[0], P = f[F_PHI]->shape[0], L = f[F_LAMBDA]->shape[0];
    char want[160];
    if (T < 1 || P < 1 || L < 1)
        return hz_fail(err, "theta_i, phi_i and wavelengths must not be empty (they have %llu, "
                            "%llu and %llu values)",
                       (unsigned long long)T, (unsigned long long)P, (unsigned long long)L);
    for (int i = F_NDF; i <= F_SIGMA; ++i)
        if (f[i]->shape[0] < 2 || f[i]->shape[1] < 2)
            return bad_shape(f[i], "at least [2, 2]", err);
    const tensor_field *v = f[F_VNDF], *l = f[F_LUM], *s = f[F_SPECTRA];
    snprintf(want, sizeof want, "[%llu (phi_i), %llu (theta_i), >= 2, >= 2]",
             (unsigned long long)P, (unsigned long long)T);
    if (v->shape[0] != P || v->shape[1] != T || v->shape[2] < 2 || v->shape[3] < 2)
        return bad_shape(v, want, err);
    snprintf(want, sizeof want, "[%llu (phi_i), %llu (theta_i), N, N] with N >= 2",
             (unsigned long long)P, (unsigned long long)T);
    if (l->shape[0] != P || l->shape[1] != T || l->shape[2] < 2 || l->shape[2] != l->shape[3])
        return bad_shape(l, want, err);
    snprintf(want, sizeof want, "[%llu (phi_i), %llu (theta_i), %llu (wavelengths), %llu, %llu]",
             (unsigned long long)P, (unsigned long long)T, (unsigned long long)L,
             (unsigned long long)l->shape[2], (unsigned long long)l->shape[3]);
    if (s->shape[0] != P || s->shape[1] != T || s->shape[2] != L || s->shape[3] != l->shape[2] ||
        s->shape[4] != l->shape[3])
        return bad_shape(s, want, err);
    if (f[F_JAC]->shape[0] != 1)
        return bad_shape(f[F_JAC], "[1]", err);
    return HZ_OK;
}

/* Finite and strictly increasing (and > 0 for wavelengths). */
static hz_status check_axis(const tensor_field *f, bool positive, hz_error *err)
{
    for (size_t i = 0; i < f->count; ++i) {
        double v = tensor_field_f32(f, i);
        if (!isfinite(v) || (positive && !(v > 0.0)))
            return hz_fail(err, "field \"%s\": value %zu is %g", f->name, i, v);
        if (i > 0 && !(v > tensor_field_f32(f, i - 1)))
            return hz_fail(err, "field \"%s\" must increase: value %zu is %g after %g", f->name,
                           i, v, (double)tensor_field_f32(f, i - 1));
    }
    return HZ_OK;
}

/* An anisotropic table must cover the whole circle of azimuths: files that
 * store a half or a quarter of it (Mitsuba's "reduction") are refused, as
 * pbrt-v4 refuses them. */
static hz_status check_reduction(const tensor_field *phi, hz_error *err)
{
    if (phi->count <= 2)
        return HZ_OK;
    double span = (double)tensor_field_f32(phi, phi->count - 1) - tensor_field_f32(phi, 0);
    double reduction = 2.0 * HZ_PI / span;
    if (fabs(reduction - 1.0) < 0.5)
        return HZ_OK;
    return hz_fail(err, "phi_i spans %.4g degrees, %.0f times less than a full circle: "
                        "files reduced by symmetry are not supported (as pbrt-v4)",
                   span * 180.0 / HZ_PI, reduction);
}

static float *floats_of(const tensor_field *f)
{
    float *v = malloc((f->count ? f->count : 1) * sizeof *v);
    for (size_t i = 0; v && i < f->count; ++i)
        v[i] = tensor_field_f32(f, i);
    return v;
}

/* A table of (x, y) from field f: shape [.., ny, nx] with `n_params`
 * leading parameter axes (phi_i, theta_i). */
static hz_status table(warp2d *w, const tensor_field *f, int n_params, const float *const *pv,
                       bool sampling, bool non_negative, hz_error *err)
{
    float *data = floats_of(f);
    if (!data)
        return hz_fail(err, "out of memory");
    for (size_t i = 0; non_negative && i < f->count; ++i)
        if (data[i] < 0.0f) {
            double v = data[i];
            free(data);
            return hz_fail(err, "field \"%s\": value %zu is negative (%g)", f->name, i, v);
        }
    size_t sizes[WARP2D_MAX_PARAMS];
    for (int i = 0; i < n_params; ++i)
        sizes[i] = (size_t)f->shape[i];
    hz_error e;
    if (warp2d_init(w, data, (size_t)f->shape[n_params + 1], (size_t)f->shape[n_params],
                    n_params, sizes, pv, sampling, &e) != HZ_OK)
        return hz_fail(err, "field \"%s\": %s", f->name, e.message);
    return HZ_OK;
}

/* The linear sRGB of a unit at each tabulated wavelength (the others 0),
 * the spectrum held at its end values outside the table: the reduction is
 * linear, so the RGB of a spectrum is the sum of these weighted by it. */
static bool channel_weights(const tensor_field *lambda, rgb *w)
{
    size_t n = lambda->count, m = 0;
    double *l = malloc((n + 2) * sizeof *l);
    rgb *ext = malloc((n + 2) * sizeof *ext);
    if (!l || !ext) {
        free(l);
        free(ext);
        return false;
    }
    /* The end values held out to 360 and 830 nm: extra points whose weight
     * goes to the end wavelengths. */
    bool before = tensor_field_f32(lambda, 0) > 360.0;
    bool after = tensor_field_f32(lambda, n - 1) < 830.0;
    if (before)
        l[m++] = 360.0;
    for (size_t k = 0; k < n; ++k)
        l[m++] = tensor_field_f32(lambda, k);
    if (after)
        l[m++] = 830.0;
    spectrum_sampled_basis_to_rgb(l, m, ext);
    for (size_t k = 0; k < n; ++k)
        w[k] = ext[k + before];
    if (before)
        w[0] = rgb_add(w[0], ext[0]);
    if (after)
        w[n - 1] = rgb_add(w[n - 1], ext[m - 1]);
    free(l);
    free(ext);
    return true;
}

/* The spectra's tables reduced to three RGB tables. */
static hz_status rgb_tables(measured_brdf *m, const tensor_field *f[F_N], const float *const *pv,
                            hz_error *err)
{
    const tensor_field *s = f[F_SPECTRA];
    size_t L = (size_t)s->shape[2], nn = (size_t)(s->shape[3] * s->shape[4]);
    size_t slices = (size_t)(s->shape[0] * s->shape[1]);
    rgb *w = malloc(L * sizeof *w);
    float *c[3] = {malloc(slices * nn * sizeof(float)), malloc(slices * nn * sizeof(float)),
                   malloc(slices * nn * sizeof(float))};
    if (!w || !c[0] || !c[1] || !c[2] || !channel_weights(f[F_LAMBDA], w)) {
        free(w);
        free(c[0]);
        free(c[1]);
        free(c[2]);
        return hz_fail(err, "out of memory");
    }
    for (size_t sl = 0; sl < slices; ++sl)
        for (size_t k = 0; k < nn; ++k) {
            double sum[3] = {0.0, 0.0, 0.0};
            for (size_t j = 0; j < L; ++j) {
                double x = tensor_field_f32(s, (sl * L + j) * nn + k);
                sum[0] += w[j].r * x;
                sum[1] += w[j].g * x;
                sum[2] += w[j].b * x;
            }
            for (int ch = 0; ch < 3; ++ch)
                c[ch][sl * nn + k] = (float)sum[ch];
        }
    free(w);
    size_t sizes[2] = {(size_t)s->shape[0], (size_t)s->shape[1]};
    hz_status st = HZ_OK;
    for (int ch = 0; ch < 3; ++ch) {
        hz_error e;
        if (st == HZ_OK && warp2d_init(&m->rgb[ch], c[ch], (size_t)s->shape[4],
                                       (size_t)s->shape[3], 2, sizes, pv, false, &e) != HZ_OK)
            st = hz_fail(err, "field \"spectra\": %s", e.message);
        else if (st != HZ_OK)
            free(c[ch]);
    }
    return st;
}

static hz_status build(measured_brdf *m, const tensor_field *f[F_N], hz_error *err)
{
    m->isotropic = f[F_PHI]->count <= 2;
    m->jacobian = f[F_JAC]->data[0] != 0;
    float *phi = floats_of(f[F_PHI]), *theta = floats_of(f[F_THETA]);
    hz_status st = HZ_ERROR;
    if (!phi || !theta)
        hz_fail(err, "out of memory");
    else {
        const float *pv[2] = {phi, theta};
        if (table(&m->ndf, f[F_NDF], 0, NULL, false, true, err) == HZ_OK &&
            table(&m->sigma, f[F_SIGMA], 0, NULL, false, true, err) == HZ_OK &&
            table(&m->vndf, f[F_VNDF], 2, pv, true, true, err) == HZ_OK &&
            table(&m->luminance, f[F_LUM], 2, pv, true, true, err) == HZ_OK)
            st = rgb_tables(m, f, pv, err);
    }
    free(phi);
    free(theta);
    return st;
}

hz_status measured_brdf_from_tensor(const tensor_file *t, measured_brdf **out, hz_error *err)
{
    *out = NULL;
    const tensor_field *f[F_N];
    if (find_fields(t, f, err) != HZ_OK || check_shapes(f, err) != HZ_OK ||
        check_axis(f[F_THETA], false, err) != HZ_OK ||
        check_axis(f[F_PHI], false, err) != HZ_OK ||
        check_axis(f[F_LAMBDA], true, err) != HZ_OK || check_reduction(f[F_PHI], err) != HZ_OK)
        return HZ_ERROR;
    const tensor_field *s = f[F_SPECTRA];
    for (size_t i = 0; i < s->count; ++i)
        if (!isfinite(tensor_field_f32(s, i)))
            return hz_fail(err, "field \"spectra\": value %zu is not finite", i);
    measured_brdf *m = calloc(1, sizeof *m);
    if (!m)
        return hz_fail(err, "out of memory");
    if (build(m, f, err) != HZ_OK) {
        measured_brdf_destroy(m);
        return HZ_ERROR;
    }
    *out = m;
    return HZ_OK;
}

hz_status measured_brdf_read(const char *path, measured_brdf **out, hz_error *err)
{
    *out = NULL;
    tensor_file *t = NULL;
    if (tensor_file_read(path, &t, err) != HZ_OK)
        return HZ_ERROR;
    hz_error e;
    hz_status st = measured_brdf_from_tensor(t, out, &e);
    tensor_file_destroy(t);
    if (st != HZ_OK)
        return hz_fail(err, "%s: %s", path, e.message);
    return HZ_OK;
}

void measured_brdf_destroy(measured_brdf *m)
{
    if (!m)
        return;
    warp2d_free(&m->ndf);
    warp2d_free(&m->sigma);
    warp2d_free(&m->vndf);
    warp2d_free(&m->luminance);
    for (int c = 0; c < 3; ++c)
        warp2d_free(&m->rgb[c]);
    free(m);
}

struct measured_cache {
    char **paths;
    measured_brdf **brdfs;
    size_t count, cap;
};

hz_status measured_cache_create(measured_cache **out, hz_error *err)
{
    *out = calloc(1, sizeof **out);
    return *out ? HZ_OK : hz_fail(err, "out of memory");
}

void measured_cache_destroy(measured_cache *c)
{
    if (!c)
        return;
    for (size_t i = 0; i < c->count; ++i) {
        free(c->paths[i]);
        measured_brdf_destroy(c->brdfs[i]);
    }
    free(c->paths);
    free(c->brdfs);
    free(c);
}

static bool grow(measured_cache *c)
{
    if (c->count < c->cap)
        return true;
    size_t cap = c->cap ? 2 * c->cap : 4;
    char **p = realloc(c->paths, cap * sizeof *p);
    if (p)
        c->paths = p;
    measured_brdf **b = p ? realloc(c->brdfs, cap * sizeof *b) : NULL;
    if (b)
        c->brdfs = b;
    if (!p || !b)
        return false;
    c->cap = cap;
    return true;
}

hz_status measured_cache_get(measured_cache *c, const char *path, const measured_brdf **out,
                             hz_error *err)
{
    for (size_t i = 0; i < c->count; ++i)
        if (strcmp(c->paths[i], path) == 0) {
            *out = c->brdfs[i];
            return HZ_OK;
        }
    measured_brdf *m = NULL;
    if (measured_brdf_read(path, &m, err) != HZ_OK)
        return HZ_ERROR;
    char *copy = malloc(strlen(path) + 1);
    if (!copy || !grow(c)) {
        free(copy);
        measured_brdf_destroy(m);
        return hz_fail(err, "out of memory");
    }
    strcpy(copy, path);
    c->paths[c->count] = copy;
    c->brdfs[c->count++] = m;
    *out = m;
    return HZ_OK;
}
