/* Directives that create entities (Camera, Shape, LightSource, materials,
 * media, objects) or set what later entities receive (NamedMaterial,
 * AreaLightSource, MediumInterface, Attribute). pbrt-v4 semantics. */
#include <assert.h>
#include <stdio.h>
#include <string.h>

#include "scene/mem.h"
#include "scene/parser_entities.h"
#include "scene/parser_params.h"
#include "scene/parser_state.h"
#include "scene/parser_tokens.h"

#define ATTR_NONE (-1)

/* `Directive "type" params...`; attribute defaults of kind `attr` are merged in. */
static hz_status read_entity(parser *ps, const token *d, int attr, scene_entity *e, hz_error *err)
{
    const char *type;
    memset(e, 0, sizeof *e);
    params_init(&e->params, d->loc);
    if (parser_string_arg(ps, d, &type, err) != HZ_OK)
        return HZ_ERROR;
    e->type = (char *)type;
    e->loc = d->loc;
    if (parser_params(ps, &e->params, d->loc, err) != HZ_OK) {
        params_free(&e->params);
        return HZ_ERROR;
    }
    if (attr != ATTR_NONE && params_add_defaults(&e->params, &ps->gs.attrs[attr], err) != HZ_OK) {
        params_free(&e->params);
        return parser_oom(ps, d->loc, err);
    }
    return HZ_OK;
}

/* `Directive "name" params...` where the type is the "string type" parameter. */
static hz_status read_named(parser *ps, const token *d, const char *what, int attr,
                            const char **name, scene_entity *e, hz_error *err)
{
    memset(e, 0, sizeof *e);
    params_init(&e->params, d->loc);
    if (parser_string_arg(ps, d, name, err) != HZ_OK)
        return HZ_ERROR;
    ps->defining.kind = attr == ATTR_MEDIUM ? 'M' : 'm';
    ps->defining.name = *name;
    ps->defining.loc = d->loc;
    e->loc = d->loc;
    if (parser_params(ps, &e->params, d->loc, err) != HZ_OK)
        goto fail;
    if (params_add_defaults(&e->params, &ps->gs.attrs[attr], err) != HZ_OK) {
        parser_oom(ps, d->loc, err);
        goto fail;
    }
    const char *type = params_string(&e->params, "type", NULL);
    if (e->params.failed) {
        params_failure(&e->params, err);
        goto fail;
    }
    if (!type) {
        hz_fail_at(err, d->loc, "%s \"%s\" has no \"string type\" parameter", what, *name);
        goto fail;
    }
    e->type = (char *)parser_intern(ps, type);
    if (!e->type) {
        parser_oom(ps, d->loc, err);
        goto fail;
    }
    /* The factory must not see "type" as an unused parameter. */
    params_remove(&e->params, "type");
    return HZ_OK;
fail:
    params_free(&e->params);
    return HZ_ERROR;
}

static hz_status d_options_entity(parser *ps, const token *d, const char *what, file_loc *seen,
                                  scene_entity *slot, hz_error *err)
{
    scene_entity e;
    if (parser_need_options(ps, d, what, seen, err) != HZ_OK ||
        read_entity(ps, d, ATTR_NONE, &e, err) != HZ_OK)
        return HZ_ERROR;
    params_free(&slot->params);
    *slot = e;
    return HZ_OK;
}

static hz_status d_camera(parser *ps, const token *d, hz_error *err)
{
    camera_entity *c = &ps->sd->camera;
    if (d_options_entity(ps, d, "Camera", &ps->seen_camera, &c->entity, err) != HZ_OK)
        return HZ_ERROR;
    c->camera_from_world = ps->gs.ctm[0];
    c->camera_from_world_end = ps->gs.ctm[1];
    c->medium = (char *)ps->gs.outside;
    c->transform_start_time = ps->sd->transform_start_time;
    c->transform_end_time = ps->sd->transform_end_time;
    /* pbrt-v4: namedCoordinateSystems["camera"] = Inverse(cameraFromWorld). */
    transform world_from_camera[2] = {transform_inverse(ps->gs.ctm[0]),
                                      transform_inverse(ps->gs.ctm[1])};
    return parser_set_coordsys(ps, "camera", world_from_camera, d->loc, err);
}

/* Appends s to the object being defined, else to the top-level shapes; false
 * when out of memory (s is then still the caller's). */
static bool add_shape(parser *ps, const shape_entity *s)
{
    scene_desc *sd = ps->sd;
    if (ps->current_object >= 0) {
        shape_entity *grown = scene_grow_implicit(sd->object_shapes, sd->object_shape_count,
                                                  sizeof *sd->object_shapes);
        if (!grown)
            return false;
        sd->object_shapes = grown;
        sd->object_shapes[sd->object_shape_count++] = *s;
        sd->objects[ps->current_object].shape_count++;
    } else {
        shape_entity *grown = scene_grow_implicit(sd->shapes, sd->shape_count, sizeof *sd->shapes);
        if (!grown)
            return false;
        sd->shapes = grown;
        sd->shapes[sd->shape_count++] = *s;
    }
    return true;
}

static hz_status d_shape(parser *ps, const token *d, hz_error *err)
{
    shape_entity s;
    memset(&s, 0, sizeof s);
    if (parser_need_world(ps, d, "Shape", err) != HZ_OK)
        return HZ_ERROR;
    if (ps->gs.has_area_light && ps->current_object >= 0)
        return hz_fail_at(err, d->loc,
                          "area lights are not supported inside ObjectBegin/ObjectEnd (the "
                          "AreaLightSource at %s:%d:%d applies here)",
                          ps->gs.area_light.loc.file, ps->gs.area_light.loc.line,
                          ps->gs.area_light.loc.column);
    if (read_entity(ps, d, ATTR_SHAPE, &s.entity, err) != HZ_OK)
        return HZ_ERROR;
    s.world_from_object = ps->gs.ctm[0];
    s.world_from_object_end = ps->gs.ctm[1];
    s.reverse_orientation = ps->gs.reverse_orientation;
    s.material = ps->gs.material;
    s.inside_medium = (char *)ps->gs.inside;
    s.outside_medium = (char *)ps->gs.outside;
    if (ps->gs.has_area_light) {
        s.area_light = ps->gs.area_light;
        if (!params_copy(&s.area_light.params, &ps->gs.area_light.params)) {
            params_free(&s.entity.params);
            return parser_oom(ps, d->loc, err);
        }
        s.has_area_light = true;
    }
    if (add_shape(ps, &s))
        return HZ_OK;
    params_free(&s.entity.params);
    if (s.has_area_light)
        params_free(&s.area_light.params);
    return parser_oom(ps, d->loc, err);
}

static hz_status d_light(parser *ps, const token *d, hz_error *err)
{
    scene_desc *sd = ps->sd;
    light_entity l;
    memset(&l, 0, sizeof l);
    if (parser_need_world(ps, d, "LightSource", err) != HZ_OK ||
        read_entity(ps, d, ATTR_LIGHT, &l.entity, err) != HZ_OK)
        return HZ_ERROR;
    l.world_from_light = ps->gs.ctm[0];
    l.world_from_light_end = ps->gs.ctm[1];
    l.medium = (char *)ps->gs.outside;
    light_entity *grown = scene_grow_implicit(sd->lights, sd->light_count, sizeof *sd->lights);
    if (!grown) {
        params_free(&l.entity.params);
        return parser_oom(ps, d->loc, err);
    }
    sd->lights = grown;
    sd->lights[sd->light_count++] = l;
    return HZ_OK;
}

static hz_status d_area_light(parser *ps, const token *d, hz_error *err)
{
    scene_entity e;
    if (parser_need_world(ps, d, "AreaLightSource", err) != HZ_OK ||
        read_entity(ps, d, ATTR_LIGHT, &e, err) != HZ_OK)
        return HZ_ERROR;
    if (ps->gs.has_area_light)
        params_free(&ps->gs.area_light.params);
    ps->gs.area_light = e;
    ps->gs.has_area_light = true;
    return HZ_OK;
}

/* Takes m (frees it when out of memory, the only failure); *index (may be
 * NULL) is where it went in sd->materials. */
static hz_status add_material(parser *ps, const token *d, material_entity m, int *index,
                              hz_error *err)
{
    scene_desc *sd = ps->sd;
    material_entity *grown =
        scene_grow_implicit(sd->materials, sd->material_count, sizeof *sd->materials);
    if (!grown) {
        params_free(&m.entity.params);
        return parser_oom(ps, d->loc, err);
    }
    sd->materials = grown;
    if (index)
        *index = (int)sd->material_count;
    sd->materials[sd->material_count++] = m;
    return HZ_OK;
}

static hz_status d_material(parser *ps, const token *d, hz_error *err)
{
    material_entity m;
    memset(&m, 0, sizeof m);
    if (parser_need_world(ps, d, "Material", err) != HZ_OK ||
        read_entity(ps, d, ATTR_MATERIAL, &m.entity, err) != HZ_OK)
        return HZ_ERROR;
    return add_material(ps, d, m, &ps->gs.material, err);
}

/* Takes t (frees it when out of memory, the only failure). */
static hz_status add_texture(parser *ps, const token *d, texture_entity t, hz_error *err)
{
    scene_desc *sd = ps->sd;
    texture_entity *grown =
        scene_grow_implicit(sd->textures, sd->texture_count, sizeof *sd->textures);
    if (!grown) {
        params_free(&t.entity.params);
        return parser_oom(ps, d->loc, err);
    }
    sd->textures = grown;
    sd->textures[sd->texture_count++] = t;
    return HZ_OK;
}

/* Takes m (frees it when out of memory, the only failure). */
static hz_status add_medium(parser *ps, const token *d, medium_entity m, hz_error *err)
{
    scene_desc *sd = ps->sd;
    medium_entity *grown = scene_grow_implicit(sd->media, sd->medium_count, sizeof *sd->media);
    if (!grown) {
        params_free(&m.entity.params);
        return parser_oom(ps, d->loc, err);
    }
    sd->media = grown;
    sd->media[sd->medium_count++] = m;
    return HZ_OK;
}

/* `Texture "name" "float"|"spectrum" "class" params...`; a name may be
 * redefined for the other value type only (as pbrt-v4). */
static hz_status d_texture(parser *ps, const token *d, hz_error *err)
{
    const char *name, *value_type;
    if (parser_need_world(ps, d, "Texture", err) != HZ_OK ||
        parser_string_arg(ps, d, &name, err) != HZ_OK ||
        parser_string_arg(ps, d, &value_type, err) != HZ_OK)
        return HZ_ERROR;
    bool spectrum = strcmp(value_type, "spectrum") == 0;
    if (!spectrum && strcmp(value_type, "float") != 0)
        return hz_fail_at(err, d->loc, "Texture \"%s\": type \"%s\" must be \"float\" or "
                          "\"spectrum\"", name, value_type);
    ps->defining.kind = 't';
    ps->defining.name = name;
    ps->defining.spectrum = spectrum;
    ps->defining.loc = d->loc;
    scene_desc *sd = ps->sd;
    for (size_t i = 0; i < sd->texture_count; ++i)
        if (sd->textures[i].spectrum == spectrum && strcmp(sd->textures[i].name, name) == 0) {
            file_loc at = sd->textures[i].entity.loc;
            return hz_fail_at(err, d->loc, "Texture \"%s\" redefined (first at %s:%d:%d)", name,
                              at.file, at.line, at.column);
        }
    texture_entity t = {.name = (char *)name, .spectrum = spectrum,
                        .world_from_texture = ps->gs.ctm[0]};
    if (read_entity(ps, d, ATTR_TEXTURE, &t.entity, err) != HZ_OK)
        return HZ_ERROR;
    return add_texture(ps, d, t, err);
}

static long find_named_material(const scene_desc *sd, const char *name)
{
    for (size_t i = 0; i < sd->material_count; ++i)
        if (sd->materials[i].name && strcmp(sd->materials[i].name, name) == 0)
            return (long)i;
    return -1;
}

static hz_status d_make_named_material(parser *ps, const token *d, hz_error *err)
{
    material_entity m;
    const char *name;
    memset(&m, 0, sizeof m);
    if (parser_need_world(ps, d, "MakeNamedMaterial", err) != HZ_OK ||
        read_named(ps, d, "MakeNamedMaterial", ATTR_MATERIAL, &name, &m.entity, err) != HZ_OK)
        return HZ_ERROR;
    long old = find_named_material(ps->sd, name);
    if (old >= 0 && ps->sd->materials[old].pending) { /* used before: fill its place */
        material_entity *p = &ps->sd->materials[old];
        params_free(&p->entity.params);
        p->entity = m.entity;
        p->pending = false;
        return HZ_OK;
    }
    if (old >= 0) {
        file_loc at = ps->sd->materials[old].entity.loc;
        params_free(&m.entity.params);
        return hz_fail_at(err, d->loc, "named material \"%s\" redefined (first at %s:%d:%d)", name,
                          at.file, at.line, at.column);
    }
    m.name = (char *)name;
    return add_material(ps, d, m, NULL, err);
}

static hz_status d_named_material(parser *ps, const token *d, hz_error *err)
{
    const char *name;
    if (parser_need_world(ps, d, "NamedMaterial", err) != HZ_OK ||
        parser_string_arg(ps, d, &name, err) != HZ_OK)
        return HZ_ERROR;
    long i = find_named_material(ps->sd, name);
    if (i >= 0) {
        ps->gs.material = (int)i;
        return HZ_OK;
    }
    /* Defined later, as pbrt-v4 allows: a pending place for it. */
    material_entity m = {.entity = {.loc = d->loc}, .name = (char *)name, .pending = true};
    params_init(&m.entity.params, d->loc);
    m.entity.type = (char *)parser_intern(ps, "diffuse");
    if (!m.entity.type)
        return parser_oom(ps, d->loc, err);
    return add_material(ps, d, m, &ps->gs.material, err);
}

void parser_report_pending_materials(const parser *ps, hz_errors *errs)
{
    const scene_desc *sd = ps->sd;
    for (size_t i = 0; i < sd->material_count; ++i)
        if (sd->materials[i].pending) {
            hz_error err;
            hz_fail_at(&err, sd->materials[i].entity.loc,
                       "NamedMaterial \"%s\": no MakeNamedMaterial defines it", sd->materials[i].name);
            hz_errors_add(errs, &err);
        }
}

static hz_status d_make_named_medium(parser *ps, const token *d, hz_error *err)
{
    scene_desc *sd = ps->sd;
    medium_entity m;
    const char *name;
    memset(&m, 0, sizeof m);
    if (read_named(ps, d, "MakeNamedMedium", ATTR_MEDIUM, &name, &m.entity, err) != HZ_OK)
        return HZ_ERROR;
    for (size_t i = 0; i < sd->medium_count; ++i) {
        if (strcmp(sd->media[i].name, name) == 0) {
            file_loc at = sd->media[i].entity.loc;
            params_free(&m.entity.params);
            return hz_fail_at(err, d->loc, "named medium \"%s\" redefined (first at %s:%d:%d)",
                              name, at.file, at.line, at.column);
        }
    }
    if (name[0] == '\0') {
        params_free(&m.entity.params);
        return hz_fail_at(err, d->loc, "a medium cannot be named \"\" (that means vacuum)");
    }
    m.name = (char *)name;
    m.world_from_medium = ps->gs.ctm[0];
    m.world_from_medium_end = ps->gs.ctm[1];
    return add_medium(ps, d, m, err);
}

static bool medium_defined(const scene_desc *sd, const char *name)
{
    for (size_t i = 0; i < sd->medium_count; ++i)
        if (strcmp(sd->media[i].name, name) == 0)
            return true;
    return false;
}

static bool texture_defined(const scene_desc *sd, const char *name, bool spectrum)
{
    for (size_t i = 0; i < sd->texture_count; ++i)
        if (sd->textures[i].spectrum == spectrum && strcmp(sd->textures[i].name, name) == 0)
            return true;
    return false;
}

void parser_define_stand_in(parser *ps)
{
    scene_desc *sd = ps->sd;
    const char *name = ps->defining.name;
    scene_entity e = {.loc = ps->defining.loc};
    params_init(&e.params, e.loc);
    const token d = {.loc = e.loc};
    hz_error err;
    switch (ps->defining.kind) {
    case 'm': {
        long old = find_named_material(sd, name);
        if (old >= 0) { /* a pending use keeps its diffuse stand-in, now defined */
            sd->materials[old].pending = false;
            return;
        }
        e.type = (char *)parser_intern(ps, "diffuse");
        if (e.type)
            add_material(ps, &d, (material_entity){.entity = e, .name = (char *)name}, NULL,
                         &err);
        return;
    }
    case 'M':
        if (name[0] == '\0' || medium_defined(sd, name))
            return;
        e.type = (char *)parser_intern(ps, "homogeneous");
        if (e.type)
            add_medium(ps, &d, (medium_entity){.entity = e, .name = (char *)name,
                                               .world_from_medium = transform_identity(),
                                               .world_from_medium_end = transform_identity()},
                       &err);
        return;
    case 't':
        if (texture_defined(sd, name, ps->defining.spectrum))
            return;
        e.type = (char *)parser_intern(ps, "constant");
        if (e.type)
            add_texture(ps, &d,
                        (texture_entity){.entity = e, .name = (char *)name,
                                         .spectrum = ps->defining.spectrum,
                                         .world_from_texture = transform_identity()},
                        &err);
        return;
    default:
        assert(!"unknown kind of definition");
    }
}

static hz_status d_medium_interface(parser *ps, const token *d, hz_error *err)
{
    const char *inside, *outside;
    token t;
    if (parser_string_arg(ps, d, &inside, err) != HZ_OK || parser_peek(ps, &t, err) != HZ_OK)
        return HZ_ERROR;
    outside = inside;
    if (t.kind == TOK_STRING && parser_string_arg(ps, d, &outside, err) != HZ_OK)
        return HZ_ERROR;
    ps->gs.inside = inside;
    ps->gs.outside = outside;
    return HZ_OK;
}

static hz_status d_reverse_orientation(parser *ps, const token *d, hz_error *err)
{
    if (parser_need_world(ps, d, "ReverseOrientation", err) != HZ_OK)
        return HZ_ERROR;
    ps->gs.reverse_orientation = !ps->gs.reverse_orientation;
    return HZ_OK;
}

static long find_object(const scene_desc *sd, const char *name)
{
    for (size_t i = 0; i < sd->object_count; ++i)
        if (strcmp(sd->objects[i].name, name) == 0)
            return (long)i;
    return -1;
}

static hz_status d_object_begin(parser *ps, const token *d, hz_error *err)
{
    scene_desc *sd = ps->sd;
    const char *name;
    if (parser_need_world(ps, d, "ObjectBegin", err) != HZ_OK ||
        parser_string_arg(ps, d, &name, err) != HZ_OK)
        return HZ_ERROR;
    if (ps->current_object >= 0) {
        file_loc at = sd->objects[ps->current_object].loc;
        return hz_fail_at(err, d->loc, "ObjectBegin inside the definition of \"%s\" (%s:%d:%d)",
                          sd->objects[ps->current_object].name, at.file, at.line, at.column);
    }
    if (find_object(sd, name) >= 0)
        return hz_fail_at(err, d->loc, "object \"%s\" redefined", name);
    object_entity *grown =
        scene_grow_implicit(sd->objects, sd->object_count, sizeof *sd->objects);
    if (!grown)
        return parser_oom(ps, d->loc, err);
    sd->objects = grown;
    if (parser_push_state(ps, 'o', d->loc, err) != HZ_OK)
        return HZ_ERROR;
    sd->objects[sd->object_count] = (object_entity){(char *)name, d->loc, sd->object_shape_count, 0};
    ps->current_object = (long)sd->object_count++;
    return HZ_OK;
}

static hz_status d_object_end(parser *ps, const token *d, hz_error *err)
{
    if (parser_need_world(ps, d, "ObjectEnd", err) != HZ_OK)
        return HZ_ERROR;
    if (ps->current_object < 0)
        return hz_fail_at(err, d->loc, "ObjectEnd without a matching ObjectBegin");
    const gstate *top = &ps->stack[ps->depth - 1];
    if (top->kind != 'o')
        return hz_fail_at(err, d->loc, "ObjectEnd inside the AttributeBegin at %s:%d:%d",
                          top->pushed_at.file, top->pushed_at.line, top->pushed_at.column);
    parser_pop_state(ps);
    ps->current_object = -1;
    return HZ_OK;
}

static hz_status d_object_instance(parser *ps, const token *d, hz_error *err)
{
    scene_desc *sd = ps->sd;
    const char *name;
    if (parser_need_world(ps, d, "ObjectInstance", err) != HZ_OK ||
        parser_string_arg(ps, d, &name, err) != HZ_OK)
        return HZ_ERROR;
    if (ps->current_object >= 0)
        return hz_fail_at(err, d->loc, "ObjectInstance inside the definition of object \"%s\"",
                          sd->objects[ps->current_object].name);
    long obj = find_object(sd, name);
    if (obj < 0)
        return hz_fail_at(err, d->loc, "ObjectInstance: no object named \"%s\"", name);
    instance_entity *grown =
        scene_grow_implicit(sd->instances, sd->instance_count, sizeof *sd->instances);
    if (!grown)
        return parser_oom(ps, d->loc, err);
    sd->instances = grown;
    sd->instances[sd->instance_count++] =
        (instance_entity){(size_t)obj, ps->gs.ctm[0], ps->gs.ctm[1], d->loc};
    return HZ_OK;
}

static hz_status d_attribute(parser *ps, const token *d, hz_error *err)
{
    static const char *const targets[ATTR_COUNT] = {"shape", "light", "material", "medium",
                                                    "texture"};
    const char *target;
    if (parser_string_arg(ps, d, &target, err) != HZ_OK)
        return HZ_ERROR;
    int k = -1;
    for (int i = 0; i < ATTR_COUNT; ++i)
        if (strcmp(targets[i], target) == 0)
            k = i;
    if (k < 0)
        return hz_fail_at(err, d->loc,
                          "Attribute target \"%s\" is not supported; use \"shape\", \"light\", "
                          "\"material\" or \"medium\"",
                          target);
    param_list pl;
    if (parser_params(ps, &pl, d->loc, err) != HZ_OK) {
        params_free(&pl);
        return HZ_ERROR;
    }
    /* A later Attribute overrides an earlier one of the same name. */
    param_list *dst = &ps->gs.attrs[k];
    for (size_t i = 0; i < pl.count; ++i) {
        params_remove(dst, pl.items[i].name);
        /* The name was just removed: fails only when out of memory (and then
         * frees items[i]; the rest are still pl's). */
        if (params_add(dst, pl.items[i], err) != HZ_OK) {
            for (size_t j = i + 1; j < pl.count; ++j)
                param_free(&pl.items[j]);
            free(pl.items);
            return parser_oom(ps, d->loc, err);
        }
    }
    free(pl.items);
    return HZ_OK;
}

static hz_status d_option(parser *ps, const token *d, hz_error *err)
{
    static const struct {
        const char *name;
        param_type type;
    } known[] = {
        {"disablepixeljitter", PARAM_BOOL}, {"disabletexturefiltering", PARAM_BOOL},
        {"disablewavelengthjitter", PARAM_BOOL}, {"displacementedgescale", PARAM_FLOAT},
        {"msereferenceimage", PARAM_STRING}, {"msereferenceout", PARAM_STRING},
        {"seed", PARAM_INTEGER}, {"forcediffuse", PARAM_BOOL}, {"pixelstats", PARAM_BOOL},
        {"wavefront", PARAM_BOOL}, {"rendercoordsys", PARAM_STRING},
    };
    param_list pl;
    if (parser_params(ps, &pl, d->loc, err) != HZ_OK) {
        params_free(&pl);
        return HZ_ERROR;
    }
    hz_status st = HZ_OK;
    if (pl.count != 1) {
        st = hz_fail_at(err, d->loc, "Option takes one parameter (\"bool disablepixeljitter\" true)");
    } else {
        param *p = &pl.items[0];
        size_t i = 0, n = sizeof known / sizeof known[0];
        while (i < n && strcmp(known[i].name, p->name) != 0)
            ++i;
        if (i == n)
            st = hz_fail_at(err, p->loc, "unknown option \"%s\"", p->name);
        else if (known[i].type != p->type || p->count != 1)
            st = hz_fail_at(err, p->loc, "option \"%s\" takes one %s value", p->name,
                            param_type_name(known[i].type));
        else if (!params_reserve(&ps->sd->options))
            st = parser_oom(ps, d->loc, err);
        else {
            /* Reserved: fails only on an Option given twice. */
            st = params_add(&ps->sd->options, *p, err);
            pl.count = 0; /* ownership moved (or freed by params_add) */
        }
    }
    params_free(&pl);
    return st;
}

/* Later "rgb" values are in this space (parse_value converts them to haze's
 * sRGB); a Film after it writes its image in it. */
static hz_status d_color_space(parser *ps, const token *d, hz_error *err)
{
    const char *name;
    if (parser_string_arg(ps, d, &name, err) != HZ_OK)
        return HZ_ERROR;
    if (!color_space_lookup(name, &ps->gs.color_space))
        return hz_fail_at(err, d->loc, "unknown ColorSpace \"%s\" (known: %s)", name,
                          color_space_names());
    return HZ_OK;
}

#define OPTION_ENTITY(fn, label, seen_field, slot)                                               \
    static hz_status fn(parser *ps, const token *d, hz_error *err)                              \
    {                                                                                             \
        return d_options_entity(ps, d, label, &ps->seen_field, &ps->sd->slot, err);               \
    }
static hz_status d_film(parser *ps, const token *d, hz_error *err)
{
    ps->sd->film_color_space = ps->gs.color_space;
    return d_options_entity(ps, d, "Film", &ps->seen_film, &ps->sd->film, err);
}
OPTION_ENTITY(d_sampler, "Sampler", seen_sampler, sampler)
OPTION_ENTITY(d_filter, "PixelFilter", seen_filter, filter)
OPTION_ENTITY(d_integrator, "Integrator", seen_integrator, integrator)
OPTION_ENTITY(d_accelerator, "Accelerator", seen_accelerator, accelerator)

hz_status parser_entity_directive(parser *ps, const token *d, bool *handled, hz_error *err)
{
    static const struct {
        const char *name;
        hz_status (*fn)(parser *, const token *, hz_error *);
    } table[] = {
        {"Camera", d_camera},
        {"Film", d_film},
        {"Sampler", d_sampler},
        {"PixelFilter", d_filter},
        {"Integrator", d_integrator},
        {"Accelerator", d_accelerator},
        {"Shape", d_shape},
        {"LightSource", d_light},
        {"AreaLightSource", d_area_light},
        {"Material", d_material},
        {"MakeNamedMaterial", d_make_named_material},
        {"NamedMaterial", d_named_material},
        {"Texture", d_texture},
        {"MakeNamedMedium", d_make_named_medium},
        {"MediumInterface", d_medium_interface},
        {"ReverseOrientation", d_reverse_orientation},
        {"ObjectBegin", d_object_begin},
        {"ObjectEnd", d_object_end},
        {"ObjectInstance", d_object_instance},
        {"Attribute", d_attribute},
        {"Option", d_option},
        {"ColorSpace", d_color_space},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; ++i) {
        if (token_is(d, table[i].name)) {
            *handled = true;
            return table[i].fn(ps, d, err);
        }
    }
    *handled = false;
    return HZ_OK;
}
