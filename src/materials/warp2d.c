#include "materials/warp2d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Keeps sampled points off the grid's edges, where a row or column of zero
 * density could be picked. */
#define U_EPS 0x1p-40

static double clamp01(double x) { return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0; }

void warp2d_free(warp2d *w)
{
    for (int i = 0; i < WARP2D_MAX_PARAMS; ++i)
        free(w->param_values[i]);
    free(w->data);
    free(w->marginal_cdf);
    free(w->conditional_cdf);
    memset(w, 0, sizeof *w);
}

/* Cumulative sums of one slice by the trapezoid rule (in units of grid
 * cells), normalised so that the last marginal value is 1; the data too. */
static bool build_cdf(const warp2d *w, size_t slice)
{
    size_t nx = w->nx, ny = w->ny;
    float *d = w->data + slice * nx * ny, *cond = w->conditional_cdf + slice * nx * ny;
    float *marg = w->marginal_cdf + slice * ny;
    double *row_sum = malloc(ny * sizeof *row_sum);
    if (!row_sum)
        return false;
    for (size_t y = 0; y < ny; ++y) {
        double sum = 0.0;
        cond[y * nx] = 0.0f;
        for (size_t x = 0; x + 1 < nx; ++x) {
            sum += 0.5 * ((double)d[y * nx + x] + (double)d[y * nx + x + 1]);
            cond[y * nx + x + 1] = (float)sum;
        }
        row_sum[y] = sum;
    }
    double total = 0.0;
    marg[0] = 0.0f;
    for (size_t y = 0; y + 1 < ny; ++y) {
        total += 0.5 * (row_sum[y] + row_sum[y + 1]);
        marg[y + 1] = (float)total;
    }
    free(row_sum);
    if (!(total > 0.0) || !isfinite(total))
        return false;
    double inv = 1.0 / total;
    for (size_t i = 0; i < nx * ny; ++i) {
        cond[i] = (float)(cond[i] * inv);
        d[i] = (float)(d[i] * inv);
    }
    for (size_t y = 0; y < ny; ++y)
        marg[y] = (float)(marg[y] * inv);
    return true;
}

static hz_status check_values(const warp2d *w, bool sampling, hz_error *err)
{
    size_t n = w->slices * w->nx * w->ny;
    for (size_t i = 0; i < n; ++i) {
        if (!isfinite(w->data[i]))
            return hz_fail(err, "value %zu is not finite", i);
        if (sampling && w->data[i] < 0.0f)
            return hz_fail(err, "value %zu is negative (%g)", i, (double)w->data[i]);
    }
    return HZ_OK;
}

static hz_status init_params(warp2d *w, int n_params, const size_t *param_size,
                             const float *const *param_values, hz_error *err)
{
    w->n_params = n_params;
    w->slices = 1;
    for (int i = n_params - 1; i >= 0; --i) {
        if (param_size[i] < 1)
            return hz_fail(err, "a parameter has no values");
        w->param_size[i] = param_size[i];
        w->param_values[i] = malloc(param_size[i] * sizeof(float));
        if (!w->param_values[i])
            return hz_fail(err, "out of memory");
        memcpy(w->param_values[i], param_values[i], param_size[i] * sizeof(float));
        w->param_stride[i] = param_size[i] > 1 ? w->slices : 0;
        w->slices *= param_size[i];
    }
    return HZ_OK;
}

hz_status warp2d_init(warp2d *w, float *data, size_t nx, size_t ny, int n_params,
                      const size_t *param_size, const float *const *param_values, bool sampling,
                      hz_error *err)
{
    memset(w, 0, sizeof *w);
    w->data = data;
    w->nx = nx;
    w->ny = ny;
    w->scale = 1.0;
    if (nx < 2 || ny < 2 || n_params < 0 || n_params > WARP2D_MAX_PARAMS) {
        warp2d_free(w);
        return hz_fail(err, "a grid of %zu x %zu values (at least 2 x 2)", nx, ny);
    }
    if (init_params(w, n_params, param_size, param_values, err) != HZ_OK ||
        check_values(w, sampling, err) != HZ_OK) {
        warp2d_free(w);
        return HZ_ERROR;
    }
    if (!sampling)
        return HZ_OK;
    w->scale = (double)(nx - 1) * (double)(ny - 1);
    w->marginal_cdf = malloc(w->slices * ny * sizeof(float));
    w->conditional_cdf = malloc(w->slices * ny * nx * sizeof(float));
    if (!w->marginal_cdf || !w->conditional_cdf) {
        warp2d_free(w);
        return hz_fail(err, "out of memory");
    }
    for (size_t s = 0; s < w->slices; ++s)
        if (!build_cdf(w, s)) {
            size_t slices = w->slices;
            warp2d_free(w);
            return hz_fail(err, "slice %zu of %zu integrates to 0", s + 1, slices);
        }
    return HZ_OK;
}

warp2d_slice warp2d_slice_at(const warp2d *w, const double *params)
{
    warp2d_slice s = warp2d_slice_none();
    for (int d = 0; d < w->n_params; ++d) {
        if (w->param_size[d] == 1)
            continue;
        /* The last value <= the parameter, among all but the last. */
        const float *v = w->param_values[d];
        size_t lo = 0, hi = w->param_size[d] - 2;
        while (lo < hi) {
            size_t mid = (lo + hi + 1) / 2;
            if (v[mid] <= params[d])
                lo = mid;
            else
                hi = mid - 1;
        }
        double t = clamp01((params[d] - v[lo]) / ((double)v[lo + 1] - v[lo]));
        /* Each slice so far splits in two along this parameter. */
        int n = s.n;
        for (int k = 0; k < n; ++k) {
            s.slice[k] += w->param_stride[d] * lo;
            if (t > 0.0) {
                s.slice[s.n] = s.slice[k] + w->param_stride[d];
                s.weight[s.n++] = s.weight[k] * t;
            }
            s.weight[k] *= 1.0 - t;
        }
        if (t == 1.0) { /* the lower ones weigh nothing */
            for (int k = 0; k < n; ++k) {
                s.slice[k] = s.slice[k + n];
                s.weight[k] = s.weight[k + n];
            }
            s.n = n;
        }
    }
    return s;
}

/* arr[i] interpolated between the slices of s (i within the first slice;
 * slice_size entries per slice). */
static inline double lookup(const float *arr, const warp2d_slice *s, size_t i, size_t slice_size)
{
    double v = 0.0;
    for (int k = 0; k < s->n; ++k)
        v += s->weight[k] * (double)arr[s->slice[k] * slice_size + i];
    return v;
}

double warp2d_eval(const warp2d *w, const warp2d_slice *s, vec2 p)
{
    double px = clamp01(p.x) * (double)(w->nx - 1), py = clamp01(p.y) * (double)(w->ny - 1);
    size_t ix = (size_t)px, iy = (size_t)py;
    ix = ix > w->nx - 2 ? w->nx - 2 : ix;
    iy = iy > w->ny - 2 ? w->ny - 2 : iy;
    double fx = px - (double)ix, fy = py - (double)iy;
    size_t n = w->nx * w->ny, i = iy * w->nx + ix;
    double v00 = lookup(w->data, s, i, n), v10 = lookup(w->data, s, i + 1, n);
    double v01 = lookup(w->data, s, i + w->nx, n);
    double v11 = lookup(w->data, s, i + w->nx + 1, n);
    return ((1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11)) *
           w->scale;
}

/* The t in [0, 1] where the integral of the density a + (b - a) s over
 * [0, t] reaches x, in the form that stays exact when a == b. */
static double solve_linear(double a, double b, double x)
{
    double den = a + sqrt(fmax(a * a + 2.0 * x * (b - a), 0.0));
    return den > 0.0 ? clamp01(2.0 * x / den) : 0.0;
}

/* The largest row r in [0, ny - 2] whose marginal cdf is below u. */
static size_t find_row(const warp2d *w, const warp2d_slice *s, double u)
{
    size_t lo = 0, hi = w->ny - 2;
    while (lo < hi) {
        size_t mid = (lo + hi + 1) / 2;
        if (lookup(w->marginal_cdf, s, mid, w->ny) < u)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

/* The conditional cdf at column x, between rows `row` and row + 1 at t. */
static double cond_at(const warp2d *w, const warp2d_slice *s, size_t row, double t, size_t x)
{
    size_t n = w->nx * w->ny, i = row * w->nx + x;
    return (1.0 - t) * lookup(w->conditional_cdf, s, i, n) +
           t * lookup(w->conditional_cdf, s, i + w->nx, n);
}

bool warp2d_sample(const warp2d *w, const warp2d_slice *s, vec2 u, vec2 *p, double *pdf)
{
    double ux = hz_clamp(u.x, U_EPS, 1.0 - U_EPS), uy = hz_clamp(u.y, U_EPS, 1.0 - U_EPS);
    size_t nx = w->nx, n = nx * w->ny;
    size_t row = find_row(w, s, uy);
    uy -= lookup(w->marginal_cdf, s, row, w->ny);
    double r0 = lookup(w->conditional_cdf, s, row * nx + nx - 1, n);
    double r1 = lookup(w->conditional_cdf, s, row * nx + 2 * nx - 1, n);
    double t = solve_linear(r0, r1, uy);
    ux *= (1.0 - t) * r0 + t * r1;
    size_t lo = 0, hi = nx - 2;
    while (lo < hi) {
        size_t mid = (lo + hi + 1) / 2;
        if (cond_at(w, s, row, t, mid) < ux)
            lo = mid;
        else
            hi = mid - 1;
    }
    ux -= cond_at(w, s, row, t, lo);
    size_t i = row * nx + lo;
    double v00 = lookup(w->data, s, i, n), v10 = lookup(w->data, s, i + 1, n);
    double v01 = lookup(w->data, s, i + nx, n), v11 = lookup(w->data, s, i + nx + 1, n);
    double c0 = (1.0 - t) * v00 + t * v01, c1 = (1.0 - t) * v10 + t * v11;
    double sx = solve_linear(c0, c1, ux);
    *p = v2(((double)lo + sx) / (double)(nx - 1), ((double)row + t) / (double)(w->ny - 1));
    *pdf = ((1.0 - sx) * c0 + sx * c1) * w->scale;
    return *pdf > 0.0 && isfinite(*pdf);
}

vec2 warp2d_invert(const warp2d *w, const warp2d_slice *s, vec2 p, double *pdf)
{
    size_t nx = w->nx, n = nx * w->ny;
    double px = clamp01(p.x) * (double)(nx - 1), py = clamp01(p.y) * (double)(w->ny - 1);
    size_t ix = (size_t)px, iy = (size_t)py;
    ix = ix > nx - 2 ? nx - 2 : ix;
    iy = iy > w->ny - 2 ? w->ny - 2 : iy;
    double fx = px - (double)ix, fy = py - (double)iy;
    size_t i = iy * nx + ix;
    double v00 = lookup(w->data, s, i, n), v10 = lookup(w->data, s, i + 1, n);
    double v01 = lookup(w->data, s, i + nx, n), v11 = lookup(w->data, s, i + nx + 1, n);
    double c0 = (1.0 - fy) * v00 + fy * v01, c1 = (1.0 - fy) * v10 + fy * v11;
    *pdf = ((1.0 - fx) * c0 + fx * c1) * w->scale;
    double sx = fx * (c0 + 0.5 * fx * (c1 - c0)) + cond_at(w, s, iy, fy, ix);
    double r0 = lookup(w->conditional_cdf, s, iy * nx + nx - 1, n);
    double r1 = lookup(w->conditional_cdf, s, iy * nx + 2 * nx - 1, n);
    double row_total = (1.0 - fy) * r0 + fy * r1;
    sx = row_total > 0.0 ? sx / row_total : 0.0;
    double sy = fy * (r0 + 0.5 * fy * (r1 - r0)) + lookup(w->marginal_cdf, s, iy, w->ny);
    return v2(clamp01(sx), clamp01(sy));
}
