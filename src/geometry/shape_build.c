/* One shape as Embree geometry: what every shape shares (its material, media
 * and alpha, and the filters that apply them) and triangle meshes, whose
 * vertices Embree holds in float. Spheres and curves: user_shapes.c. A shape
 * whose error has a place is left out (geom_shape_failed). */
#include "geometry/alpha.h"
#include "geometry/shape_build.h"
#include "geometry/user_shapes.h"

#include <stdlib.h>
#include <string.h>

/* Shadow rays pass through interfaces (they bound media, not surfaces). */
static void reject_occlusion(const struct RTCFilterFunctionNArguments *args)
{
    for (unsigned i = 0; i < args->N; ++i)
        args->valid[i] = 0;
}

/* The index of medium `name` in sd->media; "" is vacuum (-1). */
static hz_status resolve_medium(const scene_desc *sd, const char *name, file_loc loc, int *out,
                                hz_error *err)
{
    *out = scene_find_medium(sd, name);
    if (*out != SCENE_MEDIUM_UNDEFINED)
        return HZ_OK;
    return hz_fail_at(err, loc, "MediumInterface names medium \"%s\", which is not defined "
                                "(MakeNamedMedium)",
                      name);
}

/* The fields of `out` every shape has before its geometry: the zero value,
 * no area light, its material and its media. */
static hz_status shape_material_media(const scene_desc *sd, const shape_entity *se,
                                      const material *materials, size_t material_count,
                                      const material *default_material, geom_shape *out,
                                      hz_error *err)
{
    memset(out, 0, sizeof *out);
    out->area_light = -1;
    out->material = default_material;
    if (se->material >= 0) {
        if ((size_t)se->material >= material_count)
            return hz_fail_at(err, se->entity.loc, "shape names material %d of %zu",
                              se->material, material_count);
        out->material = &materials[se->material];
    }
    if (resolve_medium(sd, se->inside_medium, se->entity.loc, &out->medium_inside, err) != HZ_OK ||
        resolve_medium(sd, se->outside_medium, se->entity.loc, &out->medium_outside, err) != HZ_OK)
        return HZ_ERROR;
    return HZ_OK;
}

/* The shape's alpha: the constant, or its "texture alpha" (which must be
 * defined before the shape). */
static hz_status shape_alpha(const shape_entity *se, const shape_geometry *g,
                             const texture_set *textures, geom_shape *out, hz_error *err)
{
    out->alpha = g->alpha;
    if (g->alpha_texture) {
        out->alpha_tex = textures ? texture_set_find(textures, g->alpha_texture, false) : NULL;
        if (!out->alpha_tex)
            return hz_fail_at(err, params_loc(&se->entity.params, "alpha"),
                              "\"texture alpha\": no float texture named \"%s\" "
                              "defined before it",
                              g->alpha_texture);
    }
    out->has_alpha = out->alpha_tex || out->alpha < 1.0;
    /* An alpha texture on an emitter is looked up at light samples too. */
    out->hit_uv |= out->alpha_tex != NULL;
    return HZ_OK;
}

/* The mesh's shading normals in the shape's space (out->n). */
static hz_status mesh_normals(const shape_entity *se, const shape_geometry *g,
                              transform space_from_object, geom_shape *out, hz_error *err)
{
    out->n = malloc(3 * g->vertex_count * sizeof(double));
    if (!out->n)
        return hz_fail(err, "out of memory");
    /* pbrt-v4's TriangleMesh flips given normals with ReverseOrientation
     * only (not with the handedness of the transform). */
    for (size_t i = 0; i < g->vertex_count; ++i) {
        vec3 n = transform_normal(&space_from_object,
                                  v3(g->n[3 * i], g->n[3 * i + 1], g->n[3 * i + 2]));
        if (se->reverse_orientation)
            n = v3_neg(n);
        out->n[3 * i] = n.x;
        out->n[3 * i + 1] = n.y;
        out->n[3 * i + 2] = n.z;
    }
    return HZ_OK;
}

/* A triangle mesh as Embree triangles: its vertices in the shape's space,
 * rounded to float once; the mesh's uv are taken from g. */
static hz_status build_triangles(RTCDevice device, const shape_entity *se, shape_geometry *g,
                                 transform space_from_object, geom_shape *out,
                                 RTCGeometry *geom_out, hz_error *err)
{
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *p = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), g->vertex_count);
    unsigned *idx = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                            3 * sizeof(unsigned), g->triangle_count);
    if (!p || !idx) {
        rtcReleaseGeometry(geom);
        return hz_fail_at(err, se->entity.loc, "out of memory for a mesh of %zu triangles",
                          g->triangle_count);
    }
    /* Transform in double, round once: render space keeps float precision
     * near the camera however far the scene is from the world origin. */
    for (size_t i = 0; i < g->vertex_count; ++i) {
        vec3 q = transform_point(&space_from_object,
                                 v3(g->p[3 * i], g->p[3 * i + 1], g->p[3 * i + 2]));
        p[3 * i] = (float)q.x;
        p[3 * i + 1] = (float)q.y;
        p[3 * i + 2] = (float)q.z;
    }
    for (size_t i = 0; i < 3 * g->triangle_count; ++i) {
        if (g->indices[i] >= g->vertex_count) {
            rtcReleaseGeometry(geom);
            return hz_fail_at(err, se->entity.loc, "vertex index %u out of range (%zu vertices)",
                              g->indices[i], g->vertex_count);
        }
        idx[i] = g->indices[i];
    }
    if (g->n && mesh_normals(se, g, space_from_object, out, err) != HZ_OK) {
        rtcReleaseGeometry(geom);
        return HZ_ERROR;
    }
    out->uv = g->uv; /* taken from g */
    g->uv = NULL;
    out->quads = g->quads;
    out->vertex_count = g->vertex_count;
    out->triangle_count = g->triangle_count;
    out->p = p;
    out->indices = idx;
    *geom_out = geom;
    return HZ_OK;
}

/* Sets the filters of the shape's geometry and attaches it to the scene,
 * which keeps it (and its buffers) alive. */
static void attach_shape(RTCScene scene, RTCGeometry geom, unsigned geom_id, geom_shape *out)
{
    bool interface = out->material->kind == MATERIAL_INTERFACE;
    if (out->has_alpha && out->kind == GEOMETRY_TRIANGLES) {
        rtcSetGeometryUserData(geom, out);
        rtcSetGeometryIntersectFilterFunction(geom, geom_alpha_filter);
        if (!interface)
            rtcSetGeometryOccludedFilterFunction(geom, geom_alpha_filter);
    }
    if (interface)
        rtcSetGeometryOccludedFilterFunction(geom, reject_occlusion);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene, geom, geom_id);
    rtcReleaseGeometry(geom);
}

hz_status geom_build_shape(RTCDevice device, RTCScene scene, unsigned geom_id,
                           const scene_desc *sd, shape_entity *se, transform space_from_object,
                           const material *materials, size_t material_count,
                           const material *default_material, const texture_set *textures,
                           geom_shape *out, hz_error *err)
{
    if (shape_material_media(sd, se, materials, material_count, default_material, out, err) !=
        HZ_OK)
        return HZ_ERROR;
    shape_geometry g;
    if (shape_geometry_create(se, &g, err) != HZ_OK)
        return HZ_ERROR;
    out->kind = g.kind;
    out->flip_normal = se->reverse_orientation ^ transform_swaps_handedness(&space_from_object);
    bool interface = out->material->kind == MATERIAL_INTERFACE;
    out->textured = material_has_textures(out->material);
    out->hit_uv = out->textured || material_needs_hair_frame(out->material);
    out->unit_area = g.unit_area;
    RTCGeometry geom = NULL;
    hz_status st = shape_alpha(se, &g, textures, out, err);
    if (st == HZ_OK && g.kind == GEOMETRY_SPHERE)
        geom = geom_build_sphere(device, &g, space_from_object, out);
    else if (st == HZ_OK && g.kind == GEOMETRY_CURVES)
        st = geom_build_curves(device, se, &g, space_from_object, interface, out, &geom, err);
    else if (st == HZ_OK && g.triangle_count > 0)
        st = build_triangles(device, se, &g, space_from_object, out, &geom, err);
    shape_geometry_free(&g);
    if (st != HZ_OK)
        return st;
    if (geom) /* else an empty mesh: nothing to intersect */
        attach_shape(scene, geom, geom_id, out);
    return HZ_OK;
}

hz_status geom_shape_failed(geom_shape *s, hz_errors *errs, hz_error *err)
{
    if (!errs || !err->loc.file)
        return HZ_ERROR;
    hz_errors_add(errs, err);
    s->left_out = true;
    s->area_light = -1;
    return HZ_OK;
}
