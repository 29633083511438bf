/* What the parser produces: the scene as pbrt-v4's directives described it,
 * with every entity's type name, typed parameters and transform, but before
 * any factory has interpreted the parameters. Factories (camera, film, sampler,
 * filter, shapes, lights, materials) read their own parameters from here and
 * report errors at the entity's place.
 *
 * Ownership: every `char *` below (entity types, names, media) points into
 * scene_desc.strings, as does every file_loc.file; param lists are owned by
 * their entity. scene_desc_free releases all of it.
 *
 * Motion: pbrt-v4 keeps two current transforms (TransformTimes/ActiveTransform).
 * The `*_end` transforms are the end-time ones; they equal the start ones
 * unless the scene used ActiveTransform EndTime/StartTime. */
#ifndef HAZE_SCENE_SCENE_DESC_H
#define HAZE_SCENE_SCENE_DESC_H

#include <stddef.h>
#include <stdint.h>

#include "core/color_space.h"
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
    transform camera_from_world_end; /* the CTM at Camera (end time) */
    char *medium;                /* outside medium current at Camera, "" = vacuum */
    double transform_start_time, transform_end_time; /* TransformTimes at Camera */
} camera_entity;

typedef struct {
    scene_entity entity;         /* "diffuse", "interface", ... */
    char *name;                  /* for MakeNamedMaterial; NULL for anonymous */
    /* A NamedMaterial met before its MakeNamedMaterial (pbrt-v4 resolves names
     * after the whole file): a "diffuse" stand-in at the NamedMaterial's place
     * until the definition fills it; one still pending at the end is an error. */
    bool pending;
} material_entity;

typedef struct {
    scene_entity entity;         /* shape type and its parameters */
    transform world_from_object; /* inside ObjectBegin/End: instance_from_object */
    transform world_from_object_end;
    bool reverse_orientation;
    int material;                /* index into scene_desc.materials, -1 = default diffuse 0.5 */
    bool has_area_light;
    scene_entity area_light;     /* AreaLightSource current at the shape, when has_area_light */
    char *inside_medium, *outside_medium; /* MediumInterface at the shape ("" = vacuum) */
} shape_entity;

typedef struct {
    scene_entity entity;
    transform world_from_light;
    transform world_from_light_end;
    char *medium;                /* outside medium at the LightSource */
} light_entity;

typedef struct {
    char *name;
    file_loc loc;
    size_t first_shape, shape_count; /* range in scene_desc.object_shapes */
} object_entity;

typedef struct {
    size_t object;               /* index into scene_desc.objects */
    transform world_from_instance; /* world_from_object of a shape = this * its own */
    transform world_from_instance_end;
    file_loc loc;
} instance_entity;

typedef struct {
    char *name;
    scene_entity entity;         /* "homogeneous", "nanovdb", ... */
    transform world_from_medium; /* start time (pbrt-v4 uses only this one) */
    transform world_from_medium_end; /* end time: haze moves media with it */
} medium_entity;

/* `Texture "name" "float"|"spectrum" "class" params`: entity.type is the
 * class. */
typedef struct {
    char *name;
    bool spectrum;               /* "spectrum" (rgb) or "float" */
    scene_entity entity;
    transform world_from_texture; /* the CTM at the directive */
} texture_entity;

typedef struct {
    /* Absent directives get default entities with the type pbrt-v4 uses
     * ("perspective", "rgb", "zsobol", "gaussian", "volpath", "bvh") and no
     * params; an absent Integrator or Accelerator has loc.line 0. */
    camera_entity camera;
    scene_entity film, sampler, filter, integrator;
    scene_entity accelerator; /* read and checked, but haze always builds Embree's BVH */
    color_space film_color_space; /* ColorSpace current at Film: the image's space */

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
    texture_entity *textures;    /* in file order */
    size_t texture_count;

    /* TransformTimes (defaults 0 and 1). */
    double transform_start_time, transform_end_time;
    /* Option directives ("bool disablepixeljitter" true, "integer seed" 3...):
     * typed parameters with pbrt-v4's option names; the renderer reads those it
     * honours with the params getters. */
    param_list options;

    /* Every file the parser read, in the order it opened them: the scene file
     * first, then each Include/Import (as named, relative to the working
     * directory; pointers into `strings`). Meshes and volumes are not here:
     * their entities name them. */
    const char **files;
    size_t file_count;

    /* Owned strings (file names, names) that file_loc.file and others point to. */
    char **strings;
    size_t string_count, string_capacity;

    /* What the parse accepted with a warning, whole "file:line:column:
     * warning: ..." lines (among `strings`), in the order met; printed when
     * the scene is built. */
    const char **warnings;
    size_t warning_count;
} scene_desc;

/* Parses `path` (and everything it includes). Follows pbrt-v4: shapes, lights,
 * materials, AttributeBegin/End and objects only after WorldBegin; Camera, Film,
 * Sampler, PixelFilter, Integrator and TransformTimes only before it, once each;
 * a file without WorldBegin is an error. Include and Import both read the file
 * in place with the current graphics state (haze does not isolate Import's
 * state as pbrt-v4 does); relative paths (here and in every
 * parameter that names a file) resolve against the top-level scene file's
 * directory, as in pbrt-v4. On error fills err with
 * "file:line:column: message" and returns HZ_ERROR; *out is then empty. */
hz_status scene_parse_file(const char *path, scene_desc *out, hz_error *err);
/* Parses text held in memory; `name` is used in diagnostics and as the base for
 * relative Include paths (its directory). */
hz_status scene_parse_string(const char *text, const char *name, scene_desc *out, hz_error *err);
/* The same, going on past errors: each error with a place is added to `errs`
 * and *out keeps what parsed (a directive that failed is left out), so the
 * caller can go on to find the scene's other problems (render_scene_check)
 * and report them together. HZ_ERROR, with *out empty, only when the file
 * cannot be read or memory runs out. Free *out either way on HZ_OK. */
hz_status scene_parse_file_all(const char *path, scene_desc *out, hz_errors *errs, hz_error *err);
hz_status scene_parse_string_all(const char *text, const char *name, scene_desc *out,
                                 hz_errors *errs, hz_error *err);
void scene_desc_free(scene_desc *sd);

/* For the parser (parser*.c). Both return false when out of memory; sd can
 * still be freed with scene_desc_free. */
bool scene_desc_init(scene_desc *sd, const char *file);
/* Records a file the parser read; `owned_name` must point into sd->strings. */
bool scene_desc_add_file(scene_desc *sd, const char *owned_name);
/* A copy of `s` owned by sd->strings (NULL when out of memory). */
char *scene_desc_own(scene_desc *sd, const char *s);

/* Every file a render of `sd` reads, as paths relative to the working
 * directory: sd->files (the scene and its includes), then the "filename" of
 * each plymesh, nanovdb medium, image light (infinite, goniometric,
 * projection) and imagemap texture. Free with scene_input_files_free. */
hz_status scene_input_files(const scene_desc *sd, char ***files, size_t *count, hz_error *err);
void scene_input_files_free(char **files, size_t count);
/* A hash of the bytes of every file scene_input_files lists, in order: what
 * makes two renders of "the same scene" the same (MPI ranks, merged parts). */
hz_status scene_inputs_hash(const scene_desc *sd, uint64_t *hash, hz_error *err);

/* The index in sd->media of the medium called `name`; -1 for "" or NULL
 * (vacuum), SCENE_MEDIUM_UNDEFINED when no MakeNamedMedium defines it. */
#define SCENE_MEDIUM_UNDEFINED (-2)
int scene_find_medium(const scene_desc *sd, const char *name);

#endif
