#include "color/rgb_spectrum.h"

#include <math.h>

#include "color/illuminant.h"

static double sigmoid(double x)
{
    if (isinf(x))
        return x > 0.0 ? 1.0 : 0.0;
    return 0.5 + x / (2.0 * sqrt(1.0 + x * x));
}

double sigmoid_poly_eval(sigmoid_poly p, double lambda)
{
    return sigmoid((p.c0 * lambda + p.c1) * lambda + p.c2);
}

double sigmoid_poly_max(sigmoid_poly p)
{
    double m = hz_fmax(sigmoid_poly_eval(p, 360.0), sigmoid_poly_eval(p, 830.0));
    double vertex = -p.c1 / (2.0 * p.c0); /* NaN or infinite when c0 = 0 */
    if (vertex >= 360.0 && vertex <= 830.0)
        m = hz_fmax(m, sigmoid_poly_eval(p, vertex));
    return m;
}

static double unit(double v) { return v > 0.0 ? (v < 1.0 ? v : 1.0) : 0.0; }

/* The largest k in [0, res - 2] with nodes[k] < v (0 when none), and where v
 * lies between nodes k and k + 1. */
static int cell(const float *nodes, int res, double v, double *frac)
{
    int lo = 0, hi = res - 2;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (nodes[mid] < v)
            lo = mid;
        else
            hi = mid - 1;
    }
    *frac = (v - nodes[lo]) / ((double)nodes[lo + 1] - nodes[lo]); /* not in float */
    return lo;
}

sigmoid_poly sigmoid_poly_from_rgb(const rgb2spec_table *table, rgb c)
{
    double v[3] = {unit(c.r), unit(c.g), unit(c.b)};
    if (v[0] == v[1] && v[1] == v[2]) /* grey: the sigmoid's inverse */
        return (sigmoid_poly){0.0, 0.0, (v[0] - 0.5) / sqrt(v[0] * (1.0 - v[0]))};
    const rgb2spec_solution *t = table->solution;
    int res = t->res;
    int m = v[0] > v[1] ? (v[0] > v[2] ? 0 : 2) : (v[1] > v[2] ? 1 : 2);
    double z = v[m], dx, dy, dz;
    int xi = cell(t->xy_nodes, res, v[(m + 1) % 3] / z, &dx);
    int yi = cell(t->xy_nodes, res, v[(m + 2) % 3] / z, &dy);
    int zi = cell(t->z_nodes, res, z, &dz);
    double out[3];
    for (int i = 0; i < 3; ++i) {
        const float *base = t->coeffs + 3 * (((size_t)(m * res + zi) * res + yi) * res + xi) + i;
        size_t sx = 3, sy = 3 * (size_t)res, sz = 3 * (size_t)res * res;
        double c00 = hz_lerp(dx, base[0], base[sx]);
        double c10 = hz_lerp(dx, base[sy], base[sy + sx]);
        double c01 = hz_lerp(dx, base[sz], base[sz + sx]);
        double c11 = hz_lerp(dx, base[sz + sy], base[sz + sy + sx]);
        out[i] = hz_lerp(dz, hz_lerp(dy, c00, c10), hz_lerp(dy, c01, c11));
    }
    return (sigmoid_poly){out[0], out[1], out[2]};
}

rgb_albedo_spectrum rgb_albedo_spectrum_from_rgb(const rgb2spec_table *t, rgb c)
{
    return (rgb_albedo_spectrum){sigmoid_poly_from_rgb(t, c)};
}

double rgb_albedo_spectrum_eval(rgb_albedo_spectrum s, double lambda)
{
    return sigmoid_poly_eval(s.poly, lambda);
}

/* 2 max(c) and the polynomial of c / (2 max): pbrt-v4's split of an
 * unbounded RGB, which looks up a colour of largest component 1/2, away from
 * the top of the table where spectra saturate. */
static void split_unbounded(const rgb2spec_table *t, rgb c, double *scale, sigmoid_poly *poly)
{
    rgb v = rgb_make(c.r > 0.0 ? c.r : 0.0, c.g > 0.0 ? c.g : 0.0, c.b > 0.0 ? c.b : 0.0);
    *scale = 2.0 * rgb_max(v);
    *poly = sigmoid_poly_from_rgb(t, *scale > 0.0 ? rgb_scale(v, 1.0 / *scale) : v);
}

rgb_unbounded_spectrum rgb_unbounded_spectrum_from_rgb(const rgb2spec_table *t, rgb c)
{
    rgb_unbounded_spectrum s;
    split_unbounded(t, c, &s.scale, &s.poly);
    return s;
}

double rgb_unbounded_spectrum_eval(rgb_unbounded_spectrum s, double lambda)
{
    return s.scale * sigmoid_poly_eval(s.poly, lambda);
}

rgb_illuminant_spectrum rgb_illuminant_spectrum_from_rgb(const rgb2spec_table *t, rgb c)
{
    rgb_illuminant_spectrum s = {.table = t};
    split_unbounded(t, c, &s.scale, &s.poly);
    return s;
}

double rgb_illuminant_spectrum_eval(rgb_illuminant_spectrum s, double lambda)
{
    if (s.scale == 0.0)
        return 0.0;
    return s.scale * sigmoid_poly_eval(s.poly, lambda) * rgb_spectrum_illuminant(s.table, lambda);
}

double rgb_spectrum_illuminant(const rgb2spec_table *t, double lambda)
{
    return t->solution->illuminant_scale *
           illuminant_raw(illuminant_of_color_space(t->cs), lambda);
}

vec3 rgb_spectrum_white_xyz(const rgb2spec_table *t)
{
    const double *w = t->solution->white_xyz;
    return v3(w[0], w[1], w[2]);
}

rgb rgb_spectrum_rgb_from_xyz(const rgb2spec_table *t, vec3 v)
{
    const double *m = t->solution->rgb_from_xyz;
    return rgb_make(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
                    m[6] * v.x + m[7] * v.y + m[8] * v.z);
}

vec3 rgb_spectrum_xyz_from_rgb(const rgb2spec_table *t, rgb c)
{
    const double *m = t->solution->xyz_from_rgb;
    return v3(m[0] * c.r + m[1] * c.g + m[2] * c.b, m[3] * c.r + m[4] * c.g + m[5] * c.b,
              m[6] * c.r + m[7] * c.g + m[8] * c.b);
}
