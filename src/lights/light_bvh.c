#include "lights/light_bvh.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static double safe_sqrt(double x) { return sqrt(fmax(0.0, x)); }
static double safe_acos(double x) { return acos(hz_clamp(x, -1.0, 1.0)); }

/* ---- cones of directions ---- */

typedef struct {
    vec3 w;
    double cos_theta; /* INFINITY: empty */
} cone;

/* v rotated by angle theta about unit axis k (Rodrigues). */
static vec3 rotate(vec3 v, vec3 k, double theta)
{
    double c = cos(theta), s = sin(theta);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(k, v), s)),
                  v3_scale(k, v3_dot(k, v) * (1.0 - c)));
}

/* The smallest cone holding both (pbrt-v4's DirectionCone Union). */
static cone cone_union(cone a, cone b)
{
    if (isinf(a.cos_theta))
        return b;
    if (isinf(b.cos_theta))
        return a;
    double ta = safe_acos(a.cos_theta), tb = safe_acos(b.cos_theta);
    double td = safe_acos(v3_dot(a.w, b.w));
    if (fmin(td + tb, HZ_PI) <= ta)
        return a;
    if (fmin(td + ta, HZ_PI) <= tb)
        return b;
    double to = 0.5 * (ta + td + tb);
    cone whole = {a.w, -1.0};
    if (to >= HZ_PI)
        return whole;
    vec3 k = v3_cross(a.w, b.w);
    if (v3_length_sq(k) == 0.0)
        return whole;
    return (cone){v3_normalize(rotate(a.w, v3_normalize(k), to - ta)), cos(to)};
}

/* ---- bounds ---- */

static light_bounds bounds_union(const light_bounds *a, const light_bounds *b)
{
    if (a->phi == 0.0)
        return *b;
    if (b->phi == 0.0)
        return *a;
    cone c = cone_union((cone){a->w, a->cos_o}, (cone){b->w, b->cos_o});
    return (light_bounds){v3(fmin(a->lo.x, b->lo.x), fmin(a->lo.y, b->lo.y),
                             fmin(a->lo.z, b->lo.z)),
                          v3(fmax(a->hi.x, b->hi.x), fmax(a->hi.y, b->hi.y),
                             fmax(a->hi.z, b->hi.z)),
                          a->phi + b->phi,
                          c.w,
                          c.cos_theta,
                          fmin(a->cos_e, b->cos_e),
                          a->two_sided || b->two_sided};
}

static vec3 centroid(const light_bounds *b) { return v3_scale(v3_add(b->lo, b->hi), 0.5); }

double light_bounds_importance(const light_bounds *b, vec3 p, vec3 n)
{
    vec3 pc = centroid(b);
    vec3 diag = v3_sub(b->hi, b->lo);
    double d2 = fmax(v3_length_sq(v3_sub(p, pc)), 0.5 * v3_length(diag));
    /* cos(a - b) and sin(a - b), clamped at a < b to 1 and 0 */
    vec3 wi = v3_sub(p, pc);
    wi = v3_length_sq(wi) > 0.0 ? v3_normalize(wi) : v3(0.0, 0.0, 1.0);
    double cos_w = v3_dot(b->w, wi);
    if (b->two_sided)
        cos_w = fabs(cos_w);
    double sin_w = safe_sqrt(1.0 - cos_w * cos_w);
    /* the cone of directions from p that the box's bounding sphere subtends */
    double r2 = 0.25 * v3_length_sq(diag), dc2 = v3_length_sq(v3_sub(p, pc));
    double cos_b = dc2 < r2 ? -1.0 : safe_sqrt(1.0 - r2 / dc2);
    double sin_b = safe_sqrt(1.0 - cos_b * cos_b);
    double sin_o = safe_sqrt(1.0 - b->cos_o * b->cos_o);
    double cos_x = cos_w > b->cos_o ? 1.0 : cos_w * b->cos_o + sin_w * sin_o;
    double sin_x = cos_w > b->cos_o ? 0.0 : sin_w * b->cos_o - cos_w * sin_o;
    double cos_p = cos_x > cos_b ? 1.0 : cos_x * cos_b + sin_x * sin_b;
    if (cos_p <= b->cos_e)
        return 0.0;
    double importance = b->phi * cos_p / d2;
    if (v3_length_sq(n) > 0.0) {
        double cos_i = fabs(v3_dot(wi, n));
        double sin_i = safe_sqrt(1.0 - cos_i * cos_i);
        importance *= cos_i > cos_b ? 1.0 : cos_i * cos_b + sin_i * sin_b;
    }
    return fmax(importance, 0.0);
}

static double max_channel(rgb c) { return fmax(c.r, fmax(c.g, c.b)); }

static void grow(light_bounds *b, vec3 p)
{
    b->lo = v3(fmin(b->lo.x, p.x), fmin(b->lo.y, p.y), fmin(b->lo.z, p.z));
    b->hi = v3(fmax(b->hi.x, p.x), fmax(b->hi.y, p.y), fmax(b->hi.z, p.z));
}

/* pbrt-v4's Light::Bounds in RGB terms; false for unbounded lights. */
static bool bounds_of(const light *l, light_bounds *out)
{
    light_bounds b = {v3(INFINITY, INFINITY, INFINITY), v3(-INFINITY, -INFINITY, -INFINITY),
                      0.0, v3(0.0, 0.0, 1.0), -1.0, 0.0, false};
    switch (l->kind) {
    case LIGHT_POINT:
        grow(&b, l->point.p);
        b.phi = l->point.image ? max_channel(light_phi(l, 0.0))
                               : 4.0 * HZ_PI * max_channel(l->emit);
        break;
    case LIGHT_SPOT: {
        grow(&b, l->spot.p);
        transform render_from_light = transform_inverse(l->spot.light_from_render);
        b.w = v3_normalize(transform_vector(&render_from_light, v3(0.0, 0.0, 1.0)));
        b.phi = 4.0 * HZ_PI * max_channel(l->emit);
        double cs = l->spot.cos_falloff_start, ce = l->spot.cos_falloff_end;
        b.cos_o = cs;
        b.cos_e = cos(safe_acos(ce) - safe_acos(cs));
        if (b.cos_e == 1.0 && ce != cs)
            b.cos_e = 0.999; /* pbrt-v4's slop for rounding in the importance */
        break;
    }
    case LIGHT_AREA: {
        const geom_shape *s = l->area.shape;
        if (s->motion)
            return false;
        b.two_sided = l->area.two_sided;
        if (s->kind == GEOMETRY_SPHERE) {
            vec3 lo, hi;
            transform_box(&s->space_from_object, v3(-s->radius, -s->radius, -s->radius),
                          v3(s->radius, s->radius, s->radius), &lo, &hi);
            grow(&b, lo);
            grow(&b, hi);
            /* π A L (light_phi doubles it for two-sided lights; the
             * bounds do not, as pbrt-v4's) */
            b.phi = max_channel(light_phi(l, 0.0)) / (b.two_sided ? 2.0 : 1.0);
            break; /* normals: the whole sphere */
        }
        cone c = {v3(0.0, 0.0, 1.0), INFINITY};
        for (size_t t = 0; t < s->triangle_count; ++t) {
            geom_hit h;
            geometry_triangle_point(s, (unsigned)t, 1.0 / 3.0, 1.0 / 3.0, &h);
            for (int k = 0; k < 3; ++k) {
                uint32_t v = s->indices[3 * t + (size_t)k];
                grow(&b, v3(s->p[3 * v], s->p[3 * v + 1], s->p[3 * v + 2]));
            }
            if (v3_length_sq(h.ng) > 0.0)
                c = cone_union(c, (cone){h.ng, 1.0});
        }
        if (isinf(c.cos_theta))
            return false;
        b.w = c.w;
        b.cos_o = c.cos_theta;
        b.phi = HZ_PI * l->area.area * max_channel(l->emit);
        break;
    }
    case LIGHT_DISTANT:
    case LIGHT_INFINITE:
        return false;
    }
    *out = b;
    return true;
}

/* ---- build ---- */

typedef struct {
    size_t light;
    light_bounds b;
} item;

/* pbrt-v4's EvaluateCost: power x solid angle of emission x box area, with
 * a penalty for splitting along a short axis. */
static double split_cost(const light_bounds *b, vec3 lo, vec3 hi, int dim)
{
    if (b->phi == 0.0)
        return 0.0;
    double to = safe_acos(b->cos_o), te = safe_acos(b->cos_e);
    double tw = fmin(to + te, HZ_PI), so = safe_sqrt(1.0 - b->cos_o * b->cos_o);
    double m = 2.0 * HZ_PI * (1.0 - b->cos_o) +
               HZ_PI / 2.0 * (2.0 * tw * so - cos(to - 2.0 * tw) - 2.0 * to * so + b->cos_o);
    vec3 d = v3_sub(hi, lo), bd = v3_sub(b->hi, b->lo);
    double dd[3] = {d.x, d.y, d.z};
    double kr = fmax(d.x, fmax(d.y, d.z)) / dd[dim];
    double area = 2.0 * (bd.x * bd.y + bd.y * bd.z + bd.z * bd.x);
    return b->phi * m * kr * area;
}

static double axis(vec3 v, int d) { return d == 0 ? v.x : d == 1 ? v.y : v.z; }

enum { BUCKETS = 12 };

static int bucket_of(const light_bounds *b, vec3 clo, vec3 chi, int dim)
{
    double lo = axis(clo, dim), hi = axis(chi, dim);
    int k = (int)(BUCKETS * (axis(centroid(b), dim) - lo) / (hi - lo));
    return k < 0 ? 0 : k >= BUCKETS ? BUCKETS - 1 : k;
}

/* A light's trail (light_bvh.trail) has one bit per level: a leaf may lie at
 * most this deep, so an interior node at most one level higher, where
 * 1 << depth is still defined. */
enum { TRAIL_BITS = 64 };

/* Whether `count` items fit below a node at `depth`: a balanced split of
 * them keeps every leaf within TRAIL_BITS levels. */
static bool fits(size_t count, int depth)
{
    int levels = TRAIL_BITS - depth;
    return levels >= (int)(sizeof(size_t) * CHAR_BIT) || count <= (size_t)1 << levels;
}

/* Builds items [start, end) at depth; returns the node's index and bounds.
 * The items fit (fits(end - start, depth)), and so does each side of the
 * split: where the bucketed split would leave too many items on a side (a
 * chain that peels one light per level, at geometrically spaced positions)
 * the midpoint split is taken, which halves them. */
static size_t build(light_bvh *t, item *it, size_t start, size_t end, uint64_t trail, int depth,
                    light_bounds *out)
{
    size_t node = t->node_count++;
    if (end - start == 1) {
        t->nodes[node] = (light_bvh_node){it[start].b, it[start].light, true};
        t->trail[it[start].light] = trail;
        *out = it[start].b;
        return node;
    }
    light_bounds all = it[start].b;
    vec3 clo = centroid(&all), chi = clo;
    for (size_t i = start; i < end; ++i) {
        all = bounds_union(&all, &it[i].b);
        vec3 c = centroid(&it[i].b);
        clo = v3(fmin(clo.x, c.x), fmin(clo.y, c.y), fmin(clo.z, c.z));
        chi = v3(fmax(chi.x, c.x), fmax(chi.y, c.y), fmax(chi.z, c.z));
    }
    double best = INFINITY;
    int best_dim = -1, best_bucket = -1;
    for (int dim = 0; dim < 3; ++dim) {
        if (axis(chi, dim) == axis(clo, dim) || axis(v3_sub(all.hi, all.lo), dim) == 0.0)
            continue;
        light_bounds bk[BUCKETS];
        memset(bk, 0, sizeof bk);
        for (size_t i = start; i < end; ++i) {
            int k = bucket_of(&it[i].b, clo, chi, dim);
            bk[k] = bounds_union(&bk[k], &it[i].b);
        }
        for (int s = 1; s < BUCKETS - 1; ++s) {
            light_bounds b0 = {0}, b1 = {0};
            for (int j = 0; j <= s; ++j)
                b0 = bounds_union(&b0, &bk[j]);
            for (int j = s + 1; j < BUCKETS; ++j)
                b1 = bounds_union(&b1, &bk[j]);
            double cost = split_cost(&b0, all.lo, all.hi, dim) +
                          split_cost(&b1, all.lo, all.hi, dim);
            if (cost > 0.0 && cost < best) {
                best = cost;
                best_dim = dim;
                best_bucket = s;
            }
        }
    }
    size_t mid = start;
    if (best_dim >= 0) {
        for (size_t i = start; i < end; ++i)
            if (bucket_of(&it[i].b, clo, chi, best_dim) <= best_bucket) {
                item tmp = it[i];
                it[i] = it[mid];
                it[mid++] = tmp;
            }
    }
    if (mid == start || mid == end || !fits(mid - start, depth + 1) || !fits(end - mid, depth + 1))
        mid = start + (end - start) / 2;
    light_bounds b0, b1;
    build(t, it, start, mid, trail, depth + 1, &b0);
    size_t second = build(t, it, mid, end, trail | (1ull << depth), depth + 1, &b1);
    *out = bounds_union(&b0, &b1);
    t->nodes[node] = (light_bvh_node){*out, second, false};
    return node;
}

hz_status light_bvh_build(const light *lights, size_t light_count, light_bvh *out,
                          hz_error *err)
{
    memset(out, 0, sizeof *out);
    size_t n = light_count ? light_count : 1;
    item *it = malloc(n * sizeof *it);
    out->nodes = malloc(2 * n * sizeof *out->nodes);
    out->unbounded = malloc(n * sizeof *out->unbounded);
    out->trail = calloc(n, sizeof *out->trail);
    out->where = calloc(n, sizeof *out->where);
    if (!it || !out->nodes || !out->unbounded || !out->trail || !out->where) {
        free(it);
        light_bvh_free(out);
        return hz_fail(err, "out of memory");
    }
    size_t m = 0;
    for (size_t i = 0; i < light_count; ++i) {
        if (lights[i].kind == LIGHT_INFINITE && !light_is_image(&lights[i]))
            continue; /* a constant sky is reached by escaping paths only */
        light_bounds b;
        if (!bounds_of(&lights[i], &b)) {
            out->unbounded[out->unbounded_count++] = i;
            out->where[i] = 1;
        } else if (b.phi > 0.0 && isfinite(b.phi)) {
            it[m++] = (item){i, b};
            out->where[i] = 2;
        }
    }
    if (m > 0) {
        light_bounds root;
        build(out, it, 0, m, 0, 0, &root);
    }
    free(it);
    return HZ_OK;
}

void light_bvh_free(light_bvh *b)
{
    free(b->nodes);
    free(b->unbounded);
    free(b->trail);
    free(b->where);
    memset(b, 0, sizeof *b);
}

static double p_unbounded(const light_bvh *b)
{
    double nu = (double)b->unbounded_count;
    return nu / (nu + (b->node_count > 0 ? 1.0 : 0.0));
}

bool light_bvh_sample(const light_bvh *b, vec3 p, vec3 n, double u, size_t *light, double *pmf)
{
    double pu = p_unbounded(b);
    if (u < pu) {
        u /= pu;
        size_t k = (size_t)(u * (double)b->unbounded_count);
        if (k >= b->unbounded_count)
            k = b->unbounded_count - 1;
        *light = b->unbounded[k];
        *pmf = pu / (double)b->unbounded_count;
        return true;
    }
    if (b->node_count == 0)
        return false;
    u = fmin((u - pu) / (1.0 - pu), 0x1.fffffffffffffp-1);
    double prob = 1.0 - pu;
    size_t i = 0;
    for (;;) {
        const light_bvh_node *nd = &b->nodes[i];
        if (nd->leaf) {
            if (i > 0 || light_bounds_importance(&nd->b, p, n) > 0.0) {
                *light = nd->index;
                *pmf = prob;
                return prob > 0.0;
            }
            return false;
        }
        double c0 = light_bounds_importance(&b->nodes[i + 1].b, p, n);
        double c1 = light_bounds_importance(&b->nodes[nd->index].b, p, n);
        if (!(c0 + c1 > 0.0))
            return false;
        double p0 = c0 / (c0 + c1);
        if (u < p0) {
            u = fmin(u / p0, 0x1.fffffffffffffp-1);
            prob *= p0;
            i = i + 1;
        } else {
            u = fmin((u - p0) / (1.0 - p0), 0x1.fffffffffffffp-1);
            prob *= 1.0 - p0;
            i = nd->index;
        }
    }
}

double light_bvh_pmf(const light_bvh *b, vec3 p, vec3 n, size_t light)
{
    double pu = p_unbounded(b);
    switch (b->where[light]) {
    case 1:
        return pu / (double)b->unbounded_count;
    case 2:
        break;
    default:
        return 0.0;
    }
    uint64_t trail = b->trail[light];
    double prob = 1.0 - pu;
    size_t i = 0;
    for (;;) {
        const light_bvh_node *nd = &b->nodes[i];
        if (nd->leaf)
            return nd->index == light && (i > 0 || light_bounds_importance(&nd->b, p, n) > 0.0)
                       ? prob
                       : 0.0;
        double c0 = light_bounds_importance(&b->nodes[i + 1].b, p, n);
        double c1 = light_bounds_importance(&b->nodes[nd->index].b, p, n);
        if (!(c0 + c1 > 0.0))
            return 0.0;
        bool second = trail & 1u;
        prob *= (second ? c1 : c0) / (c0 + c1);
        i = second ? nd->index : i + 1;
        trail >>= 1;
    }
}
