/* What the parser produces: the scene as pbrt-v4's directives described it,
 * with every entity's type name, typed parameters and transform, but before
 * any factory has interpreted the parameters. Factories (camera, film, sampler,
 * filter, shapes, lights, materials) read their own parameters from here and
 * report errors at the entity's place. */
#ifndef HAZE_SCENE_SCENE_DESC_H
#define HAZE_SCENE_SCENE_DESC_H

#include <stddef.h>

#include "core/error.h"
#include "core/transform.h"
#include "scene/params.h"

typedef struct {
    char *type;        /* e.g. "perspective", "rgb", "trianglemesh", "point" */
    param_list params;
    file_loc loc;      /* the directive's keyword */
} scene_entity;

typedef struct {
    scene_entity entity;
    transform camera_from_world; /* the CTM at Camera (start time) */
    char *medium;                /* outside medium current at Camera, "" = vacuum */
} camera_entity;

typedef struct {
    scene_entity entity;         /* "diffuse", "interface", ... */
    char *name;                  /* for MakeNamedMaterial; NULL for anonymous */
} material_entity;

typedef struct {
    scene_entity entity;         /* shape type and its parameters */
    transform world_from_object;
    bool reverse_orientation;
    int material;                /* index into scene_desc.materials, -1 = default diffuse 0.5 */
    bool has_area_light;
    scene_entity area_light;     /* AreaLightSource current at the shape, when has_area_light */
    char *inside_medium, *outside_medium; /* MediumInterface at the shape ("" = vacuum) */
} shape_entity;

typedef struct {
    scene_entity entity;
    transform world_from_light;
    char *medium;                /* outside medium at the LightSource */
} light_entity;

typedef struct {
    char *name;
    file_loc loc;
    size_t first_shape, shape_count; /* range in scene_desc.object_shapes */
} object_entity;

typedef struct {
    size_t object;               /* index into scene_desc.objects */
    transform world_from_instance;
    file_loc loc;
} instance_entity;

typedef struct {
    char *name;
    scene_entity entity;         /* "homogeneous", "nanovdb", ... */
    transform world_from_medium;
} medium_entity;

typedef struct {
    /* Absent directives get default entities with the type pbrt-v4 uses
     * ("perspective", "rgb", "zsobol", "gaussian", "volpath") and no params. */
    camera_entity camera;
    scene_entity film, sampler, filter, integrator;

    shape_entity *shapes;        /* top-level shapes, in file order */
    size_t shape_count;
    shape_entity *object_shapes; /* shapes inside ObjectBegin/End */
    size_t object_shape_count;
    object_entity *objects;
    size_t object_count;
    instance_entity *instances;
    size_t instance_count;
    material_entity *materials;
    size_t material_count;
    light_entity *lights;
    size_t light_count;
    medium_entity *media;
    size_t medium_count;

    /* Owned strings (file names, names) that file_loc.file and others point to. */
    char **strings;
    size_t string_count;
} scene_desc;

/* Parses `path` (and everything it includes). On error fills err with
 * "file:line:column: message" and returns HZ_ERROR; *out is then empty. */
hz_status scene_parse_file(const char *path, scene_desc *out, hz_error *err);
/* Parses text held in memory; `name` is used in diagnostics and as the base for
 * relative Include paths (its directory). */
hz_status scene_parse_string(const char *text, const char *name, scene_desc *out, hz_error *err);
void scene_desc_free(scene_desc *sd);

#endif
