/* The scene builder: runs every factory in order and owns what they build. */
#include "render/render_scene.h"

#include <assert.h>
#include <math.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera/footprint.h"
#include "color/rgb2spec_module.h"
#include "scene/spectrum.h"
#include "render/color_choice.h"
#include "geometry/geometry.h"
#include "lights/lights.h"
#include "materials/material.h"
#include "integrator/volpath_media.h"

struct render_scene {
    camera cam;
    film *film;
    sampler smp;
    filter *filt;
    texture_set *textures;
    size_t texture_count;
    measured_cache *measured; /* the measured materials' files */
    material *materials;
    size_t material_count;
    material default_material;
    geometry *geom;
    light *lights;
    size_t light_count;
    medium *media;
    size_t medium_count;
    integrator integ;
    /* Spectral rendering: the RGB -> spectrum table of sRGB; NULL: RGB. */
    const rgb2spec_table *spectral;
    /* Spectral rendering with a camera sensor: samples reach the film as
     * that sensor's RGB (sensor_rgb); NULL otherwise. */
    const film_sensor *sensor;
    bool cam_differentials; /* camera_find_min_differentials done */
    /* The sampled spectra of lights, materials and media, copied out of the
     * scene_desc (which may go before the render_scene does): keep_spectrum. */
    double **spectra;
    size_t spectra_count;
    scene_options options;
    /* singlescatter's shadow caches, each at its spacing (voxels): the
     * integrator reads the one of its settings; --target-error's pilot tries
     * others (render_scene_set_marching). */
    shadow_caches *caches[RENDER_SCENE_CACHES];
    double cache_spacing[RENDER_SCENE_CACHES];
};

scene_options render_scene_options(const render_scene *rs) { return rs->options; }
bool render_scene_has_textures(const render_scene *rs)
{
    return rs->texture_count > 0 || (rs->film && film_wants_surface(rs->film));
}

static bool animated(const transform *start, const transform *end)
{
    return memcmp(&start->m, &end->m, sizeof start->m) != 0;
}

/* Top-level shapes and instances move (geometry.h). A shape inside
 * ObjectBegin/End would need an instance inside an instance, which Embree (as
 * Debian builds it, one instance level) cannot do: that stays an error rather
 * than a silently static image. Lights follow pbrt-v4, which warns and uses
 * the start transform; area lights move with their shapes. */
static hz_status check_motion(scene_desc *sd, FILE *warn, hz_error *err)
{
    for (size_t i = 0; i < sd->object_shape_count; ++i)
        if (animated(&sd->object_shapes[i].world_from_object,
                     &sd->object_shapes[i].world_from_object_end))
            return hz_fail_at(err, sd->object_shapes[i].entity.loc,
                              "animated shape transforms inside ObjectBegin/ObjectEnd are not "
                              "supported; animate the ObjectInstance instead");
    for (size_t i = 0; i < sd->light_count; ++i) {
        light_entity *l = &sd->lights[i];
        if (animated(&l->world_from_light, &l->world_from_light_end))
            hz_warn_at(warn, l->entity.loc,
                       "animated lights are not supported; using the start transform (as "
                       "pbrt-v4)");
    }
    return HZ_OK;
}

/* Points s's sampled values at a copy the render_scene owns. */
static hz_status keep_spectrum(render_scene *rs, spectrum_value *s, hz_error *err)
{
    if (s->kind != SPECTRUM_VALUE_SAMPLED || s->n == 0)
        return HZ_OK;
    double **grown = realloc(rs->spectra, (rs->spectra_count + 1) * sizeof *grown);
    double *copy = malloc(2 * s->n * sizeof *copy);
    if (grown)
        rs->spectra = grown;
    if (!grown || !copy) {
        free(copy);
        return hz_fail(err, "out of memory");
    }
    memcpy(copy, s->lambda, s->n * sizeof *copy);
    memcpy(copy + s->n, s->value, s->n * sizeof *copy);
    rs->spectra[rs->spectra_count++] = copy;
    s->lambda = copy;
    s->value = copy + s->n;
    return HZ_OK;
}

/* Every error of the scene in one run: an error with a place (an entity's)
 * is collected and the build goes on without that entity (HZ_OK); one
 * without (memory, devices) is left in `err` and ends the build (HZ_ERROR). */
static hz_status collect(hz_errors *errs, const hz_error *err)
{
    if (!err->loc.file)
        return HZ_ERROR;
    hz_errors_add(errs, err);
    return HZ_OK;
}

static hz_status build_materials(render_scene *rs, scene_desc *sd, transform render_from_world,
                                 hz_errors *errs, hz_error *err)
{
    rs->default_material = material_default();
    if (texture_set_create(sd, render_from_world, errs, &rs->textures, err) != HZ_OK)
        return HZ_ERROR;
    rs->texture_count = sd->texture_count;
    if (measured_cache_create(&rs->measured, err) != HZ_OK)
        return HZ_ERROR;
    rs->materials = calloc(sd->material_count ? sd->material_count : 1, sizeof *rs->materials);
    if (!rs->materials)
        return hz_fail(err, "out of memory");
    rs->material_count = sd->material_count;
    for (size_t i = 0; i < sd->material_count; ++i)
        if (material_from_entity(&sd->materials[i], rs->textures, rs->measured, &rs->materials[i],
                                 err) != HZ_OK) {
            if (collect(errs, err) != HZ_OK)
                return HZ_ERROR;
            rs->materials[i] = material_default();
        }
    if (material_resolve_mixes(rs->materials, sd->materials, sd->material_count, err) != HZ_OK &&
        collect(errs, err) != HZ_OK)
        return HZ_ERROR;
    for (size_t i = 0; i < rs->material_count; ++i)
        if (keep_spectrum(rs, &rs->materials[i].eta_spec, err) != HZ_OK ||
            keep_spectrum(rs, &rs->materials[i].k_spec, err) != HZ_OK ||
            keep_spectrum(rs, &rs->materials[i].interface_eta_spec, err) != HZ_OK)
            return HZ_ERROR;
    return HZ_OK;
}

/* pbrt-v4's Accelerator: its type and parameters are checked as pbrt-v4
 * reads them, then a warning says they change nothing here (they only set
 * the speed of pbrt-v4's own BVH or kd-tree; haze builds Embree's BVH). */
static hz_status read_accelerator(scene_entity *e, FILE *warn, hz_error *err)
{
    if (e->loc.line == 0)
        return HZ_OK;
    param_list *pl = &e->params;
    if (strcmp(e->type, "bvh") == 0) {
        params_int(pl, "maxnodeprims", 4);
        const char *split = params_string(pl, "splitmethod", "sah");
        if (strcmp(split, "sah") && strcmp(split, "middle") && strcmp(split, "equal") &&
            strcmp(split, "hlbvh"))
            params_reject(pl, "splitmethod",
                          "\"splitmethod\" \"%.40s\" is unknown (pbrt-v4 has \"sah\", "
                          "\"middle\", \"equal\", \"hlbvh\")",
                          split);
    } else if (strcmp(e->type, "kdtree") == 0) {
        params_int(pl, "intersectcost", 5);
        params_int(pl, "traversalcost", 1);
        params_float(pl, "emptybonus", 0.5);
        params_int(pl, "maxprims", 1);
        params_int(pl, "maxdepth", -1);
    } else {
        return hz_fail_at(err, e->loc,
                          "Accelerator \"%.40s\" is unknown (pbrt-v4 has \"bvh\" and \"kdtree\")",
                          e->type);
    }
    if (params_finish(pl, "Accelerator", err) != HZ_OK)
        return HZ_ERROR;
    hz_warn_at(warn, e->loc,
               "Accelerator \"%s\" changes nothing in haze, which always builds Embree's BVH "
               "(the image is the same)",
               e->type);
    return HZ_OK;
}

static hz_status build_lights(render_scene *rs, scene_desc *sd, transform render_from_world,
                              FILE *warn, hz_errors *errs, hz_error *err)
{
    size_t n = sd->light_count;
    for (size_t i = 0; i < sd->shape_count; ++i)
        n += sd->shapes[i].has_area_light;
    rs->lights = calloc(n ? n : 1, sizeof *rs->lights);
    if (!rs->lights)
        return hz_fail(err, "out of memory");
    for (size_t i = 0; i < sd->light_count; ++i) {
        if (light_from_entity(&sd->lights[i], render_from_world, &rs->lights[rs->light_count],
                              warn, err) == HZ_OK)
            rs->light_count++;
        else if (collect(errs, err) != HZ_OK)
            return HZ_ERROR;
    }
    for (size_t i = 0; rs->geom && i < sd->shape_count; ++i) {
        geom_shape *gs = geometry_shape(rs->geom, i);
        if (!sd->shapes[i].has_area_light || gs->left_out)
            continue;
        if (gs->material->kind == MATERIAL_INTERFACE) {
            /* As pbrt-v4: an interface is no surface, so it cannot emit. */
            hz_warn_at(warn, sd->shapes[i].area_light.loc,
                       "ignoring the area light of a shape with Material \"interface\" (as "
                       "pbrt-v4)");
            continue;
        }
        if (light_area_from_entity(&sd->shapes[i].area_light, gs, &rs->lights[rs->light_count],
                                   warn, err) == HZ_OK) {
            /* An image emitter's radiance depends on the hit's (u, v). */
            gs->hit_uv |= rs->lights[rs->light_count].area.image != NULL;
            gs->area_light = (int)rs->light_count++;
        }
        else if (collect(errs, err) != HZ_OK)
            return HZ_ERROR;
    }
    for (size_t i = 0; i < rs->light_count; ++i)
        if (keep_spectrum(rs, &rs->lights[i].spectrum, err) != HZ_OK)
            return HZ_ERROR;
    return HZ_OK;
}

/* Media in scene_desc order (shapes refer to them by that index); the camera's
 * medium is resolved by name now that the whole file is read. */
static hz_status build_media(render_scene *rs, scene_desc *sd, transform render_from_world,
                             FILE *warn, hz_errors *errs, hz_error *err)
{
    rs->media = calloc(sd->medium_count ? sd->medium_count : 1, sizeof *rs->media);
    if (!rs->media)
        return hz_fail(err, "out of memory");
    /* Rays take times in the camera's shutter (the TransformTimes when the
     * camera could not be built: only errors are reported then). */
    medium_times times = {sd->transform_start_time, sd->transform_end_time,
                          rs->film ? rs->cam.shutter_open : sd->transform_start_time,
                          rs->film ? rs->cam.shutter_close : sd->transform_end_time};
    for (size_t i = 0; i < sd->medium_count; ++i) {
        /* A refused medium keeps its slot (shapes refer to media by index),
         * empty. */
        if (medium_create(&sd->media[i], render_from_world, &times, warn, &rs->media[i], err) !=
            HZ_OK) {
            if (collect(errs, err) != HZ_OK)
                return HZ_ERROR;
            memset(&rs->media[i], 0, sizeof rs->media[i]);
        }
        rs->medium_count++;
        medium *m = &rs->media[i];
        if (keep_spectrum(rs, &m->sigma_a_spec, err) != HZ_OK ||
            keep_spectrum(rs, &m->sigma_s_spec, err) != HZ_OK ||
            keep_spectrum(rs, &m->Le_spec, err) != HZ_OK)
            return HZ_ERROR;
    }
    rs->cam.medium = scene_find_medium(sd, sd->camera.medium);
    if (rs->cam.medium == SCENE_MEDIUM_UNDEFINED &&
        collect(errs, (hz_fail_at(err, sd->camera.entity.loc,
                                  "the camera sits in medium \"%s\", which is not defined "
                                  "(MakeNamedMedium)",
                                  sd->camera.medium),
                       err)) != HZ_OK)
        return HZ_ERROR;
    /* pbrt-v4 checks a light's medium name too (haze does not use it: shadow
     * rays take the medium of the point they leave). */
    for (size_t i = 0; i < sd->light_count; ++i)
        if (scene_find_medium(sd, sd->lights[i].medium) == SCENE_MEDIUM_UNDEFINED &&
            collect(errs, (hz_fail_at(err, sd->lights[i].entity.loc,
                                      "the light sits in medium \"%s\", which is not defined "
                                      "(MakeNamedMedium)",
                                      sd->lights[i].medium),
                           err)) != HZ_OK)
            return HZ_ERROR;
    return HZ_OK;
}

/* Reads the Option directives (render_scene.h, scene_options). */
static hz_status read_options(param_list *pl, const render_options *opt, uint64_t *seed,
                              scene_options *out, hz_error *err)
{
    int s = params_int(pl, "seed", 0);
    if (params_has(pl, "seed") && !(opt && opt->seed_given)) {
        if (s < 0)
            params_reject(pl, "seed", "Option \"seed\" must be >= 0, got %d", s);
        *seed = (uint64_t)(s < 0 ? 0 : s);
    }
    out->disable_pixel_jitter = params_bool(pl, "disablepixeljitter", false);
    out->force_diffuse = params_bool(pl, "forcediffuse", false);
    const char *space = params_string(pl, "rendercoordsys", "cameraworld");
    if (strcmp(space, "cameraworld") != 0 && strcmp(space, "camera") != 0 &&
        strcmp(space, "world") != 0)
        params_reject(pl, "rendercoordsys",
                      "Option \"rendercoordsys\" \"%s\" is not one of \"camera\", "
                      "\"cameraworld\", \"world\"",
                      space);
    /* Everything else pbrt-v4 knows (pixelstats, msereferenceimage,
     * disabletexturefiltering, wavefront, ...) is reported here as unused. */
    for (size_t i = 0; i < pl->count; ++i)
        if (!pl->items[i].used)
            return hz_fail_at(err, pl->items[i].loc,
                              "Option \"%s\" is not supported by haze (supported: seed, "
                              "disablepixeljitter, forcediffuse, rendercoordsys)",
                              pl->items[i].name);
    return params_finish(pl, "Option", err);
}

/* Why the shadow cache (integrator/shadow_cache.h) could not apply to the
 * scene with integrator inputs `in`, as the end of a sentence: NULL when it
 * can (a static scene, a grid medium that rays enter, a distant light). */
static const char *shadow_cache_obstacle(const render_scene *rs, const integrator_inputs *in)
{
    render_motion motion = render_scene_motion(rs);
    if (motion.surfaces || motion.media > 0)
        return motion.media > 0 ? "tabulates shadows once, for a static scene: here media move"
                                : "tabulates shadows once, for a static scene: here surfaces move";
    bool grid = false, distant = false;
    for (size_t i = 0; i < in->medium_count; ++i)
        grid |= medium_is_density_grid(&in->media[i]);
    for (size_t i = 0; i < in->light_count; ++i)
        distant |= in->lights[i].kind == LIGHT_DISTANT;
    return !grid      ? "caches distant lights' shadows in grid media: this scene has no grid "
                        "medium that rays enter, so it would change nothing"
           : !distant ? "caches distant lights' shadows in grid media: this scene has no distant "
                        "light, so it would change nothing"
                      : NULL;
}

/* Whether volpath's "stepsize" marches any of in's media. */
static bool any_marchable(const integrator_inputs *in)
{
    for (size_t i = 0; i < in->medium_count; ++i)
        if (volpath_marches(&in->media[i]))
            return true;
    return false;
}

/* The shadow cache replaces shadow rays of distant lights in grid media:
 * refused where it would change nothing or could not hold (anything moves). */
static hz_status check_shadow_cache(const render_scene *rs, scene_desc *sd,
                                    const integrator_inputs *in, hz_error *err)
{
    const char *why = shadow_cache_obstacle(rs, in);
    return why ? hz_fail_at(err, params_loc(&sd->integrator.params, "shadowcache"),
                            "\"shadowcache\" %s", why)
               : HZ_OK;
}

/* The Film's parameters with the command line's overrides. False (and
 * *err set) when the Film was refused. */
static bool read_film(scene_desc *sd, const render_options *opt, film_params *fp, hz_error *err)
{
    if (film_params_from_entity_region(&sd->film, opt ? &opt->region : NULL, fp, NULL, err) !=
        HZ_OK)
        return false;
    film_params_set_color_space(fp, sd->film_color_space);
    if (opt && opt->output) {
        /* -o wins, and writes an EXR (cli/outputs.c refuses other names),
         * which holds every channel. */
        if (strlen(opt->output) >= sizeof fp->filename) {
            hz_fail(err, "output file name too long: %s", opt->output);
            return false;
        }
        snprintf(fp->filename, sizeof fp->filename, "%s", opt->output);
    } else if (film_params_check_format(&sd->film, fp, err) != HZ_OK) {
        return false;
    }
    /* Adaptive sampling needs the statistics, whatever the file keeps. */
    if (opt && opt->statistics)
        fp->write_variance = fp->write_sample_count = true;
    return true;
}

/* The film of the built camera. */
static hz_status build_film(render_scene *rs, scene_desc *sd, const film_params *fp, FILE *warn,
                            hz_error *err)
{
    rs->film = film_create(fp, err);
    if (!rs->film) {
        /* The film's own failures (its size) name the Film. */
        char msg[sizeof err->message];
        memcpy(msg, err->message, sizeof msg);
        return hz_fail_at(err, sd->film.loc, "%s", msg);
    }
    if (params_has(&sd->film.params, "scale"))
        hz_warn_at(warn, params_loc(&sd->film.params, "scale"),
                   "Film \"scale\" was removed from pbrt-v4 in 2020 (\"iso\" replaces it) "
                   "and today's pbrt-v4 refuses it; haze multiplies the image by it, as "
                   "pbrt-v4 did");
    /* maxcomponentvalue clamps L * imaging ratio, as pbrt-v4 does. */
    film_set_imaging_ratio(rs->film, camera_imaging_ratio(&rs->cam, fp));
    /* A gbuffer's positions and normals: camera space (at the shutter's
     * open) or world space. */
    film_set_output_from_render(rs->film, fp->gbuffer_world
                                              ? rs->cam.world_from_render
                                              : transform_inverse(rs->cam.render_from_camera));
    return HZ_OK;
}

/* The sampler, with --spp. */
static hz_status build_sampler(render_scene *rs, scene_desc *sd, const render_options *opt,
                               uint64_t seed, FILE *warn, hz_error *err)
{
    if (sampler_from_entity(&sd->sampler, seed, &rs->smp, err) != HZ_OK)
        return HZ_ERROR;
    if (opt && opt->spp > 0)
        sampler_set_spp(&rs->smp, opt->spp);
    if (rs->smp.warning[0])
        hz_warn_at(warn, sd->sampler.loc, "%s", rs->smp.warning);
    return HZ_OK;
}

/* Media that only volpath renders, under singlescatter: refused. */
static hz_status check_media_integrator(const render_scene *rs, scene_desc *sd,
                                        const integrator_params *ip, hz_errors *errs,
                                        hz_error *err)
{
    for (size_t i = 0; ip->kind == INTEGRATOR_SINGLESCATTER && i < rs->medium_count; ++i)
        if (medium_type_volpath_only(sd->media[i].entity.type) &&
            collect(errs, (hz_fail_at(err, sd->media[i].entity.loc,
                                      "MakeNamedMedium \"%s\": a \"%s\" medium needs "
                                      "Integrator \"volpath\" (singlescatter renders nanovdb, "
                                      "uniformgrid and homogeneous media)",
                                      rs->media[i].name ? rs->media[i].name : "",
                                      sd->media[i].entity.type),
                           err)) != HZ_OK)
            return HZ_ERROR;
    return HZ_OK;
}

/* pbrt-v4 renders a scene with no Integrator with "volpath" (maxdepth 5):
 * say once which haze renders. */
static void warn_default_integrator(const render_scene *rs, scene_desc *sd, FILE *warn)
{
    const char *why, *what;
    bool forced = integrator_default_kind(sd, &why, &what) == INTEGRATOR_VOLPATH;
    if (!warn || sd->integrator.loc.line != 0 || !(rs->medium_count > 0 || forced))
        return;
    const char *file = sd->file_count ? sd->files[0] : "<input>";
    if (forced)
        fprintf(warn,
                "%s: warning: the scene names no Integrator and has a \"%s\" %s, which "
                "only \"volpath\" renders: haze renders pbrt-v4's default, \"volpath\" "
                "with maxdepth 5\n",
                file, why, what);
    else
        fprintf(warn,
                "%s: warning: the scene names no Integrator: haze renders single scattering "
                "(\"singlescatter\", its default), pbrt-v4 multiple scattering (\"volpath\", "
                "maxdepth 5); name Integrator \"volpath\" for pbrt-v4's image\n",
                file);
}

/* The integrator over what was built, and the shadow caches it asks for. */
static hz_status build_integrator(render_scene *rs, scene_desc *sd, const integrator_params *ip,
                                  FILE *warn, hz_error *err)
{
    /* Media that no ray can enter (no shape names one, the camera sits in
     * none) cost nothing: the integrators see a scene without media, so its
     * shadow rays stay occlusion tests and the image is the one without
     * them, byte for byte. */
    bool media_used = rs->cam.medium >= 0 || geometry_references_media(rs->geom);
    integrator_inputs in = {rs->geom, rs->lights, rs->light_count, rs->media,
                            media_used ? rs->medium_count : 0, &rs->cam, 0.0};
    double spacing = ip->kind == INTEGRATOR_SINGLESCATTER ? ip->singlescatter.shadow_cache
                     : ip->kind == INTEGRATOR_VOLPATH       ? ip->volpath.shadow_cache
                                                            : 0.0;
    if (spacing > 0.0 && check_shadow_cache(rs, sd, &in, err) != HZ_OK)
        return HZ_ERROR;
    if (ip->kind == INTEGRATOR_VOLPATH && ip->volpath.step > 0.0 && !any_marchable(&in))
        return hz_fail_at(err, params_loc(&sd->integrator.params, "stepsize"),
                          "\"stepsize\" marches grid media whose coefficients are a density "
                          "times constants (no colour or emission grid, not moving): this scene "
                          "has none that rays enter, so it would change nothing");
    if (ip->kind == INTEGRATOR_VOLPATH && ip->volpath.medium_splits > 1 && in.medium_count == 0)
        return hz_fail_at(err, params_loc(&sd->integrator.params, "mediumsplits"),
                          "\"mediumsplits\" splits paths where they first scatter in a medium: "
                          "this scene has no medium that rays enter, so it would change nothing");
    if (integrator_init(&rs->integ, ip, &in, err) != HZ_OK)
        return HZ_ERROR;
    if (!(spacing > 0.0))
        return HZ_OK;
    rs->cache_spacing[0] = spacing;
    /* The caches walk their columns at lookups: the inputs the integrator
     * keeps, which live as long as the render_scene. */
    bool single = ip->kind == INTEGRATOR_SINGLESCATTER;
    const integrator_inputs *kept = single ? &rs->integ.singlescatter.in : &rs->integ.volpath.in;
    if (shadow_caches_create(kept, spacing, 0, warn, &rs->caches[0], err) != HZ_OK)
        return HZ_ERROR;
    if (single)
        rs->integ.singlescatter.caches = rs->caches[0];
    else
        rs->integ.volpath.caches = rs->caches[0];
    return HZ_OK;
}

/* Builds what it can; see collect(). */
/* The constant colours' spectra of materials and lights, looked up once. */
static void prepare_spectral(render_scene *rs)
{
    for (size_t i = 0; i < rs->material_count; ++i)
        material_prepare_spectral(&rs->materials[i], rs->spectral);
    material_prepare_spectral(&rs->default_material, rs->spectral);
    for (size_t i = 0; i < rs->light_count; ++i)
        light_prepare_spectral(&rs->lights[i], rs->spectral);
    for (size_t i = 0; i < rs->medium_count; ++i)
        medium_prepare_spectral(&rs->media[i], rs->spectral);
}

static hz_status build_all(render_scene *rs, scene_desc *sd, const render_options *opt,
                           FILE *warn, hz_errors *errs, hz_error *err)
{
#define CHECK(call)                                                                                \
    if ((call) != HZ_OK && collect(errs, err) != HZ_OK)                                            \
    return HZ_ERROR
    uint64_t seed = opt ? opt->seed : 0;
    CHECK(read_options(&sd->options, opt, &seed, &rs->options, err));
    film_params fp;
    bool have_film = read_film(sd, opt, &fp, err);
    if (!have_film && collect(errs, err) != HZ_OK)
        return HZ_ERROR;
    CHECK(read_accelerator(&sd->accelerator, warn, err));
    rs->filt = filter_create(&sd->filter, err);
    if (!rs->filt && collect(errs, err) != HZ_OK)
        return HZ_ERROR;
    CHECK(build_sampler(rs, sd, opt, seed, warn, err));
    bool have_camera = false;
    if (have_film) {
        have_camera = camera_create(&sd->camera, &fp, &rs->cam, err) == HZ_OK;
        if (!have_camera && collect(errs, err) != HZ_OK)
            return HZ_ERROR;
    }
    if (have_camera && build_film(rs, sd, &fp, warn, err) != HZ_OK)
        return HZ_ERROR;
    integrator_params ip = {.kind = INTEGRATOR_SINGLESCATTER};
    CHECK(integrator_params_from_scene(sd, warn, &ip, err));
    if (ip.kind == INTEGRATOR_VOLPATH)
        ip.volpath.force_diffuse = rs->options.force_diffuse;
    CHECK(check_motion(sd, warn, err));
    /* Render space: the world translated so the camera sits at the origin. */
    transform render_from_world =
        have_camera ? transform_inverse(rs->cam.world_from_render) : transform_identity();
    if (build_materials(rs, sd, render_from_world, errs, err) != HZ_OK)
        return HZ_ERROR;
    CHECK(geometry_create(sd, render_from_world, rs->materials, rs->material_count,
                          &rs->default_material, rs->textures, opt && opt->portable_isa, errs,
                          &rs->geom, err));
    if (rs->geom && rs->film && film_wants_surface(rs->film))
        geometry_require_uv(rs->geom);
    if (build_lights(rs, sd, render_from_world, warn, errs, err) != HZ_OK ||
        build_media(rs, sd, render_from_world, warn, errs, err) != HZ_OK ||
        check_media_integrator(rs, sd, &ip, errs, err) != HZ_OK)
        return HZ_ERROR;
#undef CHECK
    if (errs->count || errs->dropped)
        return HZ_OK; /* reported by the caller; nothing to render */
    warn_default_integrator(rs, sd, warn);
    render_color asked = opt ? opt->color : RENDER_COLOR_AUTO, color = asked;
    color_choice choice = {false, NULL};
    if (asked == RENDER_COLOR_AUTO) {
        color_choice_scene cs = {rs->materials, rs->material_count, &rs->default_material,
                                 rs->media, rs->medium_count,
                                 rs->film && film_get_params(rs->film)->sensor.curves,
                                 rs->film && isfinite(film_get_params(rs->film)->max_component_value),
                                 ip.kind == INTEGRATOR_VOLPATH};
        choice = color_choice_auto(&cs);
        color = choice.spectral ? RENDER_COLOR_SPECTRAL : RENDER_COLOR_RGB;
    }
    if (color == RENDER_COLOR_SPECTRAL) {
        const rgb2spec_table *tables;
        if (rgb2spec_tables_load(&tables, err) == HZ_OK) {
            rs->spectral = &tables[COLOR_SPACE_SRGB];
            prepare_spectral(rs);
            if (rs->film && film_get_params(rs->film)->sensor.curves) {
                rs->sensor = &film_get_params(rs->film)->sensor;
                film_take_sensor_rgb(rs->film);
            }
        } else if (asked == RENDER_COLOR_SPECTRAL) {
            return HZ_ERROR;
        } else if (warn) { /* auto: the scene still renders, in RGB */
            fprintf(warn, "haze: warning: rendering in RGB although the scene has %s: %s\n",
                    choice.why, err->message);
        }
    }
    return build_integrator(rs, sd, &ip, warn, err);
}

/* Every error with a place in one run (sorted in file order, at most
 * HZ_ERRORS_MAX), ended early only by one without a place. */
static hz_status build(render_scene *rs, scene_desc *sd, const render_options *opt, FILE *warn,
                       hz_errors *errs, hz_error *err)
{
    for (size_t i = 0; warn && i < sd->warning_count; ++i)
        fprintf(warn, "%s\n", sd->warnings[i]);
    if (build_all(rs, sd, opt, warn, errs, err) != HZ_OK)
        hz_errors_add(errs, err);
    return hz_errors_finish(errs, sd->files, sd->file_count, err);
}

hz_status render_scene_check(scene_desc *sd, const render_options *opt, hz_errors *errs,
                             hz_error *err)
{
    render_scene *rs = calloc(1, sizeof *rs);
    if (!rs) {
        hz_fail(err, "out of memory");
        hz_errors_add(errs, err);
    } else {
        if (build_all(rs, sd, opt, NULL, errs, err) != HZ_OK)
            hz_errors_add(errs, err);
        render_scene_destroy(rs);
    }
    return hz_errors_finish(errs, sd->files, sd->file_count, err);
}

hz_status render_scene_create(scene_desc *sd, const render_options *opt, FILE *warn,
                              render_scene **out, hz_error *err)
{
    *out = NULL;
    render_scene *rs = calloc(1, sizeof *rs);
    if (!rs)
        return hz_fail(err, "out of memory");
    hz_errors errs = {0};
    if (build(rs, sd, opt, warn, &errs, err) != HZ_OK) {
        render_scene_destroy(rs);
        return HZ_ERROR;
    }
    *out = rs;
    return HZ_OK;
}

void render_scene_destroy(render_scene *rs)
{
    if (!rs)
        return;
    integrator_free(&rs->integ);
    for (int i = 0; i < RENDER_SCENE_CACHES; ++i)
        shadow_caches_destroy(rs->caches[i]);
    for (size_t i = 0; i < rs->light_count; ++i)
        light_free(&rs->lights[i]);
    free(rs->lights);
    for (size_t i = 0; i < rs->medium_count; ++i)
        medium_destroy(&rs->media[i]);
    free(rs->media);
    geometry_destroy(rs->geom);
    free(rs->materials);
    measured_cache_destroy(rs->measured);
    texture_set_destroy(rs->textures);
    if (rs->film)
        film_destroy(rs->film);
    if (rs->filt)
        filter_destroy(rs->filt);
    camera_free(&rs->cam);
    for (size_t i = 0; i < rs->spectra_count; ++i)
        free(rs->spectra[i]);
    free(rs->spectra);
    free(rs);
}

const camera *render_scene_camera(const render_scene *rs) { return &rs->cam; }

bool render_scene_black_outside(const render_scene *rs, double out[4])
{
    if (rs->cam.medium >= 0)
        return false;
    for (size_t i = 0; i < rs->light_count; ++i)
        if (rs->lights[i].kind == LIGHT_INFINITE)
            return false;
    vec3 lo, hi;
    if (!geometry_static_box(rs->geom, &lo, &hi))
        return false;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) { /* no shape: every ray misses */
        out[0] = out[2] = INFINITY;
        out[1] = out[3] = -INFINITY;
        return true;
    }
    return camera_raster_bounds(&rs->cam, lo, hi, out);
}
film *render_scene_film(render_scene *rs) { return rs->film; }
const sampler *render_scene_sampler(const render_scene *rs) { return &rs->smp; }
const filter *render_scene_filter(const render_scene *rs) { return rs->filt; }
const geometry *render_scene_geometry(const render_scene *rs) { return rs->geom; }
size_t render_scene_light_count(const render_scene *rs) { return rs->light_count; }
const light *render_scene_lights(const render_scene *rs) { return rs->lights; }

render_motion render_scene_motion(const render_scene *rs)
{
    render_motion m = {rs->cam.motion, geometry_has_motion(rs->geom), 0};
    for (size_t i = 0; i < rs->medium_count; ++i)
        m.media += medium_moves(&rs->media[i]);
    return m;
}

render_memory render_scene_memory(const render_scene *rs)
{
    render_memory mem = {0.0, 0.0, film_memory_bytes(rs->film),
                         (double)geometry_embree_peak_bytes(rs->geom),
                         (double)shadow_caches_bytes(render_scene_shadow_caches(rs))};
    for (size_t i = 0; i < rs->medium_count; ++i) {
        medium_memory mm = medium_bytes(&rs->media[i]);
        mem.grids += mm.grids;
        mem.majorants += mm.majorants;
    }
    return mem;
}

medium_work render_scene_media_work(const render_scene *rs)
{
    medium_work w = {0, 0.0};
    for (size_t i = 0; i < rs->medium_count; ++i) {
        medium_work mw = medium_work_done(&rs->media[i]);
        w.majorant_bricks += mw.majorant_bricks;
        w.majorant_seconds += mw.majorant_seconds;
    }
    return w;
}

const shadow_caches *render_scene_shadow_caches(const render_scene *rs)
{
    switch (rs->integ.kind) {
    case INTEGRATOR_SINGLESCATTER:
        return rs->integ.singlescatter.caches;
    case INTEGRATOR_VOLPATH:
        return rs->integ.volpath.caches;
    }
    return NULL;
}

/* The caches at `spacing`: from the pool, or built into a free slot (or one
 * whose caches the integrator does not read). NULL when they cannot be built. */
static const shadow_caches *cache_at(render_scene *rs, double spacing)
{
    for (int i = 0; i < RENDER_SCENE_CACHES; ++i)
        if (rs->caches[i] && rs->cache_spacing[i] == spacing)
            return rs->caches[i];
    const shadow_caches *current = render_scene_shadow_caches(rs);
    int slot = -1;
    for (int i = 0; i < RENDER_SCENE_CACHES && slot < 0; ++i)
        if (!rs->caches[i])
            slot = i;
    for (int i = 0; i < RENDER_SCENE_CACHES && slot < 0; ++i)
        if (rs->caches[i] != current)
            slot = i;
    if (slot < 0)
        return NULL;
    shadow_caches_destroy(rs->caches[slot]);
    rs->caches[slot] = NULL;
    hz_error err = {0};
    if (shadow_caches_create(&rs->integ.singlescatter.in, spacing, 0, NULL, &rs->caches[slot],
                             &err) != HZ_OK)
        return NULL;
    rs->cache_spacing[slot] = spacing;
    return rs->caches[slot];
}

static bool marches(transmittance_mode m)
{
    return m == TRANSMITTANCE_RAYMARCH || m == TRANSMITTANCE_JITTERED;
}

bool render_scene_marching(const render_scene *rs, render_marching *m)
{
    if (rs->integ.kind != INTEGRATOR_SINGLESCATTER)
        return false;
    const singlescatter_scene *sc = &rs->integ.singlescatter;
    bool grids = false;
    for (size_t i = 0; i < sc->in.medium_count; ++i)
        grids |= medium_is_density_grid(&sc->in.media[i]);
    const singlescatter_settings *set = &sc->settings;
    if (!grids || !(marches(set->mode) || marches(set->shadow_mode)))
        return false;
    double scale = INFINITY;
    for (size_t i = 0; i < sc->in.medium_count; ++i) {
        const medium *md = &sc->in.media[i];
        vec3 corners[8];
        double voxel;
        if (medium_is_density_grid(md) && medium_support(md, corners, &voxel))
            scale = fmin(scale, singlescatter_auto_step_scale(set, md, 1.0 / voxel, INFINITY));
    }
    *m = (render_marching){set->mode, set->shadow_mode, set->step, set->shadow_step,
                           set->shadow_cache, !shadow_cache_obstacle(rs, &sc->in),
                           set->auto_steps, isfinite(scale) ? scale : 1.0};
    return true;
}

void render_scene_set_marching(render_scene *rs, const render_marching *m)
{
    assert(rs->integ.kind == INTEGRATOR_SINGLESCATTER);
    singlescatter_settings set = rs->integ.singlescatter.settings;
    set.mode = m->mode;
    set.shadow_mode = m->shadow_mode;
    set.step = m->step;
    set.shadow_step = m->shadow_step;
    set.shadow_cache = m->shadow_cache;
    const shadow_caches *caches = m->shadow_cache > 0.0 ? cache_at(rs, m->shadow_cache) : NULL;
    if (!caches) /* none asked for, or none could be built: shadow rays */
        set.shadow_cache = 0.0;
    rs->integ.singlescatter = singlescatter_scene_make(&rs->integ.singlescatter.in, set);
    rs->integ.singlescatter.caches = caches;
}

void render_scene_keep_current_cache(render_scene *rs)
{
    const shadow_caches *current = render_scene_shadow_caches(rs);
    for (int i = 0; i < RENDER_SCENE_CACHES; ++i)
        if (rs->caches[i] && rs->caches[i] != current) {
            shadow_caches_destroy(rs->caches[i]);
            rs->caches[i] = NULL;
        }
}

/* The camera sensor's RGB of a sample's wavelengths (pbrt-v4's
 * PixelSensor::ToSensorRGB): each lane's radiance over its density, on the
 * sensor's curves, in the units of the XYZ spectral_to_rgb makes. */
static rgb sensor_rgb(const film_sensor *fs, const spectral_ctx *sp, rgb L)
{
    const double v[WAVELENGTH_LANES] = {L.r, L.g, L.b, L.w};
    rgb sum = rgb_grey(0.0);
    for (int i = 0; i < WAVELENGTH_LANES; ++i) {
        if (!(sp->wl.pdf[i] > 0.0) || v[i] == 0.0)
            continue;
        sum = rgb_add(sum, rgb_scale(sensor_response(fs, sp->wl.lambda[i]), v[i] / sp->wl.pdf[i]));
    }
    return rgb_scale(sum, 1.0 / (WAVELENGTH_LANES * SPECTRUM_CIE_Y_INTEGRAL));
}

/* One camera sample's radiance: linear RGB, or the sensor's RGB when
 * `to_sensor` and spectral rendering has a camera sensor. */
static rgb li(const render_scene *rs, const ray_differential *r, sampler_state *s, double *depth,
              film_surface *vs, integrator_counters *counters, bool to_sensor)
{
    if (!rs->spectral)
        return integrator_li(&rs->integ, r, NULL, s, depth, vs, counters);
    spectral_ctx sp = spectral_ctx_make(rs->spectral, sampler_wavelength_1d(s));
    rgb L = integrator_li(&rs->integ, r, &sp, s, depth, vs, counters);
    return to_sensor && rs->sensor ? sensor_rgb(rs->sensor, &sp, L) : spectral_to_rgb(&sp, L);
}

rgb render_scene_li(const render_scene *rs, const ray_differential *r, sampler_state *s,
                    double *depth, integrator_counters *counters)
{
    return li(rs, r, s, depth, NULL, counters, false);
}

rgb render_scene_li_surface(const render_scene *rs, const ray_differential *r, sampler_state *s,
                            double *depth, film_surface *vs, integrator_counters *counters)
{
    return li(rs, r, s, depth, vs, counters, true);
}

void render_scene_set_footprint_scale(render_scene *rs, double scale)
{
    if (scale > 0.0 && rs->film && !rs->cam_differentials) { /* once: every pass calls this */
        camera_find_min_differentials(&rs->cam);
        rs->cam_differentials = true;
    }
    integrator_set_footprint_scale(&rs->integ, scale);
}

bool render_scene_spectral(const render_scene *rs) { return rs->spectral != NULL; }
