/* pbrt-v4's ray-curve intersection (Curve::IntersectRay and
 * RecursiveIntersect): each segment is cut into 2^splitdepth pieces (one
 * Embree primitive each); a piece is looked at from the ray (the ray along
 * z), split in halves down to a depth chosen from its flatness, and each
 * last piece is hit where the ray passes within half the width of the curve
 * point that the ray's projection onto its chord picks, between the planes
 * perpendicular to the curve at its ends. Done in double in the shape's
 * space, so the hits are pbrt-v4's (a ray-facing flat ribbon; "cylinder"
 * only shades differently; a "ribbon"'s width is foreshortened by its
 * normal). */
#include "geometry/geometry.h"

#include <math.h>

static vec3 lerp3(double t, vec3 a, vec3 b) { return v3_add(v3_scale(a, 1.0 - t), v3_scale(b, t)); }

/* pbrt-v4's BlossomCubicBezier. */
static vec3 blossom(const vec3 p[4], double u0, double u1, double u2)
{
    vec3 a[3] = {lerp3(u0, p[0], p[1]), lerp3(u0, p[1], p[2]), lerp3(u0, p[2], p[3])};
    vec3 b[2] = {lerp3(u1, a[0], a[1]), lerp3(u1, a[1], a[2])};
    return lerp3(u2, b[0], b[1]);
}

void geometry_curve_piece(const geom_shape *s, unsigned prim, vec3 cp[4], double *u0, double *u1)
{
    unsigned pieces = 1u << s->curve_split;
    size_t seg = prim >> s->curve_split;
    const double *c = &s->curve_cp[12 * seg];
    vec3 p[4];
    for (int i = 0; i < 4; ++i)
        p[i] = v3(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
    unsigned k = prim & (pieces - 1u);
    *u0 = (double)k / pieces;
    *u1 = (double)(k + 1) / pieces;
    cp[0] = blossom(p, *u0, *u0, *u0);
    cp[1] = blossom(p, *u0, *u0, *u1);
    cp[2] = blossom(p, *u0, *u1, *u1);
    cp[3] = blossom(p, *u1, *u1, *u1);
}

double geometry_curve_width(const geom_shape *s, size_t seg, double u)
{
    const double *w = &s->curve_w[2 * seg];
    return (1.0 - u) * w[0] + u * w[1];
}

vec3 geometry_curve_ribbon_normal(const geom_shape *s, size_t seg, double u)
{
    const double *cn = &s->curve_n[6 * seg];
    vec3 n0 = v3(cn[0], cn[1], cn[2]), n1 = v3(cn[3], cn[4], cn[5]);
    double angle = acos(fmin(fmax(v3_dot(n0, n1), -1.0), 1.0));
    if (!(angle > 0.0))
        return n0;
    double inv = 1.0 / sin(angle);
    return v3_add(v3_scale(n0, sin((1.0 - u) * angle) * inv), v3_scale(n1, sin(u * angle) * inv));
}

/* The ray and what the recursion keeps. */
typedef struct {
    const geom_shape *s;
    size_t seg;
    vec3 d;           /* the ray's direction (in the shape's space) */
    double len, zmax; /* |d|, |d| tfar: the ray's extent along its z */
    double znear;     /* |d| tnear */
    double best_z, best_u;
} curve_query;

static void bounds_xyz(const vec3 cp[4], double pad, vec3 *lo, vec3 *hi)
{
    *lo = v3_min(v3_min(cp[0], cp[1]), v3_min(cp[2], cp[3]));
    *hi = v3_max(v3_max(cp[0], cp[1]), v3_max(cp[2], cp[3]));
    *lo = v3_sub(*lo, v3(pad, pad, pad));
    *hi = v3_add(*hi, v3(pad, pad, pad));
}

/* Whether the box of the ray-space control points, widened by half the
 * width, meets the ray (x = y = 0, z in [0, zmax]). */
static bool ray_meets(const curve_query *q, const vec3 cp[4], double max_width)
{
    vec3 lo, hi;
    bounds_xyz(cp, 0.5 * max_width, &lo, &hi);
    return lo.x <= 0.0 && hi.x >= 0.0 && lo.y <= 0.0 && hi.y >= 0.0 && hi.z >= 0.0 &&
           lo.z <= q->zmax;
}

static vec3 bezier_at(const vec3 cp[4], double u, vec3 *deriv)
{
    vec3 a[3] = {lerp3(u, cp[0], cp[1]), lerp3(u, cp[1], cp[2]), lerp3(u, cp[2], cp[3])};
    vec3 b[2] = {lerp3(u, a[0], a[1]), lerp3(u, a[1], a[2])};
    vec3 db = v3_sub(b[1], b[0]);
    *deriv = v3_length_sq(db) > 0.0 ? v3_scale(db, 3.0) : v3_sub(cp[3], cp[0]);
    return lerp3(u, b[0], b[1]);
}

static void recurse(curve_query *q, const vec3 cp[4], double u0, double u1, int depth)
{
    if (depth > 0) {
        vec3 sp[7] = {cp[0],
                      v3_scale(v3_add(cp[0], cp[1]), 0.5),
                      v3_scale(v3_add(v3_add(cp[0], v3_scale(cp[1], 2.0)), cp[2]), 0.25),
                      v3_scale(v3_add(v3_add(cp[0], v3_scale(cp[1], 3.0)),
                                      v3_add(v3_scale(cp[2], 3.0), cp[3])),
                               0.125),
                      v3_scale(v3_add(v3_add(cp[1], v3_scale(cp[2], 2.0)), cp[3]), 0.25),
                      v3_scale(v3_add(cp[2], cp[3]), 0.5),
                      cp[3]};
        double u[3] = {u0, 0.5 * (u0 + u1), u1};
        for (int h = 0; h < 2; ++h) {
            double mw = fmax(geometry_curve_width(q->s, q->seg, u[h]),
                             geometry_curve_width(q->s, q->seg, u[h + 1]));
            if (ray_meets(q, &sp[3 * h], mw))
                recurse(q, &sp[3 * h], u[h], u[h + 1], depth - 1);
        }
        return;
    }
    /* Between the planes perpendicular to the curve at its two ends. */
    if ((cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x) < 0.0)
        return;
    if ((cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x) < 0.0)
        return;
    double sx = cp[3].x - cp[0].x, sy = cp[3].y - cp[0].y;
    double denom = sx * sx + sy * sy;
    if (denom == 0.0)
        return;
    double w = (-cp[0].x * sx - cp[0].y * sy) / denom;
    double u = fmin(fmax(u0 + w * (u1 - u0), u0), u1);
    double width = geometry_curve_width(q->s, q->seg, u);
    if (q->s->curve == CURVE_RIBBON)
        width *= fabs(v3_dot(geometry_curve_ribbon_normal(q->s, q->seg, u), q->d)) / q->len;
    vec3 deriv;
    vec3 pc = bezier_at(cp, fmin(fmax(w, 0.0), 1.0), &deriv);
    if (pc.x * pc.x + pc.y * pc.y > 0.25 * width * width)
        return;
    if (pc.z < 0.0 || pc.z > q->zmax || pc.z <= q->znear || pc.z >= q->best_z)
        return;
    q->best_z = pc.z;
    q->best_u = u;
}

double geometry_curve_hit(const geom_shape *s, unsigned prim, vec3 o, vec3 d, double tnear,
                          double tfar, double *u_hit)
{
    vec3 cp[4];
    double u0, u1;
    geometry_curve_piece(s, prim, cp, &u0, &u1);
    double len = v3_length(d);
    if (!(len > 0.0))
        return -1.0;
    /* The ray's frame (pbrt-v4's LookAt(o, o + d, up)): z along d, up
     * perpendicular to d and the chord. */
    vec3 z = v3_scale(d, 1.0 / len);
    vec3 up = v3_cross(d, v3_sub(cp[3], cp[0]));
    vec3 x, y;
    if (!(v3_length_sq(up) > 0.0)) {
        v3_basis(z, &x, &y);
    } else {
        x = v3_cross(v3_normalize(up), z);
        if (!(v3_length_sq(x) > 0.0))
            return -1.0;
        x = v3_normalize(x);
        y = v3_cross(z, x);
    }
    vec3 rc[4];
    for (int i = 0; i < 4; ++i) {
        vec3 r = v3_sub(cp[i], o);
        rc[i] = v3(v3_dot(r, x), v3_dot(r, y), v3_dot(r, z));
    }
    size_t seg = prim >> s->curve_split;
    curve_query q = {.s = s, .seg = seg, .d = d, .len = len, .zmax = len * tfar,
                     .znear = len * tnear, .best_z = INFINITY, .best_u = 0.0};
    double mw = fmax(geometry_curve_width(s, seg, u0), geometry_curve_width(s, seg, u1));
    if (!ray_meets(&q, rc, mw))
        return -1.0;
    /* pbrt-v4's refinement depth: the curve's flatness against a twentieth
     * of its width. */
    double l0 = 0.0;
    for (int i = 0; i < 2; ++i)
        l0 = fmax(l0, fmax(fmax(fabs(rc[i].x - 2 * rc[i + 1].x + rc[i + 2].x),
                                fabs(rc[i].y - 2 * rc[i + 1].y + rc[i + 2].y)),
                           fabs(rc[i].z - 2 * rc[i + 1].z + rc[i + 2].z)));
    int depth = 0;
    if (l0 > 0.0) {
        const double *w = &s->curve_w[2 * seg];
        double eps = fmax(w[0], w[1]) * 0.05;
        double r = 1.41421356237 * 6.0 * l0 / (8.0 * eps);
        /* pbrt-v4's Log2Int rounds to the nearest power (in log space) */
        int r0 = (int)floor(log2(r) + 0.5) / 2;
        depth = r0 < 0 ? 0 : r0 > 10 ? 10 : r0;
    }
    recurse(&q, rc, u0, u1, depth);
    if (!(q.best_z < INFINITY))
        return -1.0;
    *u_hit = q.best_u;
    return q.best_z / len;
}

void geometry_curve_bounds(const geom_shape *s, unsigned prim, vec3 *lo, vec3 *hi)
{
    vec3 cp[4];
    double u0, u1;
    geometry_curve_piece(s, prim, cp, &u0, &u1);
    size_t seg = prim >> s->curve_split;
    double w = fmax(geometry_curve_width(s, seg, u0), geometry_curve_width(s, seg, u1));
    bounds_xyz(cp, 0.5 * w, lo, hi);
}
