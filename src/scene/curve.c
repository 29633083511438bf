/* pbrt-v4's "curve" shape: its control points as cubic Bezier segments.
 * "bezier" curves of degree 3 share end points (3n + 1 points); degree 2
 * segments (2n + 1 points) are raised to cubic; uniform "bspline" curves
 * (n + degree points) become one Bezier segment per span by blossoming, as
 * pbrt-v4 converts them. The width runs linearly from width0 to width1 over
 * the whole curve; a ribbon's normals "N" are given at the segment ends. */
#include "scene/curve.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/vec.h"
#include "scene/mem.h"

static vec3 point_at(const double *P, size_t i) { return v3(P[3 * i], P[3 * i + 1], P[3 * i + 2]); }

/* (1 - t) a + t b, as pbrt-v4's Lerp. */
static vec3 mix(double t, vec3 a, vec3 b) { return v3_add(v3_scale(a, 1.0 - t), v3_scale(b, t)); }

/* The cubic Bezier control points of segment `seg` (pbrt-v4's
 * ElevateQuadraticBezierToCubic, QuadraticBSplineToBezier and
 * CubicBSplineToBezier). */
static void segment_points(const double *P, size_t seg, int degree, bool bspline, vec3 out[4])
{
    if (!bspline) {
        size_t o = seg * (size_t)degree;
        if (degree == 3) {
            for (int i = 0; i < 4; ++i)
                out[i] = point_at(P, o + (size_t)i);
            return;
        }
        vec3 a = point_at(P, o), b = point_at(P, o + 1), c = point_at(P, o + 2);
        out[0] = a;
        out[1] = mix(2.0 / 3.0, a, b);
        out[2] = mix(1.0 / 3.0, b, c);
        out[3] = c;
        return;
    }
    if (degree == 2) {
        vec3 a = point_at(P, seg), b = point_at(P, seg + 1), c = point_at(P, seg + 2);
        vec3 p11 = mix(0.5, a, b), p22 = mix(0.5, b, c);
        out[0] = p11;
        out[1] = mix(2.0 / 3.0, p11, b);
        out[2] = mix(1.0 / 3.0, b, p22);
        out[3] = p22;
        return;
    }
    vec3 p012 = point_at(P, seg), p123 = point_at(P, seg + 1), p234 = point_at(P, seg + 2),
         p345 = point_at(P, seg + 3);
    vec3 p122 = mix(2.0 / 3.0, p012, p123), p223 = mix(1.0 / 3.0, p123, p234);
    vec3 p233 = mix(2.0 / 3.0, p123, p234), p334 = mix(1.0 / 3.0, p234, p345);
    out[0] = mix(0.5, p122, p223);
    out[1] = p223;
    out[2] = p233;
    out[3] = mix(0.5, p233, p334);
}

/* A "curve" Shape's parameters, as read (curve_read). */
typedef struct {
    const double *P, *N;
    size_t np, nn;
    double w0, w1;
    int degree, split;
    bool bspline;
    curve_type type;
} curve_params;

/* Reads the parameters; a bad value is rejected (params_reject), to be
 * reported by params_finish. */
static void curve_read(param_list *pl, curve_params *c)
{
    c->np = c->nn = 0;
    c->P = params_point3s(pl, "P", &c->np);
    c->N = params_normals(pl, "N", &c->nn);
    double width = params_float(pl, "width", 1.0);
    c->w0 = params_float(pl, "width0", width);
    c->w1 = params_float(pl, "width1", width);
    c->degree = params_int(pl, "degree", 3);
    const char *basis = params_string(pl, "basis", "bezier");
    const char *type = params_string(pl, "type", "flat");
    /* pbrt-v4 cuts each segment into 2^splitdepth pieces (its BVH's
     * primitives), each refined by its own flatness: as haze does. */
    c->split = params_int(pl, "splitdepth", 3);
    if (c->split < 0 || c->split > 8)
        params_reject(pl, "splitdepth", "curve \"splitdepth\" must be in [0, 8], got %d", c->split);
    double w0 = c->w0, w1 = c->w1;
    if (!(isfinite(w0) && isfinite(w1) && w0 >= 0.0 && w1 >= 0.0 && (w0 > 0.0 || w1 > 0.0)))
        params_reject(pl, params_has(pl, "width0") ? "width0" : "width",
                      "curve widths must be finite and >= 0, not both 0 (got %g, %g)", w0, w1);
    if (c->degree != 2 && c->degree != 3)
        params_reject(pl, "degree", "curve \"degree\" must be 2 or 3, got %d", c->degree);
    c->bspline = strcmp(basis, "bspline") == 0;
    if (!c->bspline && strcmp(basis, "bezier") != 0)
        params_reject(pl, "basis", "curve \"basis\" must be \"bezier\" or \"bspline\", got \"%s\"",
                      basis);
    c->type = CURVE_FLAT;
    if (strcmp(type, "cylinder") == 0)
        c->type = CURVE_CYLINDER;
    else if (strcmp(type, "ribbon") == 0)
        c->type = CURVE_RIBBON;
    else if (strcmp(type, "flat") != 0)
        params_reject(pl, "type",
                      "curve \"type\" must be \"flat\", \"cylinder\" or \"ribbon\", got \"%s\"",
                      type);
    if (c->N && c->type != CURVE_RIBBON)
        params_reject(pl, "N",
                      "curve \"N\" is used by \"ribbon\" curves only (pbrt-v4 ignores it here "
                      "with a warning)");
}

/* The number of segments of the control points, and the check of the
 * normals against it. */
static hz_status curve_segments(const shape_entity *se, param_list *pl, const curve_params *c,
                                size_t *out, hz_error *err)
{
    size_t np = c->np, nn = c->nn;
    int degree = c->degree;
    const double *N = c->N;
    size_t segs;
    if (!c->bspline) {
        if (np < (size_t)degree + 1 || (np - 1) % (size_t)degree != 0)
            return hz_fail_at(err, params_loc(pl, "P"),
                              "curve: a degree %d Bezier curve needs %d + %d n control points "
                              "(n >= 0), got %zu",
                              degree, degree + 1, degree, np);
        segs = (np - 1) / (size_t)degree;
    } else {
        if (np < (size_t)degree + 1)
            return hz_fail_at(err, params_loc(pl, "P"),
                              "curve: a degree %d b-spline needs at least %d control points, "
                              "got %zu",
                              degree, degree + 1, np);
        segs = np - (size_t)degree;
    }
    if (c->type == CURVE_RIBBON && !N)
        return hz_fail_at(err, se->entity.loc,
                          "a \"ribbon\" curve needs \"normal N\" at its segment ends");
    if (N && nn != segs + 1)
        return hz_fail_at(err, params_loc(pl, "N"),
                          "curve: %zu segments need %zu normals \"N\", got %zu", segs, segs + 1,
                          nn);
    for (size_t i = 0; N && i < nn; ++i)
        if (!(v3_length_sq(point_at(N, i)) > 0.0) || !v3_is_finite(point_at(N, i)))
            return hz_fail_at(err, params_loc(pl, "N"),
                              "curve normal %zu must be finite and non-zero", i);
    *out = segs;
    return HZ_OK;
}

/* Each segment's control points, end widths and (ribbon) end normals. */
static void curve_fill(shape_geometry *g, const curve_params *c, size_t segs)
{
    const double *P = c->P, *N = c->N;
    double w0 = c->w0, w1 = c->w1;
    for (size_t s = 0; s < segs; ++s) {
        vec3 cp[4];
        segment_points(P, s, c->degree, c->bspline, cp);
        for (int i = 0; i < 4; ++i) {
            g->cp[12 * s + 3 * (size_t)i] = cp[i].x;
            g->cp[12 * s + 3 * (size_t)i + 1] = cp[i].y;
            g->cp[12 * s + 3 * (size_t)i + 2] = cp[i].z;
        }
        g->width[2 * s] = w0 + (w1 - w0) * (double)s / (double)segs;
        g->width[2 * s + 1] = w0 + (w1 - w0) * (double)(s + 1) / (double)segs;
        for (int e = 0; N && e < 2; ++e) {
            vec3 n = v3_normalize(point_at(N, s + (size_t)e));
            g->normals[6 * s + 3 * (size_t)e] = n.x;
            g->normals[6 * s + 3 * (size_t)e + 1] = n.y;
            g->normals[6 * s + 3 * (size_t)e + 2] = n.z;
        }
    }
}

hz_status shape_curve_create(shape_entity *se, shape_geometry *g, hz_error *err)
{
    param_list *pl = &se->entity.params;
    curve_params c;
    curve_read(pl, &c);
    if (params_finish(pl, "Shape \"curve\"", err) != HZ_OK)
        return HZ_ERROR;
    if (!c.P)
        return hz_fail_at(err, se->entity.loc, "curve needs \"point3 P\"");
    size_t segs = 0;
    if (curve_segments(se, pl, &c, &segs, err) != HZ_OK)
        return HZ_ERROR;
    g->kind = GEOMETRY_CURVES;
    g->curve = c.type;
    g->split = c.split;
    g->segment_count = segs;
    g->cp = scene_array(segs, 12 * sizeof *g->cp);
    g->width = scene_array(segs, 2 * sizeof *g->width);
    g->normals = c.N ? scene_array(segs, 6 * sizeof *g->normals) : NULL;
    if (!g->cp || !g->width || (c.N && !g->normals)) /* g freed by the caller */
        return hz_fail_at(err, se->entity.loc, "curve: out of memory for %zu segments", segs);
    curve_fill(g, &c, segs);
    return HZ_OK;
}
