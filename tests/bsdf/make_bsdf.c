/* Writes RGL-format measured BRDFs (.bsdf tensor files, Dupuy and Jakob
 * 2018) of analytic BRDFs, for the tests: no real measurement can be
 * downloaded here, and an analytic one has closed forms to check against.
 *
 *   haze_make_bsdf OUTDIR
 *
 * writes into OUTDIR
 *   lambert.bsdf         Lambertian, albedo 0.5 (flat spectrum)
 *   lambert-colour.bsdf  Lambertian, albedo 0.1, 0.3, 0.6, 0.8 at 400, 500,
 *                        600, 700 nm (held at its ends outside)
 *   lambert-nojac.bsdf   lambert.bsdf with "jacobian" 0 (spectra = f cos)
 *   ggx.bsdf             a rough conductor: Trowbridge-Reitz alpha 0.3, eta 1,
 *                        k 4 (normal-incidence reflectance 0.8), flat spectrum
 *   ggx-aniso.bsdf       the same with alpha_x 0.2, alpha_y 0.5, tabulated
 *                        at 13 incident azimuths
 *   tiny.bsdf            a Lambertian at the least resolution the format
 *                        allows (fuzzing seeds, truncated copies)
 *
 * Each file is made as the paper describes: the microfacet distribution D of
 * the parameterisation (the conductor's own; alpha 0.5 for the Lambertians),
 * its projected area sigma(wo) = (z + sqrt(z^2 + ax^2 x^2 + ay^2 y^2)) / 2,
 * per tabulated wo the density of visible normals over the (sqrt(2 theta /
 * pi), phi / 2 pi + 1/2) square, and the reflectance R = f 4 sigma cos_i / D
 * at the points of the sample square that this density's warp maps to
 * normals (materials/warp2d.h). The luminance table is the spectra's mean. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "materials/microfacet.h"
#include "materials/warp2d.h"

#define PI 3.14159265358979323846

typedef struct {
    const char *file;
    tr_distribution d; /* of the parameterisation */
    bool lambert;      /* else the conductor of d */
    bool jacobian;
    int n_lambda;
    const float *lambda;
    const double *albedo; /* lambert: per wavelength */
    int n_phi, n_theta;   /* incident directions */
    int ndf_res, vndf_res, sample_res;
} spec;

typedef struct {
    const char *name;
    uint8_t dtype; /* 1 uint8, 10 float32 */
    int ndim;
    uint64_t shape[5];
    const void *data;
} field;

static uint64_t count_of(const field *f)
{
    uint64_t n = 1;
    for (int i = 0; i < f->ndim; ++i)
        n *= f->shape[i];
    return n;
}

static void put(FILE *out, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; ++i)
        fputc((int)((v >> (8 * i)) & 0xff), out);
}

static void put_f32(FILE *out, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    put(out, bits, 4);
}

static int write_tensor(const char *path, const field *f, int n)
{
    FILE *out = fopen(path, "wb");
    if (!out) {
        perror(path);
        return 1;
    }
    uint64_t offset = 12 + 2 + 4;
    for (int i = 0; i < n; ++i)
        offset += 2 + strlen(f[i].name) + 2 + 1 + 8 + 8 * (uint64_t)f[i].ndim;
    fwrite("tensor_file", 1, 12, out);
    put(out, 1, 1);
    put(out, 0, 1);
    put(out, (uint64_t)n, 4);
    for (int i = 0; i < n; ++i) {
        put(out, strlen(f[i].name), 2);
        fwrite(f[i].name, 1, strlen(f[i].name), out);
        put(out, (uint64_t)f[i].ndim, 2);
        put(out, f[i].dtype, 1);
        put(out, offset, 8);
        for (int j = 0; j < f[i].ndim; ++j)
            put(out, f[i].shape[j], 8);
        offset += count_of(&f[i]) * (f[i].dtype == 1 ? 1 : 4);
    }
    for (int i = 0; i < n; ++i) {
        uint64_t c = count_of(&f[i]);
        for (uint64_t k = 0; k < c; ++k) {
            if (f[i].dtype == 1)
                put(out, ((const uint8_t *)f[i].data)[k], 1);
            else
                put_f32(out, ((const float *)f[i].data)[k]);
        }
    }
    if (fclose(out) != 0) {
        perror(path);
        return 1;
    }
    return 0;
}

static double u_to_theta(double u) { return u * u * (PI / 2.0); }
static double u_to_phi(double u) { return (2.0 * u - 1.0) * PI; }

static vec3 spherical(double theta, double phi)
{
    return v3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

static double sigma_of(tr_distribution d, vec3 w)
{
    double a = d.alpha_x * w.x, b = d.alpha_y * w.y;
    return 0.5 * (w.z + sqrt(w.z * w.z + a * a + b * b));
}

/* The incident directions: elevations up to just below the horizon. */
static double theta_i(const spec *s, int t)
{
    return s->n_theta == 1 ? 0.0 : t / (double)(s->n_theta - 1) * (PI / 2.0) * 0.995;
}

static double phi_i(const spec *s, int p)
{
    return s->n_phi == 1 ? 0.0 : -PI + 2.0 * PI * p / (double)(s->n_phi - 1);
}

/* A 2D table of D or sigma over the square. */
static float *square_table(const spec *s, bool sigma)
{
    int n = s->ndf_res;
    float *v = malloc((size_t)n * n * sizeof *v);
    for (int y = 0; v && y < n; ++y)
        for (int x = 0; x < n; ++x) {
            vec3 w = spherical(u_to_theta(x / (double)(n - 1)), u_to_phi(y / (double)(n - 1)));
            v[y * n + x] = (float)(sigma ? sigma_of(s->d, w) : tr_d(s->d, w));
        }
    return v;
}

/* The normal at square point u for wo of azimuth phi_o. */
static vec3 normal_at(const spec *s, vec2 u, double phi_o)
{
    bool iso = s->n_phi <= 2;
    return spherical(u_to_theta(u.x), u_to_phi(u.y) + (iso ? phi_o : 0.0));
}

/* The density of visible normals from wo over the square (one slice). */
static void vndf_slice(const spec *s, vec3 wo, double phi_o, float *out)
{
    int n = s->vndf_res;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            vec2 u = v2(x / (double)(n - 1), y / (double)(n - 1));
            vec3 wm = normal_at(s, u, phi_o);
            double jac = 2.0 * PI * PI * u.x * sin(u_to_theta(u.x));
            out[y * n + x] =
                (float)(tr_d(s->d, wm) * fmax(v3_dot(wo, wm), 0.0) * jac / sigma_of(s->d, wo));
        }
}

/* R per wavelength at wi (above the surface) for the normal wm. */
static void reflectance(const spec *s, vec3 wo, vec3 wi, vec3 wm, float *out)
{
    for (int l = 0; l < s->n_lambda; ++l) {
        double r;
        if (s->lambert) {
            double f = s->albedo[l] / PI;
            r = s->jacobian ? f * 4.0 * sigma_of(s->d, wo) * wi.z / tr_d(s->d, wm) : f * wi.z;
        } else {
            /* f 4 sigma cos_i / D = F G2 sigma / cos_o = F (1 + L_o) / (1 + L_o + L_i) */
            double lo = tr_lambda(s->d, wo), li = tr_lambda(s->d, wi);
            double F = fresnel_complex(v3_dot(wo, wm), rgb_grey(1.0), rgb_grey(4.0)).g;
            r = F * (1.0 + lo) / (1.0 + lo + li);
        }
        out[l] = isfinite(r) ? (float)r : 0.0f;
    }
}

/* Spectra and luminance of one incident direction over the sample square. */
static int sample_slice(const spec *s, vec3 wo, double phi_o, const float *vndf, float *spectra,
                        float *lum)
{
    int n = s->sample_res, nv = s->vndf_res, L = s->n_lambda;
    float *copy = malloc((size_t)nv * nv * sizeof *copy);
    if (!copy)
        return 1;
    memcpy(copy, vndf, (size_t)nv * nv * sizeof *copy);
    warp2d w;
    hz_error err;
    if (warp2d_init(&w, copy, (size_t)nv, (size_t)nv, 0, NULL, NULL, true, &err) != HZ_OK) {
        fprintf(stderr, "haze_make_bsdf: vndf: %s\n", err.message);
        return 1;
    }
    const warp2d_slice none = warp2d_slice_none();
    float r[64];
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            vec2 u_wm;
            double pdf;
            bool ok = warp2d_sample(&w, &none, v2(x / (double)(n - 1), y / (double)(n - 1)),
                                    &u_wm, &pdf);
            vec3 wm = normal_at(s, u_wm, phi_o);
            vec3 wi = reflect_dir(wo, wm);
            double mean = 0.0;
            for (int l = 0; l < L; ++l)
                r[l] = 0.0f;
            if (ok && wi.z > 0.0)
                reflectance(s, wo, wi, wm, r);
            for (int l = 0; l < L; ++l) {
                spectra[((size_t)l * n + y) * n + x] = r[l];
                mean += r[l] / L;
            }
            lum[y * n + x] = (float)mean;
        }
    warp2d_free(&w);
    return 0;
}

static int write_spec(const spec *s, const char *dir)
{
    size_t P = (size_t)s->n_phi, T = (size_t)s->n_theta, L = (size_t)s->n_lambda;
    size_t nv = (size_t)s->vndf_res, n = (size_t)s->sample_res;
    float *theta = malloc(T * sizeof *theta), *phi = malloc(P * sizeof *phi);
    float *vndf = malloc(P * T * nv * nv * sizeof *vndf);
    float *spectra = malloc(P * T * L * n * n * sizeof *spectra);
    float *lum = malloc(P * T * n * n * sizeof *lum);
    float *ndf = square_table(s, false), *sigma = square_table(s, true);
    int rc = !(theta && phi && vndf && spectra && lum && ndf && sigma);
    for (size_t t = 0; t < T && !rc; ++t)
        theta[t] = (float)theta_i(s, (int)t);
    for (size_t p = 0; p < P && !rc; ++p)
        phi[p] = (float)phi_i(s, (int)p);
    for (size_t p = 0; p < P && !rc; ++p)
        for (size_t t = 0; t < T && !rc; ++t) {
            /* The wo of the float values the file holds. */
            vec3 wo = spherical(theta[t], phi[p]);
            size_t k = p * T + t;
            vndf_slice(s, wo, phi[p], vndf + k * nv * nv);
            rc = sample_slice(s, wo, phi[p], vndf + k * nv * nv, spectra + k * L * n * n,
                              lum + k * n * n);
        }
    const char *desc = "haze test BRDF (tests/bsdf/make_bsdf.c)";
    uint8_t jac = s->jacobian;
    uint64_t nd = (uint64_t)s->ndf_res;
    field f[] = {
        {"description", 1, 1, {strlen(desc)}, desc},
        {"jacobian", 1, 1, {1}, &jac},
        {"theta_i", 10, 1, {T}, theta},
        {"phi_i", 10, 1, {P}, phi},
        {"wavelengths", 10, 1, {L}, s->lambda},
        {"ndf", 10, 2, {nd, nd}, ndf},
        {"sigma", 10, 2, {nd, nd}, sigma},
        {"vndf", 10, 4, {P, T, nv, nv}, vndf},
        {"luminance", 10, 4, {P, T, n, n}, lum},
        {"spectra", 10, 5, {P, T, L, n, n}, spectra},
    };
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, s->file);
    if (!rc)
        rc = write_tensor(path, f, (int)(sizeof f / sizeof f[0]));
    free(theta);
    free(phi);
    free(vndf);
    free(spectra);
    free(lum);
    free(ndf);
    free(sigma);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: haze_make_bsdf OUTDIR\n");
        return 2;
    }
    static const float grey_l[] = {360, 480, 600, 720, 830};
    static const double grey_a[] = {0.5, 0.5, 0.5, 0.5, 0.5};
    static const float colour_l[] = {400, 500, 600, 700};
    static const double colour_a[] = {0.1, 0.3, 0.6, 0.8};
    /* The Lambertians' parameterisation: a uniform D (alpha 1) leaves the
     * normals near the pole with few sample-square cells (the visible
     * density there goes as x^3), where f then errs by up to 37% at
     * 32 x 32; alpha 0.5 brings the worst to 12% (grazing pairs). */
    const tr_distribution one = {0.5, 0.5};
    const spec specs[] = {
        {"lambert.bsdf", one, true, true, 5, grey_l, grey_a, 1, 16, 64, 64, 32},
        {"lambert-colour.bsdf", one, true, true, 4, colour_l, colour_a, 1, 16, 64, 64, 32},
        {"lambert-nojac.bsdf", one, true, false, 5, grey_l, grey_a, 1, 16, 64, 64, 32},
        {"ggx.bsdf", {0.3, 0.3}, false, true, 5, grey_l, NULL, 1, 16, 64, 64, 32},
        {"ggx-aniso.bsdf", {0.2, 0.5}, false, true, 2, colour_l, NULL, 13, 16, 64, 64, 32},
        {"tiny.bsdf", one, true, true, 2, colour_l, colour_a, 1, 2, 2, 3, 2},
    };
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; ++i)
        if (write_spec(&specs[i], argv[1]) != 0)
            return 1;
    return 0;
}
