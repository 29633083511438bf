#include "core/sampling.h"

#include <assert.h>
#include <math.h>

vec2 sample_uniform_disk_concentric(vec2 u)
{
    double ox = 2.0 * u.x - 1.0, oy = 2.0 * u.y - 1.0;
    if (ox == 0.0 && oy == 0.0)
        return v2(0.0, 0.0);
    double r, theta;
    if (fabs(ox) > fabs(oy)) {
        r = ox;
        theta = (HZ_PI / 4.0) * (oy / ox);
    } else {
        r = oy;
        theta = HZ_PI / 2.0 - (HZ_PI / 4.0) * (ox / oy);
    }
    return v2(r * cos(theta), r * sin(theta));
}

vec2 sample_uniform_disk_polar(vec2 u)
{
    double r = sqrt(u.x), theta = 2.0 * HZ_PI * u.y;
    return v2(r * cos(theta), r * sin(theta));
}

vec2 sample_uniform_triangle(vec2 u)
{
    /* Heitz's low-distortion map (pbrt-v4 SampleUniformTriangle). */
    double b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    return v2(b0, b1);
}

double sample_regular_polygon_area(int n)
{
    assert(n >= 3);
    return 0.5 * n * sin(2.0 * HZ_PI / n);
}

vec2 sample_regular_polygon(int n, double rotation, vec2 u)
{
    assert(n >= 3);
    /* The polygon is n congruent triangles fanned around the centre, so picking
     * one with u.x and reusing the remainder of u.x keeps the map uniform and
     * stratified. */
    double scaled = u.x * n;
    int i = (int)scaled;
    if (i >= n) /* u.x rounding up to 1 */
        i = n - 1;
    vec2 ut = v2(fmin(scaled - i, 0x1.fffffffffffffp-1), u.y);
    double step = 2.0 * HZ_PI / n;
    double a0 = rotation + i * step, a1 = a0 + step;
    vec2 b = sample_uniform_triangle(ut);
    /* Vertex 0 of the triangle is the centre (weight b.x drops out). */
    double b2 = 1.0 - b.x - b.y;
    return v2(b.y * cos(a0) + b2 * cos(a1), b.y * sin(a0) + b2 * sin(a1));
}

bool regular_polygon_contains(int n, double rotation, vec2 p, double eps)
{
    assert(n >= 3);
    double step = 2.0 * HZ_PI / n, apothem = cos(HZ_PI / n);
    for (int i = 0; i < n; ++i) {
        double a = rotation + (i + 0.5) * step; /* outward normal of edge i */
        if (p.x * cos(a) + p.y * sin(a) > apothem + eps)
            return false;
    }
    return true;
}

vec3 sample_uniform_sphere(vec2 u)
{
    double z = 1.0 - 2.0 * u.x;
    double r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * HZ_PI * u.y;
    return v3(r * cos(phi), r * sin(phi), z);
}

vec3 sample_uniform_hemisphere(vec2 u)
{
    double z = u.x;
    double r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * HZ_PI * u.y;
    return v3(r * cos(phi), r * sin(phi), z);
}

vec3 sample_cosine_hemisphere(vec2 u)
{
    vec2 d = sample_uniform_disk_concentric(u);
    return v3(d.x, d.y, sqrt(fmax(0.0, 1.0 - d.x * d.x - d.y * d.y)));
}

vec3 sample_uniform_cone(vec2 u, double cos_max)
{
    double cos_theta = (1.0 - u.x) + u.x * cos_max;
    double sin_theta = sqrt(fmax(0.0, 1.0 - cos_theta * cos_theta));
    double phi = 2.0 * HZ_PI * u.y;
    return v3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta);
}

double sample_exponential(double u, double a)
{
    return -log1p(-u) / a;
}

vec3 equal_area_square_to_sphere(vec2 p)
{
    double u = 2.0 * p.x - 1.0, v = 2.0 * p.y - 1.0;
    double up = fabs(u), vp = fabs(v);
    double signed_distance = 1.0 - (up + vp);
    double r = 1.0 - fabs(signed_distance);
    double phi = (r == 0.0 ? 1.0 : (vp - up) / r + 1.0) * HZ_PI / 4.0;
    double z = copysign(1.0 - r * r, signed_distance);
    double s = r * sqrt(fmax(0.0, 2.0 - r * r));
    return v3(copysign(cos(phi), u) * s, copysign(sin(phi), v) * s, z);
}

vec2 equal_area_sphere_to_square(vec3 d)
{
    double x = fabs(d.x), y = fabs(d.y), z = fabs(d.z);
    double r = sqrt(fmax(0.0, 1.0 - z));
    double a = fmax(x, y), b = fmin(x, y);
    double phi = a == 0.0 ? 0.0 : atan(b / a) * 2.0 / HZ_PI;
    if (x < y)
        phi = 1.0 - phi;
    double v = phi * r, u = r - v;
    if (d.z < 0.0) { /* the southern hemisphere folds over the diagonals */
        double t = u;
        u = 1.0 - v;
        v = 1.0 - t;
    }
    u = copysign(u, d.x);
    v = copysign(v, d.y);
    return v2(0.5 * (u + 1.0), 0.5 * (v + 1.0));
}

vec2 equal_area_wrap(vec2 p)
{
    if (p.x < 0.0) {
        p.x = -p.x;
        p.y = 1.0 - p.y;
    } else if (p.x > 1.0) {
        p.x = 2.0 - p.x;
        p.y = 1.0 - p.y;
    }
    if (p.y < 0.0) {
        p.x = 1.0 - p.x;
        p.y = -p.y;
    } else if (p.y > 1.0) {
        p.x = 1.0 - p.x;
        p.y = 2.0 - p.y;
    }
    return p;
}
