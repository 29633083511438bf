#include <stdlib.h>
#include <string.h>

#include "scene/mem.h"
#include "scene/scene_desc.h"

char *scene_desc_own(scene_desc *sd, const char *s)
{
    char **grown = scene_grow(sd->strings, &sd->string_capacity, sd->string_count,
                              sizeof *sd->strings);
    if (!grown)
        return NULL;
    sd->strings = grown;
    char *copy = scene_strdup(s);
    if (copy)
        sd->strings[sd->string_count++] = copy;
    return copy;
}

static bool default_entity(scene_desc *sd, scene_entity *e, const char *type, file_loc loc)
{
    e->type = scene_desc_own(sd, type);
    e->loc = loc;
    params_init(&e->params, loc);
    return e->type != NULL;
}

bool scene_desc_init(scene_desc *sd, const char *file)
{
    memset(sd, 0, sizeof *sd);
    sd->camera.camera_from_world = transform_identity();
    sd->camera.camera_from_world_end = transform_identity();
    sd->camera.transform_start_time = 0.0;
    sd->camera.transform_end_time = 1.0;
    sd->transform_start_time = 0.0;
    sd->transform_end_time = 1.0;
    file_loc start = {scene_desc_own(sd, file), 1, 1, NULL};
    /* Line 0: no Integrator directive (haze then renders with singlescatter). */
    file_loc no_integrator = {start.file, 0, 0, NULL};
    params_init(&sd->options, start);
    if (!start.file || !scene_desc_add_file(sd, start.file))
        return false;
    sd->camera.medium = scene_desc_own(sd, "");
    return sd->camera.medium && default_entity(sd, &sd->camera.entity, "perspective", start) &&
           default_entity(sd, &sd->film, "rgb", start) &&
           default_entity(sd, &sd->sampler, "zsobol", start) &&
           default_entity(sd, &sd->filter, "gaussian", start) &&
           default_entity(sd, &sd->integrator, "volpath", no_integrator) &&
           default_entity(sd, &sd->accelerator, "bvh", no_integrator);
}

bool scene_desc_add_file(scene_desc *sd, const char *owned_name)
{
    const char **grown = scene_grow_implicit(sd->files, sd->file_count, sizeof *sd->files);
    if (!grown)
        return false;
    sd->files = grown;
    sd->files[sd->file_count++] = owned_name;
    return true;
}

static void free_shapes(shape_entity *s, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        params_free(&s[i].entity.params);
        if (s[i].has_area_light)
            params_free(&s[i].area_light.params);
    }
    free(s);
}

void scene_desc_free(scene_desc *sd)
{
    params_free(&sd->camera.entity.params);
    params_free(&sd->film.params);
    params_free(&sd->sampler.params);
    params_free(&sd->filter.params);
    params_free(&sd->integrator.params);
    params_free(&sd->accelerator.params);
    params_free(&sd->options);
    free_shapes(sd->shapes, sd->shape_count);
    free_shapes(sd->object_shapes, sd->object_shape_count);
    free(sd->objects);
    free(sd->instances);
    for (size_t i = 0; i < sd->material_count; ++i)
        params_free(&sd->materials[i].entity.params);
    free(sd->materials);
    free(sd->warnings);
    for (size_t i = 0; i < sd->light_count; ++i)
        params_free(&sd->lights[i].entity.params);
    free(sd->lights);
    for (size_t i = 0; i < sd->medium_count; ++i)
        params_free(&sd->media[i].entity.params);
    free(sd->media);
    for (size_t i = 0; i < sd->texture_count; ++i)
        params_free(&sd->textures[i].entity.params);
    free(sd->textures);
    for (size_t i = 0; i < sd->string_count; ++i)
        free(sd->strings[i]);
    free(sd->strings);
    free(sd->files);
    memset(sd, 0, sizeof *sd);
}

int scene_find_medium(const scene_desc *sd, const char *name)
{
    if (!name || !name[0])
        return -1;
    for (size_t i = 0; i < sd->medium_count; ++i)
        if (strcmp(sd->media[i].name, name) == 0)
            return (int)i;
    return SCENE_MEDIUM_UNDEFINED;
}
