/* Small value types and their arithmetic: vec2, vec3, rgb. All inline. */
#ifndef HAZE_CORE_VEC_H
#define HAZE_CORE_VEC_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#define HZ_PI 3.14159265358979323846
#define HZ_INV_PI 0.31830988618379067154

/* fmax and fmin as glibc computes them (a NaN argument yields the other;
 * equal arguments, +0 and -0 included, yield b), inline: the compiler calls
 * libm for fmax and fmin, which hot loops pay for (a few million calls a
 * frame through rgb_max alone). */
static inline double hz_fmax(double a, double b) { return a > b || b != b ? a : b; }
static inline double hz_fmin(double a, double b) { return a < b || b != b ? a : b; }

typedef struct { double x, y; } vec2;
typedef struct { double x, y, z; } vec3;
/* Linear (scene-referred) RGB in the sRGB/Rec.709 primaries: r, g, b; w is
 * a copy of g, kept by every function below, so that reductions over four
 * lanes (rgb_max, rgb_is_black) give the three channels' answer. Spectral
 * rendering (color/wavelengths.h) carries four wavelengths in the same
 * struct, one per lane r, g, b, w; its reductions that differ from RGB's
 * take the lane count (rgb_lanes_avg). Build one from three channels with
 * rgb_make, never a three-element literal. */
typedef struct { double r, g, b, w; } rgb;

static inline vec2 v2(double x, double y) { return (vec2){x, y}; }
static inline vec3 v3(double x, double y, double z) { return (vec3){x, y, z}; }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v3_scale(vec3 a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_neg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
static inline double v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_length_sq(vec3 a) { return v3_dot(a, a); }
static inline double v3_length(vec3 a) { return sqrt(v3_dot(a, a)); }
static inline vec3 v3_normalize(vec3 a) { return v3_scale(a, 1.0 / v3_length(a)); }
static inline vec3 v3_lerp(double t, vec3 a, vec3 b)
{
    return v3_add(v3_scale(a, 1.0 - t), v3_scale(b, t));
}
static inline double v3_max_component(vec3 a)
{
    return hz_fmax(a.x, hz_fmax(a.y, a.z));
}
static inline vec3 v3_min(vec3 a, vec3 b)
{
    return v3(hz_fmin(a.x, b.x), hz_fmin(a.y, b.y), hz_fmin(a.z, b.z));
}
static inline vec3 v3_max(vec3 a, vec3 b)
{
    return v3(hz_fmax(a.x, b.x), hz_fmax(a.y, b.y), hz_fmax(a.z, b.z));
}
static inline vec3 v3_abs(vec3 a) { return v3(fabs(a.x), fabs(a.y), fabs(a.z)); }
static inline bool v3_is_finite(vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
/* Builds an orthonormal basis (b1, b2) around unit vector n (Duff et al. 2017). */
static inline void v3_basis(vec3 n, vec3 *b1, vec3 *b2)
{
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    *b1 = v3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    *b2 = v3(b, sign + n.y * n.y * a, -n.y);
}

static inline rgb rgb_make(double r, double g, double b) { return (rgb){r, g, b, g}; }
static inline rgb rgb_grey(double v) { return (rgb){v, v, v, v}; }
static inline rgb rgb_add(rgb a, rgb b) { return (rgb){a.r + b.r, a.g + b.g, a.b + b.b, a.w + b.w}; }
static inline rgb rgb_mul(rgb a, rgb b) { return (rgb){a.r * b.r, a.g * b.g, a.b * b.b, a.w * b.w}; }
static inline rgb rgb_sub(rgb a, rgb b) { return (rgb){a.r - b.r, a.g - b.g, a.b - b.b, a.w - b.w}; }
static inline rgb rgb_scale(rgb a, double s) { return (rgb){a.r * s, a.g * s, a.b * s, a.w * s}; }
/* e^{-sigma d} per lane; a lane that does not attenuate stays 1 (0 *
 * INFINITY would be NaN). A grey sigma takes one exp. */
static inline double exp_neg_lane(double sigma, double d) { return sigma > 0.0 ? exp(-sigma * d) : 1.0; }
static inline rgb rgb_exp_neg(rgb sigma, double d)
{
    if (sigma.r == sigma.g && sigma.g == sigma.b && sigma.b == sigma.w)
        return rgb_grey(exp_neg_lane(sigma.r, d));
    double g = exp_neg_lane(sigma.g, d);
    return (rgb){exp_neg_lane(sigma.r, d), g, exp_neg_lane(sigma.b, d),
                 sigma.w == sigma.g ? g : exp_neg_lane(sigma.w, d)};
}
static inline bool rgb_is_black(rgb a) { return a.r == 0.0 && a.g == 0.0 && a.b == 0.0 && a.w == 0.0; }
static inline double rgb_max(rgb a) { return hz_fmax(a.r, hz_fmax(a.g, hz_fmax(a.b, a.w))); }
/* The mean of the three channels (RGB rendering). */
static inline double rgb_avg(rgb a) { return (a.r + a.g + a.b) / 3.0; }
/* The mean of the first `lanes` lanes: 3 in RGB, 4 in spectral rendering. */
static inline double rgb_lanes_avg(rgb a, int lanes)
{
    return lanes == 3 ? rgb_avg(a) : (a.r + a.g + a.b + a.w) / 4.0;
}
/* a / b per lane, 0 where b is not positive. */
static inline double div_or_zero(double a, double b) { return b > 0.0 ? a / b : 0.0; }
static inline rgb rgb_div_or_zero(rgb a, rgb b)
{
    return (rgb){div_or_zero(a.r, b.r), div_or_zero(a.g, b.g), div_or_zero(a.b, b.b),
                 div_or_zero(a.w, b.w)};
}
/* f of each lane. */
static inline rgb rgb_map(rgb a, double (*f)(double)) { return (rgb){f(a.r), f(a.g), f(a.b), f(a.w)}; }
/* Channel or lane i (0 r, 1 g, 2 b, 3 w). */
static inline double rgb_ch(rgb c, int i) { return i == 0 ? c.r : i == 1 ? c.g : i == 2 ? c.b : c.w; }
/* Lane i set to v (the copy w follows g only through rgb_make). */
static inline void rgb_set_ch(rgb *c, int i, double v)
{
    double *lane = i == 0 ? &c->r : i == 1 ? &c->g : i == 2 ? &c->b : &c->w;
    *lane = v;
}
/* Rec.709 luminance. */
static inline double rgb_luminance(rgb a) { return 0.2126 * a.r + 0.7152 * a.g + 0.0722 * a.b; }

static inline double hz_clamp(double v, double lo, double hi) { return v < lo ? lo : (v > hi ? hi : v); }
static inline double hz_lerp(double t, double a, double b) { return (1.0 - t) * a + t * b; }
/* nextafter(x, INFINITY) inline (stepping past surfaces calls it for every
 * crossing): the next double up; +inf and NaN stay, +-0 give the smallest
 * subnormal. */
static inline double hz_next_up(double x)
{
    if (!(x < INFINITY)) /* +inf, NaN */
        return x;
    if (x == 0.0)
        return 0x1p-1074;
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    bits += x > 0.0 ? 1 : UINT64_MAX; /* toward +inf: up in magnitude, or down */
    memcpy(&x, &bits, sizeof x);
    return x;
}
static inline double hz_radians(double deg) { return deg * (HZ_PI / 180.0); }

#endif
