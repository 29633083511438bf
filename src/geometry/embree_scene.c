/* The geometry's Embree device and top-level scene: geometry_create and
 * geometry_destroy, the top-level shapes (objects, instances and motion:
 * instances.c), the box around everything static, and what the rest of haze
 * asks of the geometry as a whole. */
#include "geometry/convex_mesh.h"
#include "geometry/embree_device.h"
#include "geometry/geometry_types.h"
#include "geometry/instances.h"
#include "geometry/medium_interface.h"
#include "geometry/shape_build.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

static bool embree_memory(void *user, ssize_t bytes, bool post)
{
    (void)post;
    geometry *g = user;
    long long now = atomic_fetch_add(&g->embree_bytes, (long long)bytes) + bytes;
    long long peak = atomic_load(&g->embree_peak);
    while (now > peak && !atomic_compare_exchange_weak(&g->embree_peak, &peak, now))
        ;
    return true;
}

size_t geometry_embree_peak_bytes(const geometry *g)
{
    long long p = atomic_load(&((geometry *)g)->embree_peak);
    return p > 0 ? (size_t)p : 0;
}

static hz_status build_shapes(geometry *g, scene_desc *sd, transform render_from_world,
                              const material *materials, size_t material_count,
                              const material *default_material, hz_errors *errs, hz_error *err)
{
    for (size_t i = 0; i < sd->shape_count; ++i) {
        shape_entity *se = &sd->shapes[i];
        transform render_from_object = transform_compose(render_from_world, se->world_from_object);
        if (geom_moves(&se->world_from_object, &se->world_from_object_end)) {
            animated_transform a = animated_transform_make(
                render_from_object, sd->transform_start_time,
                transform_compose(render_from_world, se->world_from_object_end),
                sd->transform_end_time);
            if (a.animated) {
                if (!g->shape_instances) {
                    g->shape_instances = calloc(sd->shape_count, sizeof *g->shape_instances);
                    if (!g->shape_instances)
                        return hz_fail(err, "out of memory");
                }
                if (geom_build_moving_shape(g, sd, i, &a, materials, material_count,
                                            default_material, err) != HZ_OK &&
                    geom_shape_failed(&g->shapes[i], errs, err) != HZ_OK)
                    return HZ_ERROR;
                continue;
            }
        }
        if (geom_build_shape(g->device, g->scene, (unsigned)i, sd, se, render_from_object,
                             materials, material_count, default_material, g->textures,
                             &g->shapes[i], err) != HZ_OK &&
            geom_shape_failed(&g->shapes[i], errs, err) != HZ_OK)
            return HZ_ERROR;
    }
    return HZ_OK;
}

/* Scenes of at most this many primitives build their BVH on the calling
 * thread (Embree's "threads=1"): Embree's task scheduler starting its worker
 * threads for the first build took a median 4.7 ms with a 12-triangle
 * scene, the device and the build 1.2 ms in all without them (40 runs each),
 * and the workers then spin beside the render threads. A build this small
 * takes well under a millisecond on one thread. */
enum { GEOMETRY_SMALL_SCENE = 10000 };

/* The primitives the scene's shapes give Embree, at most, or SIZE_MAX when
 * some shape's count is unknown before it is built (a PLY file, a
 * subdivision surface, ...). Reads the parameters without marking them used. */
static size_t primitive_bound(const scene_desc *sd)
{
    size_t n = sd->instance_count;
    for (size_t i = 0; i < sd->shape_count + sd->object_shape_count; ++i) {
        const scene_entity *e = i < sd->shape_count ? &sd->shapes[i].entity
                                                    : &sd->object_shapes[i - sd->shape_count].entity;
        /* A mesh has fewer triangles than index values; a curve fewer
         * segments than control point coordinates, each cut into at most
         * 2^8 pieces (its "splitdepth"). */
        const char *count_of = NULL;
        int shift = 0;
        if (strcmp(e->type, "trianglemesh") == 0 || strcmp(e->type, "bilinearmesh") == 0) {
            count_of = "indices";
        } else if (strcmp(e->type, "curve") == 0) {
            count_of = "P";
            shift = 8;
        } else if (strcmp(e->type, "sphere") != 0) {
            return SIZE_MAX;
        }
        size_t k = 1;
        for (size_t j = 0; count_of && j < e->params.count; ++j)
            if (strcmp(e->params.items[j].name, count_of) == 0)
                k = e->params.items[j].count;
        n += k << shift;
    }
    return n;
}

static RTCDevice new_device(bool portable_isa, bool small)
{
    /* Embree's choice is the widest ISA the CPU has (AVX-512 here: 12% faster
     * than SSE4.2 on bench/scenes/surfaces.pbrt). Hit points are recomputed
     * in double (geom_surface_at), so an ISA changes an image only where rays
     * graze a shared edge; pinning SSE4.2 removes even that across machines.
     * Fall back to Embree's choice on a CPU without SSE4.2. */
    RTCDevice d = NULL;
    if (portable_isa)
        d = rtcNewDevice(small ? "isa=sse4.2,threads=1" : "isa=sse4.2");
    if (!d && small)
        d = rtcNewDevice("threads=1");
    return d ? d : rtcNewDevice(NULL);
}

/* The world box, when nothing moves (Embree's bounds of the scene, padded
 * as the interface boxes). An empty scene has an empty box. */
static void find_world_box(geometry *g)
{
    if (g->motion)
        return;
    struct RTCBounds b;
    rtcGetSceneBounds(g->scene, &b);
    vec3 lo = v3(b.lower_x, b.lower_y, b.lower_z), hi = v3(b.upper_x, b.upper_y, b.upper_z);
    g->has_world_box = true;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) {
        g->world_box[0] = v3(1.0, 1.0, 1.0);
        g->world_box[1] = v3(-1.0, -1.0, -1.0);
        return;
    }
    double pad = 1e-5 * v3_max_component(v3_max(v3_abs(lo), v3_abs(hi))) + 1e-30;
    vec3 d = v3(pad, pad, pad);
    g->world_box[0] = v3_sub(lo, d);
    g->world_box[1] = v3_add(hi, d);
}


bool geometry_static_box(const geometry *g, vec3 *lo, vec3 *hi)
{
    *lo = g->world_box[0];
    *hi = g->world_box[1];
    return g->has_world_box;
}

hz_status geometry_create(scene_desc *sd, transform render_from_world, const material *materials,
                          size_t material_count, const material *default_material,
                          const texture_set *textures, bool portable_isa, hz_errors *errs,
                          geometry **out, hz_error *err)
{
    *out = NULL;
    geometry *g = calloc(1, sizeof *g);
    if (!g)
        return hz_fail(err, "out of memory");
    g->start_time = sd->transform_start_time;
    g->end_time = sd->transform_end_time;
    g->textures = textures;
    g->device = new_device(portable_isa, primitive_bound(sd) <= GEOMETRY_SMALL_SCENE);
    if (!g->device) {
        free(g);
        return hz_fail(err, "cannot create the Embree device (error %d)",
                       (int)rtcGetDeviceError(NULL));
    }
    rtcSetDeviceMemoryMonitorFunction(g->device, embree_memory, g);
    g->scene = geom_new_scene(g->device);
    if (!g->scene) {
        hz_status st = geom_new_scene_failed(g->device, err);
        geometry_destroy(g);
        return st;
    }
    g->shapes = calloc(sd->shape_count ? sd->shape_count : 1, sizeof *g->shapes);
    if (!g->shapes) {
        geometry_destroy(g);
        return hz_fail(err, "out of memory");
    }
    g->shape_count = sd->shape_count;
    if (build_shapes(g, sd, render_from_world, materials, material_count, default_material, errs,
                     err) != HZ_OK ||
        geom_build_objects(g, sd, materials, material_count, default_material, errs, err) !=
            HZ_OK ||
        geom_build_instances(g, sd, render_from_world, err) != HZ_OK) {
        geometry_destroy(g);
        return HZ_ERROR;
    }
    rtcCommitScene(g->scene);
    find_world_box(g);
    if (geom_check_device(g->device, err) != HZ_OK || geom_find_interfaces(g, err) != HZ_OK ||
        geom_find_convex_interfaces(g, sd->medium_count, err) != HZ_OK) {
        geometry_destroy(g);
        return HZ_ERROR;
    }
    *out = g;
    return HZ_OK;
}

static void free_shape_arrays(geom_shape *s)
{
    free(s->planes);
    free(s->faces);
    free(s->face_tris);
    free(s->convex_tris);
    free(s->n);
    free(s->uv);
    free(s->curve_cp);
    free(s->curve_w);
    free(s->curve_n);
}

void geometry_destroy(geometry *g)
{
    if (!g)
        return;
    for (size_t i = 0; i < g->shape_count; ++i)
        free_shape_arrays(&g->shapes[i]);
    free(g->shapes);
    if (g->shape_instances) {
        for (size_t i = 0; i < g->shape_count; ++i) {
            instance *in = g->shape_instances[i];
            if (!in)
                continue;
            free(in->motion.steps);
            if (in->own_scene)
                rtcReleaseScene(in->own_scene);
            free(in);
        }
        free(g->shape_instances);
    }
    for (size_t o = 0; o < g->object_count; ++o) {
        for (size_t i = 0; i < g->objects[o].shape_count; ++i)
            free_shape_arrays(&g->objects[o].shapes[i]);
        free(g->objects[o].shapes);
        if (g->objects[o].scene)
            rtcReleaseScene(g->objects[o].scene);
    }
    free(g->objects);
    for (size_t i = 0; i < g->instance_count; ++i)
        free(g->instances[i].motion.steps);
    free(g->instances);
    free(g->interface_boxes);
    free(g->convex_around);
    if (g->scene)
        rtcReleaseScene(g->scene);
    if (g->device)
        rtcReleaseDevice(g->device);
    free(g);
}

struct RTCSceneTy *geometry_embree_scene(const geometry *g) { return g->scene; }

bool geometry_has_motion(const geometry *g) { return g->motion; }

static bool shapes_reference_media(const geom_shape *shapes, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!shapes[i].left_out && (shapes[i].medium_inside >= 0 || shapes[i].medium_outside >= 0))
            return true;
    return false;
}

bool geometry_references_media(const geometry *g)
{
    if (shapes_reference_media(g->shapes, g->shape_count))
        return true;
    for (size_t i = 0; i < g->object_count; ++i)
        if (shapes_reference_media(g->objects[i].shapes, g->objects[i].shape_count))
            return true;
    return false;
}

size_t geometry_shape_count(const geometry *g) { return g->shape_count; }
geom_shape *geometry_shape(geometry *g, size_t i) { return &g->shapes[i]; }

void geometry_require_uv(geometry *g)
{
    for (size_t i = 0; i < g->shape_count; ++i)
        g->shapes[i].hit_uv = true;
    for (size_t o = 0; o < g->object_count; ++o)
        for (size_t i = 0; i < g->objects[o].shape_count; ++i)
            g->objects[o].shapes[i].hit_uv = true;
}
