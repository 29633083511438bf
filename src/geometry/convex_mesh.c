/* Small static convex meshes that change the medium (geom_shape.planes):
 * their planes, faces and triangles' barycentric planes, and the next hit of
 * a ray that knows it is inside one or has left it (geom_past), found from
 * the planes without asking Embree (geometry_intersect_past). */
#include "geometry/convex_mesh.h"
#include "geometry/intersect.h"
#include "geometry/medium_interface.h"
#include "geometry/surface_hit.h"

#include <stdlib.h>

/* Meshes up to this many triangles are checked for convexity (all pairs of
 * triangle and vertex: at most 64 x 192). */
#define GEOMETRY_MAX_CONVEX_TRIANGLES 64

/* The planes of a convex mesh (geom_shape.planes), or NULL when some vertex
 * lies in front of some triangle's plane by more than `tol`. A degenerate
 * triangle (Embree never reports it) gets a zero plane. */
static double *convex_planes(const geom_shape *s, double tol)
{
    double *out = malloc(4 * s->triangle_count * sizeof *out);
    if (!out)
        return NULL;
    for (size_t t = 0; t < s->triangle_count; ++t) {
        vec3 v[3];
        for (int k = 0; k < 3; ++k) {
            const float *f = &s->p[3 * s->indices[3 * t + (size_t)k]];
            v[k] = v3(f[0], f[1], f[2]);
        }
        vec3 n = v3_cross(v3_sub(v[1], v[0]), v3_sub(v[2], v[0]));
        double len = v3_length(n);
        if (!(len > 0.0)) {
            out[4 * t] = out[4 * t + 1] = out[4 * t + 2] = out[4 * t + 3] = 0.0;
            continue;
        }
        n = v3_scale(n, 1.0 / len);
        double front = 0.0, behind = 0.0;
        for (size_t k = 0; k < s->vertex_count; ++k) {
            const float *f = &s->p[3 * k];
            double h = v3_dot(v3_sub(v3(f[0], f[1], f[2]), v[0]), n);
            front = hz_fmax(front, h);
            behind = hz_fmax(behind, -h);
        }
        if (front > tol && behind > tol) {
            free(out);
            return NULL;
        }
        if (front > tol)
            n = v3_neg(n);
        out[4 * t] = n.x;
        out[4 * t + 1] = n.y;
        out[4 * t + 2] = n.z;
        out[4 * t + 3] = v3_dot(n, v[0]);
    }
    return out;
}

/* geom_shape.convex_tris. */
static geom_convex_tri *convex_tris(const geom_shape *s)
{
    geom_convex_tri *out = malloc(s->triangle_count * sizeof *out);
    if (!out)
        return NULL;
    for (size_t t = 0; t < s->triangle_count; ++t) {
        const uint32_t *tri = &s->indices[3 * t];
        vec3 p0 = geom_vertex(s, tri[0]), p1 = geom_vertex(s, tri[1]), p2 = geom_vertex(s, tri[2]);
        vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0), n = v3_cross(e1, e2);
        double nn = v3_dot(n, n);
        /* b1 = ((q - p0) x e2) . n / |n|^2, b2 = (e1 x (q - p0)) . n / |n|^2;
         * a degenerate triangle holds no point. */
        vec3 a1 = nn > 0.0 ? v3_scale(v3_cross(e2, n), 1.0 / nn) : v3(0, 0, 0);
        vec3 a2 = nn > 0.0 ? v3_scale(v3_cross(n, e1), 1.0 / nn) : v3(0, 0, 0);
        geom_convex_tri *c = &out[t];
        c->b1[0] = a1.x;
        c->b1[1] = a1.y;
        c->b1[2] = a1.z;
        c->b1[3] = nn > 0.0 ? -v3_dot(a1, p0) : -1.0;
        c->b2[0] = a2.x;
        c->b2[1] = a2.y;
        c->b2[2] = a2.z;
        c->b2[3] = nn > 0.0 ? -v3_dot(a2, p0) : -1.0;
        c->p2 = p2;
        c->n = v3_cross(v3_sub(p0, p2), v3_sub(p1, p2));
        c->ng = v3_normalize(c->n);
        if (s->flip_normal)
            c->ng = v3_neg(c->ng);
    }
    return out;
}

/* geom_shape.faces from its planes: triangles whose planes agree (normals
 * within 1e-9, offsets within convex_tol) share a face. */
static hz_status convex_faces(geom_shape *s)
{
    size_t n = s->triangle_count;
    uint32_t *face_of = malloc(n * sizeof *face_of);
    s->faces = malloc(n * sizeof *s->faces);
    s->face_tris = malloc(n * sizeof *s->face_tris);
    if (!face_of || !s->faces || !s->face_tris) {
        free(face_of);
        return HZ_ERROR;
    }
    size_t faces = 0;
    for (size_t t = 0; t < n; ++t) {
        const double *pl = &s->planes[4 * t];
        face_of[t] = UINT32_MAX;
        if (pl[0] == 0.0 && pl[1] == 0.0 && pl[2] == 0.0)
            continue; /* degenerate: never hit */
        size_t f = 0;
        while (f < faces &&
               !(fabs(s->faces[f].n[0] - pl[0]) <= 1e-9 && fabs(s->faces[f].n[1] - pl[1]) <= 1e-9 &&
                 fabs(s->faces[f].n[2] - pl[2]) <= 1e-9 &&
                 fabs(s->faces[f].c - pl[3]) <= s->convex_tol))
            ++f;
        if (f == faces) {
            s->faces[faces] = (geom_face){{pl[0], pl[1], pl[2]}, pl[3], 0, 0};
            ++faces;
        }
        face_of[t] = (uint32_t)f;
        s->faces[f].count++;
    }
    uint32_t next = 0;
    for (size_t f = 0; f < faces; ++f) {
        s->faces[f].first = next;
        next += s->faces[f].count;
        s->faces[f].count = 0;
    }
    for (size_t t = 0; t < n; ++t)
        if (face_of[t] != UINT32_MAX) {
            geom_face *f = &s->faces[face_of[t]];
            s->face_tris[f->first + f->count++] = (uint32_t)t;
        }
    s->face_count = faces;
    free(face_of);
    return HZ_OK;
}

hz_status geom_find_convex_interfaces(geometry *g, size_t medium_count, hz_error *err)
{
    if (g->motion || g->instance_count > 0 || g->object_count > 0 || g->shape_count == 0)
        return HZ_OK;
    bool any = false;
    for (size_t i = 0; i < g->shape_count; ++i) {
        const geom_shape *s = &g->shapes[i];
        any |= geom_changes_medium(s) && s->kind == GEOMETRY_TRIANGLES &&
               s->triangle_count <= GEOMETRY_MAX_CONVEX_TRIANGLES;
    }
    if (!any)
        return HZ_OK;
    size_t n = g->shape_count;
    vec3(*box)[2] = malloc(n * sizeof *box);
    vec3(*before)[2] = malloc((n + 1) * sizeof *before);
    vec3(*after)[2] = malloc((n + 1) * sizeof *after);
    if (!box || !before || !after) {
        free(box);
        free(before);
        free(after);
        return hz_fail(err, "out of memory");
    }
    /* before[i]: the union of the boxes of shapes 0..i-1; after[i]: of i..n-1. */
    before[0][0] = after[n][0] = v3(INFINITY, INFINITY, INFINITY);
    before[0][1] = after[n][1] = v3(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < n; ++i) {
        box[i][0] = v3(INFINITY, INFINITY, INFINITY);
        box[i][1] = v3(-INFINITY, -INFINITY, -INFINITY);
        if (!g->shapes[i].left_out)
            geom_shape_box(&g->shapes[i], &box[i][0], &box[i][1]);
        before[i + 1][0] = v3_min(before[i][0], box[i][0]);
        before[i + 1][1] = v3_max(before[i][1], box[i][1]);
    }
    for (size_t i = n; i-- > 0;) {
        after[i][0] = v3_min(after[i + 1][0], box[i][0]);
        after[i][1] = v3_max(after[i + 1][1], box[i][1]);
    }
    for (size_t i = 0; i < n; ++i) {
        geom_shape *s = &g->shapes[i];
        if (!geom_changes_medium(s) || s->kind != GEOMETRY_TRIANGLES ||
            s->triangle_count > GEOMETRY_MAX_CONVEX_TRIANGLES)
            continue;
        /* Float rounding: 1e-6 of the mesh's extent. */
        s->convex_tol = 1e-6 * v3_max_component(v3_sub(box[i][1], box[i][0]));
        s->planes = convex_planes(s, s->convex_tol);
        if (s->planes && (convex_faces(s) != HZ_OK || !(s->convex_tris = convex_tris(s)))) {
            free(box);
            free(before);
            free(after);
            return hz_fail(err, "out of memory");
        }
        s->others_lo = v3_min(before[i][0], after[i + 1][0]);
        s->others_hi = v3_max(before[i][1], after[i + 1][1]);
    }
    free(box);
    free(before);
    free(after);
    g->convex_around = calloc(medium_count ? medium_count : 1, sizeof *g->convex_around);
    if (!g->convex_around)
        return hz_fail(err, "out of memory");
    g->convex_around_count = medium_count;
    double largest = -1.0;
    for (size_t i = n; i-- > 0;) {
        const geom_shape *s = &g->shapes[i];
        if (s->planes && s->medium_inside >= 0 && (size_t)s->medium_inside < medium_count)
            g->convex_around[s->medium_inside] = s;
        if (s->planes && s->face_count > 0 && s->convex_tol > largest) {
            largest = s->convex_tol; /* proportional to the mesh's extent */
            g->convex_entry = s;
        }
    }
    return HZ_OK;
}

geom_past geometry_past(const geom_hit *h, vec3 d)
{
    geom_past past = {NULL, NULL};
    const double *n = h->shape->planes;
    if (!n)
        return past;
    n += 4 * (size_t)h->prim;
    double dn = d.x * n[0] + d.y * n[1] + d.z * n[2];
    if (dn > 0.0)
        past.left = h->shape;
    else if (dn < 0.0)
        past.within = h->shape;
    return past;
}

const geom_shape *geometry_convex_around(const geometry *g, int medium)
{
    return medium >= 0 && (size_t)medium < g->convex_around_count ? g->convex_around[medium]
                                                                   : NULL;
}

/* How far q lies inside triangle `prim` of convex mesh s (the least of its
 * barycentrics: >= 0 inside), and its barycentrics (Embree's u, v). */
static double triangle_inside(const geom_shape *s, unsigned prim, vec3 q, double *u, double *v)
{
    const geom_convex_tri *c = &s->convex_tris[prim];
    double b1 = c->b1[0] * q.x + c->b1[1] * q.y + c->b1[2] * q.z + c->b1[3];
    double b2 = c->b2[0] * q.x + c->b2[1] * q.y + c->b2[2] * q.z + c->b2[3];
    *u = b1;
    *v = b2;
    return hz_fmin(hz_fmin(b1, b2), 1.0 - b1 - b2);
}

/* surface_at for triangle `prim` of convex mesh s (no uv, no shading
 * normals), with its cached plane: the same values. */
static void convex_surface_at(const geom_shape *s, unsigned prim, double u, double v, vec3 o,
                              vec3 d, double t, geom_hit *hit)
{
    const geom_convex_tri *c = &s->convex_tris[prim];
    double dn = v3_dot(d, c->n);
    if (dn == 0.0) {
        geom_surface_at(s, prim, u, v, o, d, t, hit);
        return;
    }
    hit->p_error = 0.0;
    hit->p = v3_add(o, v3_scale(d, v3_dot(v3_sub(c->p2, o), c->n) / dn));
    hit->ng = hit->ns = c->ng;
}

/* The hit of o + t d on face f of convex mesh s: the face's triangle that
 * holds the point. 1 with *hit filled, -1 (Embree must answer) when none
 * does. */
static int face_hit(const geom_shape *s, const geom_face *f, vec3 o, vec3 d, double t,
                    geom_hit *hit)
{
    vec3 q = v3_add(o, v3_scale(d, t));
    double best = -INFINITY, u = 0.0, v = 0.0;
    unsigned prim = 0;
    for (uint32_t i = 0; i < f->count && best < 0.0; ++i) {
        unsigned k = s->face_tris[f->first + i];
        double bu = 0.0, bv = 0.0, in = triangle_inside(s, k, q, &bu, &bv);
        if (in > best) {
            best = in;
            prim = k;
            u = bu;
            v = bv;
        }
    }
    if (!(best >= -1e-7))
        return -1;
    hit->t = t;
    hit->prim = prim;
    hit->shape = s;
    convex_surface_at(s, prim, u, v, o, d, t, hit);
    return 1;
}

/* The next hit of a ray inside convex mesh s (geom_past.within): 1 with
 * *hit filled (the mesh's exit), 0 for none within [tmin, tmax], -1 when
 * Embree must answer (the origin is not inside, another shape's box lies on
 * the way, the exit is not found on a triangle, or the hit needs more than
 * the plane). */
static int convex_exit(const geom_shape *s, vec3 o, vec3 d, double tmin, double tmax,
                       geom_hit *hit)
{
    if (s->hit_uv || s->n || !geom_embree_can_trace(o, d, tmin, tmax))
        return -1;
    vec3 p = v3_add(o, v3_scale(d, tmin));
    double t_exit = INFINITY;
    const geom_face *exit = NULL;
    for (size_t k = 0; k < s->face_count; ++k) {
        const geom_face *f = &s->faces[k];
        double h = f->n[0] * p.x + f->n[1] * p.y + f->n[2] * p.z - f->c;
        if (!(h <= s->convex_tol))
            return -1; /* not inside (or NaN) */
        double dn = f->n[0] * d.x + f->n[1] * d.y + f->n[2] * d.z;
        if (dn > 0.0 && -h < t_exit * dn) {
            t_exit = -h / dn;
            exit = f;
        }
    }
    if (!exit || !(t_exit >= 0.0))
        return -1;
    double t = tmin + t_exit;
    bool others = s->others_lo.x <= s->others_hi.x;
    if (t > tmax)
        return others && !geom_misses_box(s->others_lo, s->others_hi, o, d, tmin, tmax) ? -1 : 0;
    if (others && !geom_misses_box(s->others_lo, s->others_hi, o, d, tmin, t))
        return -1;
    return face_hit(s, exit, o, d, t, hit);
}

/* The next hit of a ray whose origin at tmin lies outside convex mesh s,
 * when the ray misses the box of every other shape: 1 with *hit filled (the
 * mesh's entry, where the last of the planes it enters through is crossed),
 * 0 for none within [tmin, tmax], -1 when Embree must answer (the origin is
 * inside or within rounding of a plane, the ray grazes an edge, another
 * shape's box lies on the way, the entry is not found on a triangle, or the
 * hit needs more than the plane). */
static int convex_entry(const geom_shape *s, vec3 o, vec3 d, double tmin, double tmax,
                        geom_hit *hit)
{
    if (s->hit_uv || s->n || !geom_embree_can_trace(o, d, tmin, tmax))
        return -1;
    if (s->others_lo.x <= s->others_hi.x &&
        !geom_misses_box(s->others_lo, s->others_hi, o, d, tmin, tmax))
        return -1;
    vec3 p = v3_add(o, v3_scale(d, tmin));
    double t_near = 0.0, t_far = INFINITY;
    const geom_face *entry = NULL;
    for (size_t k = 0; k < s->face_count; ++k) {
        const geom_face *f = &s->faces[k];
        double h = f->n[0] * p.x + f->n[1] * p.y + f->n[2] * p.z - f->c;
        if (!(fabs(h) > s->convex_tol))
            return -1; /* on the surface (or NaN) */
        double dn = f->n[0] * d.x + f->n[1] * d.y + f->n[2] * d.z;
        if (h > 0.0) {
            if (!(dn < 0.0))
                return 0; /* in front of this plane and not moving towards it */
            if (h > t_near * -dn) {
                t_near = h / -dn;
                entry = f;
            }
        } else if (dn > 0.0 && -h < t_far * dn) {
            t_far = -h / dn;
        }
    }
    if (!entry)
        return -1; /* inside */
    /* Where the entry and exit planes cross within rounding the ray grazes
     * an edge: Embree decides. */
    double slack = 1e-6 * (t_near + fabs(tmin));
    if (t_near > t_far + slack)
        return 0;
    if (!(t_near < t_far - slack))
        return -1;
    double t = tmin + t_near;
    if (t > tmax)
        return 0;
    return face_hit(s, entry, o, d, t, hit);
}

bool geometry_intersect_past(const geometry *g, geom_past past, vec3 o, vec3 d, double tmin,
                             double tmax, double time, geom_hit *hit)
{
    /* The box of the other shapes lies inside the world box: it replaces
     * that test. With no other shape, nothing is left to hit. */
    const geom_shape *left = past.left;
    if (left)
        return left->others_lo.x <= left->others_hi.x &&
               !geom_misses_box(left->others_lo, left->others_hi, o, d, tmin, tmax) &&
               geom_trace(g, o, d, tmin, tmax, time, hit);
    if (past.within) {
        int found = convex_exit(past.within, o, d, tmin, tmax, hit);
        if (found >= 0)
            return found;
    }
    if (geom_misses_world_box(g, o, d, tmin, tmax))
        return false;
    if (g->convex_entry) {
        int found = convex_entry(g->convex_entry, o, d, tmin, tmax, hit);
        if (found >= 0)
            return found;
    }
    return geom_trace(g, o, d, tmin, tmax, time, hit);
}
