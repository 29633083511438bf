/* Shape factories. Every error names the parameter's (or the Shape's)
 * file:line:column; params_finish makes unknown parameters errors. */
#include "scene/shape.h"
#include "scene/loopsubdiv.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/path.h"
#include "scene/curve.h"
#include "scene/mem.h"
#include "scene/ply.h"

/* A disk or cylinder becomes this many segments per full turn: the chord
 * error is r(1 - cos(pi/256)) < 8e-5 r, far below a pixel for any sensible
 * framing (shading normals of a cylinder are the exact ones). */
#define DISK_SEGMENTS 256

static hz_status finish(shape_entity *se, hz_error *err)
{
    char what[96];
    snprintf(what, sizeof what, "Shape \"%.60s\"", se->entity.type);
    return params_finish(&se->entity.params, what, err);
}

/* NULL when out of memory. */
static double *dup_doubles(const double *src, size_t n)
{
    double *d = scene_array(n, sizeof *d);
    if (d)
        memcpy(d, src, n * sizeof *d);
    return d;
}

/* trianglemesh (tri_verts 3) and bilinearmesh (4: pbrt's p00 p10 p01 p11 order). */
static hz_status create_mesh(shape_entity *se, int per_face, shape_geometry *g, hz_error *err)
{
    param_list *pl = &se->entity.params;
    size_t np, ni, nn, nuv;
    const double *P = params_point3s(pl, "P", &np);
    const double *idx = params_ints(pl, "indices", &ni);
    const double *N = params_normals(pl, "N", &nn);
    const double *uv = params_point2s(pl, "uv", &nuv);
    if (finish(se, err) != HZ_OK)
        return HZ_ERROR;
    const char *type = se->entity.type;
    if (!P)
        return hz_fail_at(err, se->entity.loc, "%s needs \"point3 P\"", type);
    if (np > UINT32_MAX)
        return hz_fail_at(err, params_loc(pl, "P"), "%s has too many vertices", type);
    static const double implicit[4] = {0, 1, 2, 3};
    if (!idx) {
        if (np != (size_t)per_face)
            return hz_fail_at(err, se->entity.loc,
                              "%s without \"integer indices\" must have exactly %d vertices, has %zu",
                              type, per_face, np);
        idx = implicit;
        ni = (size_t)per_face;
    }
    if (ni % (size_t)per_face != 0)
        return hz_fail_at(err, params_loc(pl, "indices"),
                          "%s \"indices\" must be a multiple of %d, got %zu values", type, per_face,
                          ni);
    for (size_t i = 0; i < ni; ++i)
        if (idx[i] < 0 || idx[i] >= (double)np)
            return hz_fail_at(err, params_loc(pl, "indices"),
                              "%s index %.0f (value %zu) is out of range [0, %zu)", type, idx[i],
                              i, np);
    if (N && nn != np)
        return hz_fail_at(err, params_loc(pl, "N"), "%s has %zu normals for %zu vertices", type, nn,
                          np);
    if (uv && nuv != np)
        return hz_fail_at(err, params_loc(pl, "uv"), "%s has %zu uvs for %zu vertices", type, nuv,
                          np);
    size_t faces = ni / (size_t)per_face;
    if (faces == 0)
        return hz_fail_at(err, se->entity.loc, "%s has no faces", type);
    g->kind = GEOMETRY_TRIANGLES;
    g->quads = per_face == 4;
    g->vertex_count = np;
    g->p = dup_doubles(P, 3 * np);
    g->n = N ? dup_doubles(N, 3 * np) : NULL;
    g->uv = uv ? dup_doubles(uv, 2 * np) : NULL;
    g->triangle_count = faces * (size_t)(per_face - 2);
    g->indices = scene_array(g->triangle_count, 3 * sizeof *g->indices);
    if (!g->p || (N && !g->n) || (uv && !g->uv) || !g->indices) /* g freed by the caller */
        return hz_fail_at(err, se->entity.loc, "%s: out of memory for %zu vertices", type, np);
    static const int tri[1][3] = {{0, 1, 2}};
    static const int quad[2][3] = {{0, 1, 3}, {0, 3, 2}}; /* p00 p10 p11, p00 p11 p01 */
    size_t o = 0;
    for (size_t f = 0; f < faces; ++f) {
        const double *v = idx + f * (size_t)per_face;
        for (int t = 0; t < per_face - 2; ++t)
            for (int c = 0; c < 3; ++c)
                g->indices[o++] = (uint32_t)v[per_face == 3 ? tri[t][c] : quad[t][c]];
    }
    return HZ_OK;
}

/* pbrt-v4's "loopsubdiv": a triangle mesh ("indices", "P") refined
 * "levels" times (default 3) and pushed to its limit surface. */
static hz_status create_loopsubdiv(shape_entity *se, shape_geometry *g, hz_error *err)
{
    param_list *pl = &se->entity.params;
    int levels = params_int(pl, "levels", 3);
    if (levels < 0 || levels > 10)
        params_reject(pl, "levels", "loopsubdiv \"levels\" must be in [0, 10], got %d", levels);
    params_string(pl, "scheme", "loop"); /* pbrt-v4 reads it and uses "loop" */
    static const char *const unused[] = {"N", "uv", "S"};
    for (int i = 0; i < 3; ++i)
        if (params_has(pl, unused[i]))
            params_reject(pl, unused[i],
                          "loopsubdiv takes no \"%s\" (it computes its own; pbrt-v4 refuses "
                          "it too)",
                          unused[i]);
    if (create_mesh(se, 3, g, err) != HZ_OK)
        return HZ_ERROR;
    /* 4^levels triangles each: keep the result under 2^28 triangles. */
    if (ldexp((double)g->triangle_count, 2 * levels) > (double)(1u << 28))
        return hz_fail_at(err, params_loc(pl, "levels"),
                          "loopsubdiv: %d levels of %zu triangles would make %.3g triangles "
                          "(at most 2^28)",
                          levels, g->triangle_count, ldexp((double)g->triangle_count, 2 * levels));
    double *p, *n;
    uint32_t *idx;
    size_t nv, nt;
    hz_error e;
    if (loop_subdivide(g->p, g->vertex_count, g->indices, g->triangle_count, levels, &p, &n, &nv,
                       &idx, &nt, &e) != HZ_OK)
        return hz_fail_at(err, se->entity.loc, "%s", e.message);
    free(g->p);
    free(g->indices);
    g->p = p;
    g->n = n;
    g->indices = idx;
    g->vertex_count = nv;
    g->triangle_count = nt;
    return HZ_OK;
}

static hz_status create_plymesh(shape_entity *se, shape_geometry *g, hz_error *err)
{
    param_list *pl = &se->entity.params;
    /* pbrt-v4 splits the mesh's edges down to "edgelength" and moves the
     * vertices along their normals by the texture: not done here. */
    if (params_has(pl, "displacement"))
        return hz_fail_at(err, params_loc(pl, "displacement"),
                          "plymesh \"displacement\" is not supported (pbrt-v4 subdivides the "
                          "mesh to \"edgelength\" and displaces its vertices; haze renders the "
                          "mesh as given): remove it, or bump-map with the material's "
                          "\"displacement\"");
    const char *name = params_string(pl, "filename", NULL);
    if (finish(se, err) != HZ_OK)
        return HZ_ERROR;
    if (!name)
        return hz_fail_at(err, se->entity.loc, "plymesh needs \"string filename\"");
    /* Relative to the directory of the scene file that names it. */
    char *path = path_of_scene_file(se->entity.loc, name);
    if (!path)
        return hz_fail_at(err, params_loc(pl, "filename"), "plymesh: out of memory");
    hz_error perr;
    hz_status st = ply_read(path, g, &perr);
    free(path);
    if (st != HZ_OK)
        return hz_fail_at(err, params_loc(pl, "filename"), "plymesh: %s", perr.message);
    return HZ_OK;
}


/* "phimax" in degrees, (0, 360] (pbrt-v4 clamps to [0, 360]), as radians. */
static double read_phimax(param_list *pl)
{
    double deg = params_float(pl, "phimax", 360.0);
    if (!(deg > 0.0 && deg <= 360.0))
        params_reject(pl, "phimax", "\"phimax\" must be in (0, 360] degrees, got %g", deg);
    return deg >= 360.0 ? 2.0 * HZ_PI : hz_radians(hz_clamp(deg, 1e-9, 360.0));
}

static hz_status create_sphere(shape_entity *se, shape_geometry *g, hz_error *err)
{
    param_list *pl = &se->entity.params;
    double r = params_float(pl, "radius", 1.0);
    if (!(r > 0.0))
        params_reject(pl, "radius", "sphere \"radius\" must be > 0, got %g", r);
    /* pbrt-v4: the z range clamped to the sphere, phimax to (0, 360]. */
    double z0 = params_float(pl, "zmin", -r), z1 = params_float(pl, "zmax", r);
    double phimax = read_phimax(pl);
    if (!(isfinite(z0) && isfinite(z1)))
        params_reject(pl, "zmin", "sphere \"zmin\" and \"zmax\" must be finite");
    double lo = hz_clamp(fmin(z0, z1), -r, r), hi = hz_clamp(fmax(z0, z1), -r, r);
    if (!(hi > lo) && r > 0.0)
        params_reject(pl, "zmax", "sphere \"zmin\" and \"zmax\" leave nothing of it");
    if (finish(se, err) != HZ_OK)
        return HZ_ERROR;
    g->kind = GEOMETRY_SPHERE;
    g->radius = r;
    g->zmin = lo;
    g->zmax = hi;
    g->phimax = phimax;
    g->unit_area = phimax * r * (hi - lo);
    return HZ_OK;
}

/* A strip between two rings of a surface of revolution about z, over phi in
 * [0, phimax]: ring k at radius rad[k] and height z[k], the first ring the
 * outer (disk) or lower (cylinder) one. DISK_SEGMENTS per full turn; the seam
 * is duplicated so u runs 0..1 as pbrt-v4's phi / phimax, v from ring 0 to
 * ring 1. Triangles wind so that their normal is pbrt-v4's: +z for a disk,
 * outward for a cylinder; `radial` gives the shading normals (x, y, 0)/r of
 * a cylinder instead of (0, 0, 1). A ring of radius 0 is a point: one
 * triangle per segment. */
static hz_status ring_strip(shape_entity *se, shape_geometry *g, double phimax,
                            const double rad[2], const double z[2], bool radial, hz_error *err)
{
    size_t segs = (size_t)ceil(DISK_SEGMENTS * phimax / (2.0 * HZ_PI));
    segs = segs < 1 ? 1 : segs;
    size_t ring = segs + 1;
    bool two = rad[1] > 0.0;
    g->kind = GEOMETRY_TRIANGLES;
    g->vertex_count = 2 * ring;
    g->p = scene_array(g->vertex_count, 3 * sizeof *g->p);
    g->n = scene_array(g->vertex_count, 3 * sizeof *g->n);
    g->uv = scene_array(g->vertex_count, 2 * sizeof *g->uv);
    g->triangle_count = two ? 2 * segs : segs;
    g->indices = scene_array(g->triangle_count, 3 * sizeof *g->indices);
    if (!g->p || !g->n || !g->uv || !g->indices) /* g freed by the caller */
        return hz_fail_at(err, se->entity.loc, "%s: out of memory", se->entity.type);
    for (size_t k = 0; k < 2; ++k)
        for (size_t i = 0; i < ring; ++i) {
            double u = (double)i / segs, phi = phimax * u;
            /* The full turn's seam lands exactly on phi = 0. */
            double c = i == segs && phimax >= 2.0 * HZ_PI ? 1.0 : cos(phi);
            double sn = i == segs && phimax >= 2.0 * HZ_PI ? 0.0 : sin(phi);
            size_t v = k * ring + i;
            g->p[3 * v] = rad[k] * c;
            g->p[3 * v + 1] = rad[k] * sn;
            g->p[3 * v + 2] = z[k];
            g->n[3 * v] = radial ? c : 0.0;
            g->n[3 * v + 1] = radial ? sn : 0.0;
            g->n[3 * v + 2] = radial ? 0.0 : 1.0;
            g->uv[2 * v] = u;
            g->uv[2 * v + 1] = (double)k;
        }
    size_t o = 0;
    for (uint32_t i = 0; i < segs; ++i) {
        uint32_t a = i, b = i + 1, c = (uint32_t)ring + i, d = (uint32_t)ring + i + 1;
        uint32_t t1[3] = {a, b, d};
        for (int j = 0; j < 3; ++j)
            g->indices[o++] = t1[j];
        if (two) {
            uint32_t t2[3] = {a, d, c};
            for (int j = 0; j < 3; ++j)
                g->indices[o++] = t2[j];
        }
    }
    return HZ_OK;
}

static hz_status create_disk(shape_entity *se, shape_geometry *g, hz_error *err)
{
    param_list *pl = &se->entity.params;
    double h = params_float(pl, "height", 0.0);
    double r = params_float(pl, "radius", 1.0);
    double ri = params_float(pl, "innerradius", 0.0);
    double phimax = read_phimax(pl);
    if (!(r > 0.0))
        params_reject(pl, "radius", "disk \"radius\" must be > 0, got %g", r);
    else if (!(ri >= 0.0 && ri < r))
        params_reject(pl, "innerradius", "disk \"innerradius\" must be in [0, radius), got %g", ri);
    if (finish(se, err) != HZ_OK)
        return HZ_ERROR;
    g->unit_area = 0.5 * phimax * (r * r - ri * ri);
    const double rad[2] = {r, ri}, z[2] = {h, h};
    return ring_strip(se, g, phimax, rad, z, false, err);
}

/* pbrt-v4's cylinder: radius, zmin, zmax, phimax, normals outward. */
static hz_status create_cylinder(shape_entity *se, shape_geometry *g, hz_error *err)
{
    param_list *pl = &se->entity.params;
    double r = params_float(pl, "radius", 1.0);
    double z0 = params_float(pl, "zmin", -1.0), z1 = params_float(pl, "zmax", 1.0);
    double phimax = read_phimax(pl);
    if (!(r > 0.0 && isfinite(r)))
        params_reject(pl, "radius", "cylinder \"radius\" must be finite and > 0, got %g", r);
    if (!(isfinite(z0) && isfinite(z1) && z0 != z1))
        params_reject(pl, "zmax", "cylinder \"zmin\" and \"zmax\" must be finite and differ");
    if (finish(se, err) != HZ_OK)
        return HZ_ERROR;
    g->unit_area = fabs(z1 - z0) * r * phimax;
    const double rad[2] = {r, r}, z[2] = {fmin(z0, z1), fmax(z0, z1)};
    return ring_strip(se, g, phimax, rad, z, true, err);
}

hz_status shape_geometry_create(shape_entity *se, shape_geometry *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    const char *type = se->entity.type;
    param_list *pl = &se->entity.params;
    /* Every shape takes "alpha" (read before the shape's own parameters are
     * finished). Values outside [0, 1] act as pbrt-v4's: 0 or 1. */
    const char *alpha_texture = params_texture(pl, "alpha");
    double alpha = alpha_texture ? 1.0 : params_float(pl, "alpha", 1.0);
    if (!isfinite(alpha))
        params_reject(pl, "alpha", "\"alpha\" must be finite, got %g", alpha);
    hz_status st;
    if (strcmp(type, "trianglemesh") == 0)
        st = create_mesh(se, 3, out, err);
    else if (strcmp(type, "bilinearmesh") == 0)
        st = create_mesh(se, 4, out, err);
    else if (strcmp(type, "plymesh") == 0)
        st = create_plymesh(se, out, err);
    else if (strcmp(type, "sphere") == 0)
        st = create_sphere(se, out, err);
    else if (strcmp(type, "disk") == 0)
        st = create_disk(se, out, err);
    else if (strcmp(type, "cylinder") == 0)
        st = create_cylinder(se, out, err);
    else if (strcmp(type, "loopsubdiv") == 0)
        st = create_loopsubdiv(se, out, err);
    else if (strcmp(type, "curve") == 0)
        st = shape_curve_create(se, out, err);
    else
        st = hz_fail_at(err, se->entity.loc,
                        "unknown shape \"%.60s\"; supported: trianglemesh plymesh sphere disk "
                        "cylinder bilinearmesh loopsubdiv curve",
                        type);
    if (st != HZ_OK) {
        shape_geometry_free(out);
        return st;
    }
    out->alpha = alpha; /* the creators fill the rest of *out */
    out->alpha_texture = alpha_texture;
    return HZ_OK;
}
