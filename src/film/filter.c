/* pbrt-v4's pixel filters. Box and triangle are sampled exactly (weight 1);
 * the others through pbrt-v4's FilterSampler: |f| tabulated at the centres
 * of 32 cells per unit radius, sampled as a 2D piecewise-constant
 * distribution, weight = f(cell) / pdf, which is ±(tabulated integral of |f|).
 * Matching pbrt-v4 here keeps images comparable with pbrt-v4's. */
#include "film/filter.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/params.h"

/* Largest radius accepted: the sampling table has (32 r)^2 cells. */
#define FILTER_MAX_RADIUS 32.0
#define ONE_MINUS_EPSILON 0x1.fffffffffffffp-1
/* Buckets of u in each sampling cdf's guide table. */
#define FILTER_GUIDE 64

struct filter {
    filter_kind kind;
    vec2 radius;
    double sigma, exp_x, exp_y; /* gaussian */
    double b, c;                /* mitchell */
    double tau;                 /* lanczos (pbrt-v4's "sinc") */
    /* FilterSampler table (gaussian, mitchell, lanczos). */
    int nx, ny;
    double *f;         /* nx*ny tabulated values, row y = cells at one height */
    double *row_cdf;   /* ny*(nx+1) */
    double *row_int;   /* ny: integral of |f| over each row (per unit x) */
    double *marg_cdf;  /* ny+1 */
    double marg_int;   /* integral of |f| over the domain */
    /* Guide tables (FILTER_GUIDE + 1 per cdf): entry j is find_interval at u
     * = j / FILTER_GUIDE, so a lookup searches only between two entries. */
    uint32_t *row_guide;  /* ny*(FILTER_GUIDE+1) */
    uint32_t *marg_guide; /* FILTER_GUIDE+1 */
};

static double gaussian(double x, double sigma)
{
    return exp(-x * x / (2.0 * sigma * sigma)) / sqrt(2.0 * HZ_PI * sigma * sigma);
}

static double mitchell_1d(double b, double c, double x)
{
    x = fabs(x);
    if (x <= 1.0)
        return ((12 - 9 * b - 6 * c) * x * x * x + (-18 + 12 * b + 6 * c) * x * x + (6 - 2 * b)) / 6;
    if (x <= 2.0)
        return ((-b - 6 * c) * x * x * x + (6 * b + 30 * c) * x * x + (-12 * b - 48 * c) * x +
                (8 * b + 24 * c)) / 6;
    return 0.0;
}

static double sinc(double x)
{
    if (fabs(x) < 1e-5)
        return 1.0 - HZ_PI * HZ_PI * x * x / 6.0;
    return sin(HZ_PI * x) / (HZ_PI * x);
}

static double windowed_sinc(double x, double radius, double tau)
{
    if (fabs(x) > radius)
        return 0.0;
    return sinc(x) * sinc(x / tau);
}

double filter_evaluate(const filter *f, vec2 p)
{
    switch (f->kind) {
    case FILTER_BOX:
        return (fabs(p.x) <= f->radius.x && fabs(p.y) <= f->radius.y) ? 1.0 : 0.0;
    case FILTER_TRIANGLE:
        return fmax(0.0, f->radius.x - fabs(p.x)) * fmax(0.0, f->radius.y - fabs(p.y));
    case FILTER_GAUSSIAN:
        return fmax(0.0, gaussian(p.x, f->sigma) - f->exp_x) *
               fmax(0.0, gaussian(p.y, f->sigma) - f->exp_y);
    case FILTER_MITCHELL:
        return mitchell_1d(f->b, f->c, 2.0 * p.x / f->radius.x) *
               mitchell_1d(f->b, f->c, 2.0 * p.y / f->radius.y);
    case FILTER_LANCZOS:
        return windowed_sinc(p.x, f->radius.x, f->tau) * windowed_sinc(p.y, f->radius.y, f->tau);
    }
    return 0.0;
}

/* ---- FilterSampler ------------------------------------------------- */

/* The largest i in [lo, hi) with cdf[i] <= u, given cdf[lo] <= u (or lo =
 * 0) and cdf[hi] > u (or hi = the cdf's cell count). */
static size_t bisect(const double *cdf, size_t lo, size_t hi, double u)
{
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Largest i in [0, n) with cdf[i] <= u; cdf has n+1 entries. */
static size_t find_interval(const double *cdf, size_t n, double u)
{
    return bisect(cdf, 0, n, u);
}

/* find_interval's answer from the guide table g of cdf: the same index,
 * searched between the entries of u's bucket (widened by one where u's
 * bucket rounds across a boundary). */
static size_t find_interval_guided(const double *cdf, size_t n, const uint32_t *g, double u)
{
    double b = u * FILTER_GUIDE;
    size_t j = b > 0.0 ? (size_t)b : 0;
    if (j >= FILTER_GUIDE)
        j = FILTER_GUIDE - 1;
    size_t lo = g[j], hi = (size_t)g[j + 1] + 1;
    while (lo > 0 && cdf[lo] > u)
        --lo;
    if (hi > n)
        hi = n;
    while (hi < n && cdf[hi] <= u)
        ++hi;
    return bisect(cdf, lo, hi, u);
}

static void build_guide(const double *cdf, size_t n, uint32_t *g)
{
    for (size_t j = 0; j <= FILTER_GUIDE; ++j)
        g[j] = (uint32_t)find_interval(cdf, n, (double)j / FILTER_GUIDE);
}

static hz_status build_table(filter *f, hz_error *err)
{
    f->nx = (int)(32.0 * f->radius.x);
    f->ny = (int)(32.0 * f->radius.y);
    if (f->nx < 1) /* pbrt-v4 would build an empty table; one cell still samples the filter */
        f->nx = 1;
    if (f->ny < 1)
        f->ny = 1;
    size_t nx = (size_t)f->nx, ny = (size_t)f->ny;
    f->f = malloc(nx * ny * sizeof *f->f);
    f->row_cdf = malloc(ny * (nx + 1) * sizeof *f->row_cdf);
    f->row_int = malloc(ny * sizeof *f->row_int);
    f->marg_cdf = malloc((ny + 1) * sizeof *f->marg_cdf);
    if (!f->f || !f->row_cdf || !f->row_int || !f->marg_cdf)
        return hz_fail(err, "filter: out of memory for the sampling table");
    double w = 2.0 * f->radius.x, h = 2.0 * f->radius.y;
    for (size_t y = 0; y < ny; y++)
        for (size_t x = 0; x < nx; x++) {
            vec2 p = v2(-f->radius.x + w * (x + 0.5) / nx, -f->radius.y + h * (y + 0.5) / ny);
            f->f[y * nx + x] = filter_evaluate(f, p);
        }
    /* As pbrt-v4's PiecewiseConstant1D: cdf of |f|, uniform when all zero. */
    for (size_t y = 0; y < ny; y++) {
        double *cdf = f->row_cdf + y * (nx + 1);
        cdf[0] = 0.0;
        for (size_t x = 0; x < nx; x++)
            cdf[x + 1] = cdf[x] + fabs(f->f[y * nx + x]) * w / nx;
        f->row_int[y] = cdf[nx] / w; /* per unit of x, as the marginal's function */
        for (size_t x = 1; x <= nx; x++)
            cdf[x] = cdf[nx] == 0.0 ? (double)x / nx : cdf[x] / cdf[nx];
    }
    f->marg_cdf[0] = 0.0;
    for (size_t y = 0; y < ny; y++)
        f->marg_cdf[y + 1] = f->marg_cdf[y] + f->row_int[y] * h / ny;
    double total = f->marg_cdf[ny];
    f->marg_int = total * w; /* integral of |f| over the whole domain */
    for (size_t y = 1; y <= ny; y++)
        f->marg_cdf[y] = total == 0.0 ? (double)y / ny : f->marg_cdf[y] / total;
    f->row_guide = malloc(ny * (FILTER_GUIDE + 1) * sizeof *f->row_guide);
    f->marg_guide = malloc((FILTER_GUIDE + 1) * sizeof *f->marg_guide);
    if (!f->row_guide || !f->marg_guide)
        return hz_fail(err, "filter: out of memory for the sampling table");
    for (size_t y = 0; y < ny; y++)
        build_guide(f->row_cdf + y * (nx + 1), nx, f->row_guide + y * (FILTER_GUIDE + 1));
    build_guide(f->marg_cdf, ny, f->marg_guide);
    return HZ_OK;
}

/* Samples one piecewise-constant 1D distribution: position in [0,1) and the cell. */
static double sample_1d(const double *cdf, size_t n, const uint32_t *guide, double u,
                        size_t *cell)
{
    size_t o = find_interval_guided(cdf, n, guide, u);
    double du = u - cdf[o];
    if (cdf[o + 1] - cdf[o] > 0.0)
        du /= cdf[o + 1] - cdf[o];
    *cell = o;
    double t = (o + du) / n;
    return t < ONE_MINUS_EPSILON ? t : ONE_MINUS_EPSILON;
}

static filter_sample sample_table(const filter *f, vec2 u)
{
    size_t nx = (size_t)f->nx, ny = (size_t)f->ny;
    filter_sample s = {v2(0.0, 0.0), 0.0};
    if (f->marg_int == 0.0)
        return s;
    size_t cy, cx;
    double ty = sample_1d(f->marg_cdf, ny, f->marg_guide, u.y, &cy);
    double tx = sample_1d(f->row_cdf + cy * (nx + 1), nx,
                          f->row_guide + cy * (FILTER_GUIDE + 1), u.x, &cx);
    s.p = v2(-f->radius.x + 2.0 * f->radius.x * tx, -f->radius.y + 2.0 * f->radius.y * ty);
    double v = f->f[cy * nx + cx];
    /* f / pdf with pdf = |f| / integral(|f|); a zero cell has zero probability. */
    s.weight = v > 0.0 ? f->marg_int : (v < 0.0 ? -f->marg_int : 0.0);
    return s;
}

/* pbrt-v4's SampleTent(u, 1): pick a side with probability 1/2, then a
 * linear ramp on it; exact importance sampling of the triangle. */
static double sample_tent(double u)
{
    if (u < 0.5) {
        double up = fmin(u * 2.0, ONE_MINUS_EPSILON);
        return -1.0 + sqrt(up);
    }
    double up = fmin((u - 0.5) * 2.0, ONE_MINUS_EPSILON);
    return 1.0 - sqrt(1.0 - up);
}

filter_sample filter_sample_offset(const filter *f, vec2 u)
{
    switch (f->kind) {
    case FILTER_BOX:
        return (filter_sample){v2(hz_lerp(u.x, -f->radius.x, f->radius.x),
                                  hz_lerp(u.y, -f->radius.y, f->radius.y)), 1.0};
    case FILTER_TRIANGLE:
        return (filter_sample){v2(f->radius.x * sample_tent(u.x), f->radius.y * sample_tent(u.y)), 1.0};
    case FILTER_GAUSSIAN:
    case FILTER_MITCHELL:
    case FILTER_LANCZOS:
        return sample_table(f, u);
    }
    return (filter_sample){v2(0.0, 0.0), 0.0};
}

/* ---- creation ------------------------------------------------------- */

filter_kind filter_get_kind(const filter *f) { return f->kind; }
vec2 filter_radius(const filter *f) { return f->radius; }

double filter_integral(const filter *f)
{
    switch (f->kind) {
    case FILTER_BOX:
        return 4.0 * f->radius.x * f->radius.y;
    case FILTER_TRIANGLE:
        return f->radius.x * f->radius.x * f->radius.y * f->radius.y;
    case FILTER_GAUSSIAN: {
        double ix = erf(f->radius.x / (f->sigma * sqrt(2.0))) - 2.0 * f->radius.x * f->exp_x;
        double iy = erf(f->radius.y / (f->sigma * sqrt(2.0))) - 2.0 * f->radius.y * f->exp_y;
        return ix * iy;
    }
    case FILTER_MITCHELL:
        return f->radius.x * f->radius.y / 4.0;
    case FILTER_LANCZOS: { /* signed integral of the table, as pbrt-v4 does numerically */
        double sum = 0.0;
        for (int i = 0; i < f->nx * f->ny; i++)
            sum += f->f[i];
        return sum * 4.0 * f->radius.x * f->radius.y / (f->nx * f->ny);
    }
    }
    return 0.0;
}

void filter_destroy(filter *f)
{
    if (!f)
        return;
    free(f->f);
    free(f->row_cdf);
    free(f->row_int);
    free(f->marg_cdf);
    free(f->row_guide);
    free(f->marg_guide);
    free(f);
}

static void check_radius(param_list *pl, const char *name, double r)
{
    if (!(r > 0.0 && r <= FILTER_MAX_RADIUS))
        params_reject(pl, name, "\"float %s\" must be in (0, %g], got %g", name, FILTER_MAX_RADIUS, r);
}

static void check_positive(param_list *pl, const char *name, double v)
{
    if (!(v > 0.0 && isfinite(v)))
        params_reject(pl, name, "\"float %s\" must be positive, got %g", name, v);
}

static void check_finite(param_list *pl, const char *name, double v)
{
    if (!isfinite(v))
        params_reject(pl, name, "\"float %s\" must be finite", name);
}

filter *filter_create(scene_entity *e, hz_error *err)
{
    const char *type = e->type ? e->type : "";
    filter *f = calloc(1, sizeof *f);
    if (!f) {
        hz_fail(err, "filter: out of memory");
        return NULL;
    }
    double r = 0.0;
    if (strcmp(type, "box") == 0) {
        f->kind = FILTER_BOX;
        r = 0.5;
    } else if (strcmp(type, "triangle") == 0) {
        f->kind = FILTER_TRIANGLE;
        r = 2.0;
    } else if (strcmp(type, "gaussian") == 0) {
        f->kind = FILTER_GAUSSIAN;
        r = 1.5;
    } else if (strcmp(type, "mitchell") == 0) {
        f->kind = FILTER_MITCHELL;
        r = 2.0;
    } else if (strcmp(type, "sinc") == 0 || strcmp(type, "lanczos") == 0) {
        f->kind = FILTER_LANCZOS;
        r = 4.0;
    } else {
        hz_fail_at(err, e->loc,
                   "unknown PixelFilter \"%s\" (supported: \"box\", \"triangle\", \"gaussian\", "
                   "\"mitchell\", \"sinc\")", type);
        free(f);
        return NULL;
    }
    param_list *pl = &e->params;
    f->radius = v2(params_float(pl, "xradius", r), params_float(pl, "yradius", r));
    check_radius(pl, "xradius", f->radius.x);
    check_radius(pl, "yradius", f->radius.y);
    switch (f->kind) {
    case FILTER_BOX:
    case FILTER_TRIANGLE:
        break;
    case FILTER_GAUSSIAN:
        f->sigma = params_float(pl, "sigma", 0.5);
        check_positive(pl, "sigma", f->sigma);
        break;
    case FILTER_MITCHELL:
        f->b = params_float(pl, "B", 1.0 / 3.0);
        f->c = params_float(pl, "C", 1.0 / 3.0);
        check_finite(pl, "B", f->b);
        check_finite(pl, "C", f->c);
        break;
    case FILTER_LANCZOS:
        f->tau = params_float(pl, "tau", 3.0);
        check_positive(pl, "tau", f->tau);
        break;
    }
    char what[96];
    snprintf(what, sizeof what, "PixelFilter \"%s\"", type);
    if (params_finish(pl, what, err) != HZ_OK) {
        free(f);
        return NULL;
    }
    if (f->kind == FILTER_GAUSSIAN) {
        f->exp_x = gaussian(f->radius.x, f->sigma);
        f->exp_y = gaussian(f->radius.y, f->sigma);
    }
    if (f->kind != FILTER_BOX && f->kind != FILTER_TRIANGLE) {
        if (build_table(f, err) != HZ_OK) {
            filter_destroy(f);
            return NULL;
        }
        if (f->marg_int == 0.0) {
            hz_fail_at(err, e->loc, "PixelFilter \"%s\" is zero everywhere with these parameters", type);
            filter_destroy(f);
            return NULL;
        }
    }
    return f;
}
