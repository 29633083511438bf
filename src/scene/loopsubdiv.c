#include "scene/loopsubdiv.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* One edge of a triangle: its ends (lo < hi), the triangle and the corner
 * opposite it. */
typedef struct {
    uint32_t lo, hi, face, opposite;
} half_edge;

static int cmp_edge(const void *pa, const void *pb)
{
    const half_edge *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return a->face < b->face ? -1 : a->face > b->face;
}

/* A mesh's edges, sorted and grouped: edge k is half-edges [first[k],
 * first[k + 1]) (one on a boundary, two inside). */
typedef struct {
    half_edge *he;
    size_t *first;
    size_t count;
} edge_set;

static void edge_set_free(edge_set *e)
{
    free(e->he);
    free(e->first);
}

static hz_status edges_of(const uint32_t *idx, size_t nt, edge_set *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    out->he = malloc(3 * nt * sizeof *out->he);
    out->first = malloc((3 * nt + 1) * sizeof *out->first);
    if (!out->he || !out->first) {
        edge_set_free(out);
        return hz_fail(err, "loopsubdiv: out of memory");
    }
    for (size_t f = 0; f < nt; ++f)
        for (int k = 0; k < 3; ++k) {
            uint32_t a = idx[3 * f + k], b = idx[3 * f + (k + 1) % 3], c = idx[3 * f + (k + 2) % 3];
            out->he[3 * f + k] = (half_edge){a < b ? a : b, a < b ? b : a, (uint32_t)f, c};
        }
    qsort(out->he, 3 * nt, sizeof *out->he, cmp_edge);
    for (size_t i = 0; i < 3 * nt;) {
        size_t j = i + 1;
        while (j < 3 * nt && out->he[j].lo == out->he[i].lo && out->he[j].hi == out->he[i].hi)
            ++j;
        if (j - i > 2) {
            edge_set_free(out);
            return hz_fail(err, "loopsubdiv: an edge is shared by %zu triangles (Loop subdivision "
                                "needs a manifold mesh)",
                           j - i);
        }
        out->first[out->count++] = i;
        i = j;
    }
    out->first[out->count] = 3 * nt;
    return HZ_OK;
}

/* Per vertex: neighbour count, the sum of the neighbours, and on a boundary
 * the sum of its (two) boundary neighbours. */
typedef struct {
    int valence, boundary_neighbours;
    double sum[3], boundary_sum[3];
} ring;

static void rings_of(const double *p, size_t nv, const edge_set *e, ring *r)
{
    memset(r, 0, nv * sizeof *r);
    for (size_t k = 0; k < e->count; ++k) {
        const half_edge *h = &e->he[e->first[k]];
        bool boundary = e->first[k + 1] - e->first[k] == 1;
        uint32_t ends[2] = {h->lo, h->hi};
        for (int s = 0; s < 2; ++s) {
            ring *v = &r[ends[s]];
            const double *q = &p[3 * (size_t)ends[1 - s]];
            v->valence++;
            for (int c = 0; c < 3; ++c)
                v->sum[c] += q[c];
            if (boundary) {
                v->boundary_neighbours++;
                for (int c = 0; c < 3; ++c)
                    v->boundary_sum[c] += q[c];
            }
        }
    }
}

static double beta_of(int valence) { return valence == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * valence); }

/* The vertex moved by its one-ring with weight beta (interior) or by its two
 * boundary neighbours with weight bb (boundary). */
static void reposition(const double *v, const ring *r, double bb, bool limit, double *out)
{
    if (r->boundary_neighbours > 0) {
        /* A corner with other than two boundary neighbours stays put. */
        if (r->boundary_neighbours != 2) {
            memcpy(out, v, 3 * sizeof *out);
            return;
        }
        for (int c = 0; c < 3; ++c)
            out[c] = (1.0 - 2.0 * bb) * v[c] + bb * r->boundary_sum[c];
        return;
    }
    double beta = beta_of(r->valence);
    double w = limit ? 1.0 / (r->valence + 3.0 / (8.0 * beta)) : beta;
    for (int c = 0; c < 3; ++c)
        out[c] = (1.0 - r->valence * w) * v[c] + w * r->sum[c];
}

static hz_status one_level(double **p, size_t *nv, uint32_t **idx, size_t *nt, hz_error *err)
{
    edge_set e;
    if (edges_of(*idx, *nt, &e, err) != HZ_OK)
        return HZ_ERROR;
    size_t nv2 = *nv + e.count, nt2 = 4 * *nt;
    ring *r = malloc((*nv ? *nv : 1) * sizeof *r);
    double *p2 = malloc(3 * nv2 * sizeof *p2);
    uint32_t *idx2 = malloc(3 * nt2 * sizeof *idx2);
    uint32_t *edge_vertex = malloc(3 * *nt * sizeof *edge_vertex); /* per half-edge slot */
    if (!r || !p2 || !idx2 || !edge_vertex || nv2 > UINT32_MAX) {
        free(r), free(p2), free(idx2), free(edge_vertex);
        edge_set_free(&e);
        return hz_fail(err, "loopsubdiv: out of memory (or over 2^32 vertices)");
    }
    rings_of(*p, *nv, &e, r);
    for (size_t v = 0; v < *nv; ++v)
        reposition(&(*p)[3 * v], &r[v], 1.0 / 8.0, false, &p2[3 * v]);
    for (size_t k = 0; k < e.count; ++k) {
        const half_edge *h = &e.he[e.first[k]];
        size_t n = e.first[k + 1] - e.first[k];
        double *q = &p2[3 * (*nv + k)];
        const double *a = &(*p)[3 * (size_t)h->lo], *b = &(*p)[3 * (size_t)h->hi];
        for (int c = 0; c < 3; ++c)
            q[c] = n == 1 ? 0.5 * (a[c] + b[c])
                          : 3.0 / 8.0 * (a[c] + b[c]) +
                                1.0 / 8.0 * ((*p)[3 * (size_t)h[0].opposite + c] +
                                             (*p)[3 * (size_t)h[1].opposite + c]);
        /* Tell each triangle which new vertex sits on this edge. */
        for (size_t i = 0; i < n; ++i) {
            uint32_t f = h[i].face;
            for (int s = 0; s < 3; ++s) {
                uint32_t x = (*idx)[3 * f + s], y = (*idx)[3 * f + (s + 1) % 3];
                if ((x == h->lo && y == h->hi) || (x == h->hi && y == h->lo))
                    edge_vertex[3 * f + s] = (uint32_t)(*nv + k);
            }
        }
    }
    for (size_t f = 0; f < *nt; ++f) {
        const uint32_t *t = &(*idx)[3 * f];
        uint32_t ab = edge_vertex[3 * f], bc = edge_vertex[3 * f + 1], ca = edge_vertex[3 * f + 2];
        const uint32_t quads[4][3] = {{t[0], ab, ca}, {t[1], bc, ab}, {t[2], ca, bc}, {ab, bc, ca}};
        memcpy(&idx2[12 * f], quads, sizeof quads);
    }
    free(r);
    free(edge_vertex);
    edge_set_free(&e);
    free(*p);
    free(*idx);
    *p = p2;
    *idx = idx2;
    *nv = nv2;
    *nt = nt2;
    return HZ_OK;
}

hz_status loop_subdivide(const double *p, size_t nv, const uint32_t *idx, size_t nt, int levels,
                         double **p_out, double **n_out, size_t *nv_out, uint32_t **idx_out,
                         size_t *nt_out, hz_error *err)
{
    *p_out = *n_out = NULL;
    *idx_out = NULL;
    for (size_t i = 0; i < 3 * nt; ++i)
        if (idx[i] >= nv)
            return hz_fail(err, "loopsubdiv: vertex index %u out of range (%zu vertices)", idx[i],
                           nv);
    double *cp = malloc((nv ? 3 * nv : 1) * sizeof *cp);
    uint32_t *ci = malloc((nt ? 3 * nt : 1) * sizeof *ci);
    if (!cp || !ci) {
        free(cp), free(ci);
        return hz_fail(err, "loopsubdiv: out of memory");
    }
    memcpy(cp, p, 3 * nv * sizeof *cp);
    memcpy(ci, idx, 3 * nt * sizeof *ci);
    for (int l = 0; l < levels; ++l)
        if (one_level(&cp, &nv, &ci, &nt, err) != HZ_OK) {
            free(cp), free(ci);
            return HZ_ERROR;
        }
    /* The limit positions, then area-weighted normals of the limit mesh. */
    edge_set e;
    ring *r = malloc((nv ? nv : 1) * sizeof *r);
    double *lp = malloc((nv ? 3 * nv : 1) * sizeof *lp);
    double *n = calloc(nv ? 3 * nv : 1, sizeof *n);
    if (!r || !lp || !n || edges_of(ci, nt, &e, err) != HZ_OK) {
        free(r), free(lp), free(n), free(cp), free(ci);
        return r && lp && n ? HZ_ERROR : hz_fail(err, "loopsubdiv: out of memory");
    }
    rings_of(cp, nv, &e, r);
    for (size_t v = 0; v < nv; ++v)
        reposition(&cp[3 * v], &r[v], 1.0 / 5.0, true, &lp[3 * v]);
    for (size_t f = 0; f < nt; ++f) {
        const double *a = &lp[3 * (size_t)ci[3 * f]], *b = &lp[3 * (size_t)ci[3 * f + 1]];
        const double *c = &lp[3 * (size_t)ci[3 * f + 2]];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double fn[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                        u[0] * w[1] - u[1] * w[0]};
        for (int k = 0; k < 3; ++k)
            for (int s = 0; s < 3; ++s)
                n[3 * (size_t)ci[3 * f + k] + s] += fn[s];
    }
    edge_set_free(&e);
    free(r);
    free(cp);
    *p_out = lp;
    *n_out = n;
    *nv_out = nv;
    *idx_out = ci;
    *nt_out = nt;
    return HZ_OK;
}
