#define _POSIX_C_SOURCE 200809L
#include "integrator/shadow_cache.h"

#include <math.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/parallel.h"
#include "core/ray.h"
#include "integrator/walk.h"

/* A light-space grid: node (i, j, k) lies at origin + h (i ex + j ey + k ez),
 * ez toward the light; 4 floats a node (optical depth R, G, B above it, and
 * 1 where no surface lies above it, else 0), k the fastest index so that a
 * column is contiguous. */
struct shadow_cache {
    vec3 origin, ex, ey, ez;
    double h, inv_h; /* node spacing */
    int n[3];
    float *nodes;
    /* Columns are built when a lookup first needs them (lazy), so a render
     * pays for the columns its in-scattering samples reach: a pilot of a
     * few hundred pixels builds a few, a sparse volume's empty columns are
     * never walked. state: COLUMN_EMPTY, _BUILDING (one thread walks it, the
     * others wait), _BUILT. The walk's inputs are the render's. */
    const integrator_inputs *in;
    int medium;
    atomic_uchar *state; /* NULL: built whole at creation */
};

enum { COLUMN_EMPTY, COLUMN_BUILDING, COLUMN_BUILT };

/* A column's node count up to which its walk's scratch lives on the stack
 * (3 doubles a node); a cache with longer columns is built whole when made. */
#define SHADOW_CACHE_LAZY_MAX_NZ 4096

struct shadow_caches {
    size_t medium_count, light_count;
    shadow_cache **pairs; /* [medium * light_count + light] */
};

/* Optical depths above this are stored as it (an infinite one would make
 * 0 * inf in the interpolation); e^-1e30 is 0. */
#define SHADOW_CACHE_TAU_MAX 1e30

/* ---- building ---- */

typedef struct {
    const integrator_inputs *in;
    const shadow_cache *c;
    int medium; /* the cached medium: the columns start in it */
    atomic_int next_column;
} build_job;

/* One column's walk: the optical depth from its start to t, and where it
 * records it at the nodes. */
typedef struct {
    const build_job *job;
    double h;
    int nz, next; /* nodes; the next to record, at t = (next + 1) h */
    double tau[3];
    double *cum; /* tau at each node, 3 a node */
} column_walk;

/* The density integral of a grid segment, fed piece by piece in order:
 * only cells of the majorant grid that are not empty cost lookups. */
typedef struct {
    medium_ray r;
    double ca, cb; /* where the density can be non-zero */
    majorant_segment seg;
    bool more; /* seg is a cell not yet passed */
} grid_pieces;

/* Midpoints no more than h apart over [a, b]. */
static double march(grid_pieces *g, double a, double b, double h)
{
    double n = ceil((b - a) / h);
    if (n > 1e6)
        n = 1e6;
    double dt = (b - a) / n, sum = 0.0;
    uint64_t lookups = 0;
    for (int s = 0; s < (int)n; ++s)
        sum += medium_ray_density(&g->r, a + (s + 0.5) * dt, &lookups);
    return sum * dt;
}

/* The integral over [p, q], p at or past every earlier piece's end. */
static double grid_piece(grid_pieces *g, double p, double q, double h)
{
    double lo = fmax(p, g->ca), hi = fmin(q, g->cb), integral = 0.0;
    while (g->more && lo < hi) {
        double a = fmax(lo, g->seg.t0), b = fmin(hi, g->seg.t1);
        if (b > a && g->seg.max > 0.0)
            integral += march(g, a, b, h);
        if (g->seg.t1 > hi)
            break;
        uint64_t steps = 0;
        g->more = medium_ray_next(&g->r, &g->seg, &steps);
    }
    return integral;
}

static void add_tau(column_walk *cw, const medium *m, double integral)
{
    rgb st = medium_sigma_t(m);
    cw->tau[0] += st.r * integral;
    cw->tau[1] += st.g * integral;
    cw->tau[2] += st.b * integral;
}

/* The segment [a, b] of the column ray o + t w in medium mi (-1: none):
 * its optical depth, cut at every node it passes, where tau is recorded. */
static void accumulate(column_walk *cw, int mi, vec3 o, vec3 w, double a, double b)
{
    const medium *m = mi >= 0 ? &cw->job->in->media[mi] : NULL;
    grid_pieces g;
    g.ca = a;
    g.cb = b;
    bool grid = m && medium_is_density_grid(m) &&
                medium_ray_start(m, o, w, 0.0, &g.ca, &g.cb, &g.r);
    if (grid) {
        /* Marching at the node spacing, a piece of a brick or more needs
         * only whether it holds density. */
        medium_ray_coarsen(&g.r, cw->h * g.r.voxels_per_t);
        uint64_t steps = 0;
        g.more = medium_ray_next(&g.r, &g.seg, &steps);
    }
    bool homogeneous = m && medium_is_homogeneous(m);
    for (double p = a;;) {
        double tk = cw->next < cw->nz ? (cw->next + 1) * cw->h : INFINITY;
        double q = fmin(tk, b);
        if (q > p && (grid || homogeneous))
            add_tau(cw, m, homogeneous ? q - p : grid_piece(&g, p, q, cw->h));
        p = fmax(p, q);
        if (cw->next >= cw->nz || !(tk <= b))
            return;
        memcpy(cw->cum + 3 * cw->next, cw->tau, sizeof cw->tau);
        cw->next++;
    }
}

static void build_column(const build_job *job, size_t column, double *cum)
{
    const shadow_cache *c = job->c;
    int i = column / c->n[1], j = column % c->n[1];
    column_walk cw = {.job = job, .h = c->h, .nz = c->n[2], .cum = cum};
    /* From one spacing below node (i, j, 0) toward the light: node k at
     * t = (k + 1) h. */
    vec3 w = c->ez;
    vec3 o = v3_add(c->origin, v3_add(v3_scale(c->ex, i * c->h),
                                      v3_sub(v3_scale(c->ey, j * c->h), v3_scale(w, c->h))));
    double t_block = -INFINITY;
    /* Opaque surfaces are crossed as interfaces: the column's optical depth
     * goes on past them, they only mark where the light is blocked. */
    ray_walk rw;
    walk_start(&rw, job->in->geom, o, w, 0.0, 0.0, INFINITY, 0.0, job->medium, WALK_EXACT_ENDS);
    for (walk_segment seg; walk_next(&rw, &seg);) {
        int medium = seg.medium;
        double t_start = seg.t0, t_end = seg.t1;
        accumulate(&cw, medium, o, w, t_start, t_end);
        if (seg.opaque)
            t_block = fmax(t_block, t_end);
    }
    if (walk_lost(&rw)) /* as a shadow ray: lost, black */
        t_block = INFINITY;
    accumulate(&cw, -1, o, w, INFINITY, INFINITY); /* nodes a lost walk did not reach */
    float *node = c->nodes + column * (size_t)c->n[2] * 4;
    for (int k = 0; k < c->n[2]; ++k, node += 4) {
        for (int ch = 0; ch < 3; ++ch) {
            double tau = cw.tau[ch] - cum[3 * k + ch];
            node[ch] = (float)(tau > SHADOW_CACHE_TAU_MAX ? SHADOW_CACHE_TAU_MAX
                               : tau > 0.0              ? tau
                                                        : 0.0);
        }
        node[3] = (k + 1) * c->h < t_block ? 0.0f : 1.0f;
    }
}

static void *build_worker(void *arg)
{
    build_job *job = arg;
    double *cum = malloc((size_t)job->c->n[2] * 3 * sizeof *cum);
    if (cum) {
        int columns = job->c->n[0] * job->c->n[1];
        for (int col; (col = atomic_fetch_add(&job->next_column, 1)) < columns;)
            build_column(job, (size_t)col, cum);
    }
    bool failed = !cum; /* the others build every column; the cache fails */
    free(cum);
    return failed ? (void *)1 : NULL;
}

static void cache_destroy(shadow_cache *c)
{
    if (c) {
        free(c->nodes);
        free(c->state);
    }
    free(c);
}

/* Column `col` of a lazy cache, built by the first lookup that needs it;
 * the same nodes whichever thread builds it. */
static void ensure_column(const shadow_cache *c, size_t col)
{
    atomic_uchar *s = &c->state[col];
    if (atomic_load_explicit(s, memory_order_acquire) == COLUMN_BUILT)
        return;
    unsigned char expect = COLUMN_EMPTY;
    if (atomic_compare_exchange_strong_explicit(s, &expect, COLUMN_BUILDING,
                                                memory_order_acquire, memory_order_acquire)) {
        double cum[3 * SHADOW_CACHE_LAZY_MAX_NZ];
        build_job job = {.in = c->in, .c = c, .medium = c->medium};
        build_column(&job, col, cum);
        atomic_store_explicit(s, COLUMN_BUILT, memory_order_release);
        return;
    }
    while (atomic_load_explicit(s, memory_order_acquire) != COLUMN_BUILT)
        sched_yield();
}

/* The cache of grid medium mi and distant light li, NULL with *err unset
 * when the medium has no bounded support (an empty grid, a non-zero
 * background). */
static hz_status cache_create(const integrator_inputs *in, int mi, size_t li, double spacing,
                              int threads, FILE *warn, shadow_cache **out, hz_error *err)
{
    *out = NULL;
    const medium *m = &in->media[mi];
    vec3 corners[8];
    double voxel;
    if (!medium_support(m, corners, &voxel))
        return HZ_OK;
    shadow_cache *c = calloc(1, sizeof *c);
    if (!c)
        return hz_fail(err, "shadow cache: out of memory");
    c->ez = in->lights[li].distant.w;
    v3_basis(c->ez, &c->ex, &c->ey);
    /* The support box's corners in the light's frame. */
    double bmin[3] = {INFINITY, INFINITY, INFINITY}, bmax[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < 8; ++k) {
        vec3 q = corners[k];
        double x[3] = {v3_dot(q, c->ex), v3_dot(q, c->ey), v3_dot(q, c->ez)};
        for (int a = 0; a < 3; ++a) {
            bmin[a] = fmin(bmin[a], x[a]);
            bmax[a] = fmax(bmax[a], x[a]);
        }
    }
    double h = spacing * voxel, nodes = 0.0;
    for (int tries = 0; tries < 64; ++tries) {
        nodes = 1.0;
        for (int a = 0; a < 3; ++a)
            nodes *= floor((bmax[a] - bmin[a]) / h) + 2.0;
        if (nodes <= SHADOW_CACHE_MAX_NODES)
            break;
        h *= 1.01 * cbrt(nodes / SHADOW_CACHE_MAX_NODES);
    }
    if (!(nodes <= SHADOW_CACHE_MAX_NODES) || !(h > 0.0) || !isfinite(h)) {
        cache_destroy(c);
        return hz_fail(err, "shadow cache of medium \"%s\": its support cannot be covered",
                       m->name ? m->name : "");
    }
    if (warn && h > spacing * voxel * 1.000001)
        fprintf(warn,
                "haze: warning: the shadow cache of medium \"%s\" would need more than %u "
                "nodes at %g voxels: built at %.3g voxels\n",
                m->name ? m->name : "", SHADOW_CACHE_MAX_NODES, spacing, h / voxel);
    c->h = h;
    c->inv_h = 1.0 / h;
    for (int a = 0; a < 3; ++a)
        c->n[a] = (int)(floor((bmax[a] - bmin[a]) / h) + 2.0);
    c->origin = v3_add(v3_add(v3_scale(c->ex, bmin[0]), v3_scale(c->ey, bmin[1])),
                       v3_scale(c->ez, bmin[2]));
    size_t count = (size_t)c->n[0] * (size_t)c->n[1] * (size_t)c->n[2];
    size_t columns = (size_t)c->n[0] * (size_t)c->n[1];
    c->nodes = malloc(count * 4 * sizeof *c->nodes);
    bool lazy = c->n[2] <= SHADOW_CACHE_LAZY_MAX_NZ;
    if (lazy)
        c->state = calloc(columns, sizeof *c->state); /* COLUMN_EMPTY */
    if (!c->nodes || (lazy && !c->state)) {
        cache_destroy(c);
        return hz_fail(err, "shadow cache of medium \"%s\": out of memory for %zu nodes",
                       m->name ? m->name : "", count);
    }
    c->in = in;
    c->medium = mi;
    if (lazy) {
        *out = c;
        return HZ_OK;
    }
    build_job job = {.in = in, .c = c, .medium = mi};
    atomic_init(&job.next_column, 0);
    bool failed = !hz_parallel_run(threads, build_worker, &job);
    if (failed) {
        cache_destroy(c);
        return hz_fail(err, "shadow cache of medium \"%s\": out of memory", m->name ? m->name : "");
    }
    *out = c;
    return HZ_OK;
}

hz_status shadow_caches_create(const integrator_inputs *in, double spacing, int threads,
                               FILE *warn, shadow_caches **out, hz_error *err)
{
    *out = NULL;
    shadow_caches *cs = calloc(1, sizeof *cs);
    size_t pairs = in->medium_count * in->light_count;
    if (!cs || (pairs && !(cs->pairs = calloc(pairs, sizeof *cs->pairs)))) {
        free(cs);
        return hz_fail(err, "shadow cache: out of memory");
    }
    cs->medium_count = in->medium_count;
    cs->light_count = in->light_count;
    for (size_t mi = 0; mi < in->medium_count; ++mi) {
        if (!medium_is_density_grid(&in->media[mi]))
            continue;
        for (size_t li = 0; li < in->light_count; ++li) {
            if (in->lights[li].kind != LIGHT_DISTANT)
                continue;
            if (cache_create(in, (int)mi, li, spacing, threads, warn,
                             &cs->pairs[mi * in->light_count + li], err) != HZ_OK) {
                shadow_caches_destroy(cs);
                return HZ_ERROR;
            }
        }
    }
    *out = cs;
    return HZ_OK;
}

void shadow_caches_destroy(shadow_caches *cs)
{
    if (!cs)
        return;
    for (size_t k = 0; k < cs->medium_count * cs->light_count; ++k)
        cache_destroy(cs->pairs[k]);
    free(cs->pairs);
    free(cs);
}

const shadow_cache *shadow_caches_get(const shadow_caches *cs, int medium, size_t light)
{
    if (!cs || medium < 0 || (size_t)medium >= cs->medium_count || light >= cs->light_count)
        return NULL;
    return cs->pairs[(size_t)medium * cs->light_count + light];
}

size_t shadow_caches_bytes(const shadow_caches *cs)
{
    size_t bytes = 0;
    for (size_t k = 0; cs && k < cs->medium_count * cs->light_count; ++k)
        if (cs->pairs[k])
            bytes += (size_t)cs->pairs[k]->n[0] * (size_t)cs->pairs[k]->n[1] *
                     (size_t)cs->pairs[k]->n[2] * 4 * sizeof(float);
    return bytes;
}

/* ---- lookups ---- */

/* Four floats as one SIMD register (GCC's and clang's vector extension, on
 * every target they build for): a node's three depths and visibility. */
typedef float v4f __attribute__((vector_size(16)));

/* Catmull-Rom weights of the four samples around fraction t. */
static inline void catmull_rom(double t, double w[4])
{
    double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
    w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
}

rgb shadow_cache_transmittance(const shadow_cache *c, vec3 p, const spectral_ctx *sp)
{
    vec3 d = v3_sub(p, c->origin);
    double x[3] = {v3_dot(d, c->ex) * c->inv_h, v3_dot(d, c->ey) * c->inv_h,
                   v3_dot(d, c->ez) * c->inv_h};
    int i[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        double top = c->n[a] - 1;
        double v = x[a] > 0.0 ? (x[a] < top ? x[a] : top) : 0.0; /* also NaN: 0 */
        i[a] = (int)v;
        if (i[a] > c->n[a] - 2)
            i[a] = c->n[a] - 2; /* n >= 2 on every axis */
        f[a] = v - i[a];
    }
    /* Across the light: Catmull-Rom over 4 x 4 columns (the optical depth's
     * curvature across columns is the cache's main error: 23x lower relMSE
     * than bilinear at one voxel on the thick peer smoke); along it: linear. */
    double wx[4], wy[4];
    catmull_rom(f[0], wx);
    catmull_rom(f[1], wy);
    /* The 4 x 4 columns' nodes at i[2], clamped to the grid; weights in
     * float, the nodes' precision (a depth's rounding, ~1e-7 of it, is far
     * below the cache's interpolation error): one 4-wide multiply-add per
     * node pair. */
    size_t col_stride = (size_t)c->n[2] * 4, ox[4], oy[4];
    for (int a = 0; a < 4; ++a) {
        int ix = i[0] - 1 + a, iy = i[1] - 1 + a;
        ix = ix < 0 ? 0 : ix >= c->n[0] ? c->n[0] - 1 : ix;
        iy = iy < 0 ? 0 : iy >= c->n[1] ? c->n[1] - 1 : iy;
        ox[a] = (size_t)ix * (size_t)c->n[1] * col_stride;
        oy[a] = (size_t)iy * col_stride;
    }
    if (c->state)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                ensure_column(c, (ox[a] + oy[b]) / col_stride);
    const float *base = c->nodes + (size_t)i[2] * 4;
    /* Separable: across y within each of the 4 x-columns, then across x. */
    float fx[4], fy0[4], fy1[4];
    for (int a = 0; a < 4; ++a) {
        fx[a] = (float)wx[a];
        fy0[a] = (float)(wy[a] * (1.0 - f[2]));
        fy1[a] = (float)(wy[a] * f[2]);
    }
    v4f sum = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int a = 0; a < 4; ++a) {
        v4f col = {0.0f, 0.0f, 0.0f, 0.0f};
        for (int b = 0; b < 4; ++b) {
            const float *n = base + ox[a] + oy[b];
            v4f lo, hi;
            memcpy(&lo, n, sizeof lo);
            memcpy(&hi, n + 4, sizeof hi);
            col += fy0[b] * lo + fy1[b] * hi;
        }
        sum += fx[a] * col;
    }
    float acc[4];
    memcpy(acc, &sum, sizeof acc);
    /* The cubic can overshoot: depths stay >= 0, visibility in [0, 1]. */
    double V = acc[3] < 1.0f ? acc[3] : 1.0;
    if (!(V > 0.0))
        return rgb_grey(0.0);
    rgb depth = rgb_make(acc[0] > 0.0f ? acc[0] : 0.0, acc[1] > 0.0f ? acc[1] : 0.0,
                         acc[2] > 0.0f ? acc[2] : 0.0);
    if (sp) /* the optical depth is linear in sigma: its unbounded spectrum */
        depth = spectral_from_rgb(sp, depth, SPECTRAL_UNBOUNDED);
    return rgb_scale(rgb_exp_neg(depth, 1.0), V);
}

double shadow_cache_spacing_param(param_list *pl, double dflt)
{
    double s = params_float(pl, "shadowcache", dflt);
    if (!(s >= 0.0 && isfinite(s)))
        params_reject(pl, "shadowcache",
                      "\"shadowcache\" must be a number of voxels >= 0 (0: no cache)");
    return s;
}
