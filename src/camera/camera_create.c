/* camera_create: reads a Camera directive's parameters into a camera_config
 * (pbrt-v4's PerspectiveCamera::Create / OrthographicCamera::Create plus haze's
 * physical-lens parameters) and reports every problem at its file:line:column. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera/camera.h"
#include "camera/lens.h"
#include "camera/lens_file.h"
#include "core/file.h"
#include "core/path.h"
#include "scene/params.h"
#include "textures/texture_image.h"

/* Fails at the parameter's own place (the directive's when it is absent). */
static hz_status fail_param(hz_error *err, const scene_entity *ent, const char *name,
                            const char *message)
{
    file_loc loc = name[0] && params_has(&ent->params, name) ? params_loc(&ent->params, name)
                                                             : ent->loc;
    return hz_fail_at(err, loc, "%s", message);
}

static bool positive_finite(double v) { return isfinite(v) && v > 0.0; }

/* Physical lens (haze extension): focallength [mm], sensorwidth [mm] along the
 * frame's longer axis and fstop give fov and the lens radius in metres. */
static hz_status read_physical_lens(scene_entity *ent, double frame, camera_config *cfg,
                                    hz_error *err)
{
    param_list *pl = &ent->params;
    char msg[256];
    if (params_has(pl, "fov"))
        return fail_param(err, ent, "fov",
                          "give either \"fov\" or \"focallength\" for a perspective camera, "
                          "not both");
    double fl = params_float(pl, "focallength", 50.0);
    double sensor = params_float(pl, "sensorwidth", 36.0);
    if (!positive_finite(fl)) {
        snprintf(msg, sizeof msg, "\"focallength\" must be finite and > 0 (millimetres), got %g",
                 fl);
        return fail_param(err, ent, "focallength", msg);
    }
    if (!positive_finite(sensor)) {
        snprintf(msg, sizeof msg, "\"sensorwidth\" must be finite and > 0 (millimetres), got %g",
                 sensor);
        return fail_param(err, ent, "sensorwidth", msg);
    }
    cfg->fov = lens_fov_from_focal_length(fl, sensor, frame);
    if (!(cfg->fov > 0.0 && cfg->fov < 180.0)) {
        snprintf(msg, sizeof msg,
                 "\"focallength\" %g mm with sensor width %g mm gives an unusable field of "
                 "view (%g degrees)",
                 fl, sensor, cfg->fov);
        return fail_param(err, ent, "focallength", msg);
    }
    if (params_has(pl, "fstop")) {
        if (params_has(pl, "lensradius"))
            return fail_param(err, ent, "fstop",
                              "give either \"lensradius\" or \"fstop\", not both");
        double fstop = params_float(pl, "fstop", 0.0);
        if (!positive_finite(fstop)) {
            snprintf(msg, sizeof msg, "\"fstop\" must be finite and > 0, got %g", fstop);
            return fail_param(err, ent, "fstop", msg);
        }
        cfg->lens_radius = lens_radius_from_fstop(fl, fstop);
    }
    return HZ_OK;
}

/* The spherical camera's "mapping"; the projective cameras' parameters,
 * which pbrt-v4 reads there and ignores, are refused. */
static hz_status read_spherical(scene_entity *ent, camera_config *cfg, hz_error *err)
{
    static const char *const projective[] = {
        "lensradius", "focaldistance", "frameaspectratio", "screenwindow", "fov",
        "blades",     "bladerotation", "focallength",      "fstop",        "sensorwidth"};
    param_list *pl = &ent->params;
    char msg[256];
    for (size_t i = 0; i < sizeof projective / sizeof projective[0]; ++i)
        if (params_has(pl, projective[i])) {
            snprintf(msg, sizeof msg,
                     "\"%s\" does nothing on a spherical camera (pbrt-v4 ignores it): "
                     "remove it",
                     projective[i]);
            return fail_param(err, ent, projective[i], msg);
        }
    const char *m = params_string(pl, "mapping", "equalarea");
    cfg->equirect = strcmp(m, "equirectangular") == 0;
    if (!cfg->equirect && strcmp(m, "equalarea") != 0) {
        snprintf(msg, sizeof msg,
                 "\"mapping\" must be \"equalarea\" or \"equirectangular\", got \"%.60s\"", m);
        return fail_param(err, ent, "mapping", msg);
    }
    return HZ_OK;
}

static hz_status read_kind(const scene_entity *ent, camera_kind *kind, hz_error *err)
{
    if (strcmp(ent->type, "perspective") == 0)
        *kind = CAMERA_PERSPECTIVE;
    else if (strcmp(ent->type, "orthographic") == 0)
        *kind = CAMERA_ORTHOGRAPHIC;
    else if (strcmp(ent->type, "spherical") == 0)
        *kind = CAMERA_SPHERICAL;
    else if (strcmp(ent->type, "realistic") == 0)
        *kind = CAMERA_REALISTIC;
    else
        return hz_fail_at(err, ent->loc,
                          "camera type \"%s\" is not supported (haze supports \"perspective\", "
                          "\"orthographic\", \"spherical\" and \"realistic\")",
                          ent->type);
    return HZ_OK;
}

/* The realistic camera's "aperture": pbrt-v4's built-in shapes, or else an
 * image file (APERTURE_IMAGE; read by read_aperture_image). */
static aperture_shape read_aperture_shape(scene_entity *ent)
{
    static const char *const names[] = {"", "gaussian", "square", "pentagon", "star"};
    static const aperture_shape shapes[] = {APERTURE_CIRCLE, APERTURE_GAUSSIAN, APERTURE_SQUARE,
                                            APERTURE_PENTAGON, APERTURE_STAR};
    const char *a = params_string(&ent->params, "aperture", "");
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        if (strcmp(a, names[i]) == 0)
            return shapes[i];
    return APERTURE_IMAGE;
}

/* An aperture image file (PNG as sRGB, EXR as linear, as pbrt-v4 reads them),
 * relative to the scene file: the mean of its R, G and B becomes the stop. */
static hz_status read_aperture_image(scene_entity *ent, realistic_lens *l, hz_error *err)
{
    param_list *pl = &ent->params;
    const char *name = params_string(pl, "aperture", "");
    file_loc loc = params_loc(pl, "aperture");
    bool png = file_has_suffix(name, ".png");
    if (!png && !file_has_suffix(name, ".exr"))
        return hz_fail_at(err, loc,
                          "\"aperture\" \"%.200s\" is not a built-in shape (\"gaussian\", "
                          "\"square\", \"pentagon\", \"star\") nor a .png or .exr image",
                          name);
    char *path = path_of_scene_file(loc, name);
    if (!path)
        return hz_fail_at(err, loc, "out of memory");
    tex_image im = {0, 0, NULL};
    float *alpha = NULL;
    hz_error why;
    hz_status st = file_check_regular(path, &why);
    if (st != HZ_OK)
        hz_fail_at(err, loc, "\"aperture\": %s", why.message);
    else if (png)
        st = tex_image_read_png(path, loc, 0, 1.0, &im, &alpha, err);
    else
        st = tex_image_read_exr(path, loc, &im, &alpha, err);
    free(path);
    free(alpha);
    if (st != HZ_OK)
        return HZ_ERROR;
    size_t n = (size_t)im.width * (size_t)im.height;
    float *mono = malloc((n ? n : 1) * sizeof *mono);
    if (!mono) {
        free(im.rgb);
        return hz_fail_at(err, loc, "out of memory");
    }
    for (size_t i = 0; i < n; ++i)
        mono[i] = (im.rgb[3 * i] + im.rgb[3 * i + 1] + im.rgb[3 * i + 2]) / 3.0f;
    free(im.rgb);
    if (realistic_set_aperture_image(l, im.width, im.height, mono, &why) != HZ_OK)
        return hz_fail_at(err, loc, "\"aperture\" \"%.200s\": %s", name, why.message);
    return HZ_OK;
}

/* The lens table named by "lensfile", relative to the scene file. */
static hz_status read_lens_table(scene_entity *ent, lens_table *t, hz_error *err)
{
    param_list *pl = &ent->params;
    const char *name = params_string(pl, "lensfile", "");
    if (!name[0])
        return fail_param(err, ent, "lensfile",
                          "the realistic camera needs \"string lensfile\" (a lens description "
                          "file)");
    char *path = path_of_scene_file(params_loc(pl, "lensfile"), name);
    if (!path)
        return fail_param(err, ent, "lensfile", "out of memory");
    hz_error why;
    hz_status st = lens_file_read(path, t, &why);
    free(path);
    if (st != HZ_OK)
        return why.loc.file ? hz_fail(err, "%s", why.message)
                            : fail_param(err, ent, "lensfile", why.message);
    return HZ_OK;
}

/* pbrt-v4's RealisticCamera::Create: the lens system focused at
 * "focusdistance", its exit pupil bounded. */
static hz_status read_realistic(scene_entity *ent, const film_params *film, realistic_lens *l,
                                hz_error *err)
{
    param_list *pl = &ent->params;
    char msg[256];
    double diameter = params_float(pl, "aperturediameter", 1.0);
    double focus = params_float(pl, "focusdistance", 10.0);
    aperture_shape shape = read_aperture_shape(ent);
    if (!positive_finite(diameter)) {
        snprintf(msg, sizeof msg, "\"aperturediameter\" must be finite and > 0 (mm), got %g",
                 diameter);
        return fail_param(err, ent, "aperturediameter", msg);
    }
    if (!positive_finite(focus)) {
        snprintf(msg, sizeof msg, "\"focusdistance\" must be finite and > 0, got %g", focus);
        return fail_param(err, ent, "focusdistance", msg);
    }
    lens_table t;
    if (read_lens_table(ent, &t, err) != HZ_OK)
        return HZ_ERROR;
    bool clamped;
    realistic_elements(&t, diameter, shape == APERTURE_IMAGE ? APERTURE_CIRCLE : shape,
                       film->diagonal, film->xres, film->yres, l, &clamped);
    if (shape == APERTURE_IMAGE && read_aperture_image(ent, l, err) != HZ_OK)
        return HZ_ERROR;
    if (clamped)
        hz_warn_at(stderr, params_loc(pl, "aperturediameter"),
                   "\"aperturediameter\" %g mm is larger than the lens's stop; using the "
                   "stop's diameter (as pbrt-v4)",
                   diameter);
    hz_error why;
    if (realistic_focus(l, focus, &why) != HZ_OK)
        return fail_param(err, ent, "focusdistance", why.message);
    realistic_bound_pupil(l, REALISTIC_PUPIL_SAMPLES);
    return HZ_OK;
}

/* The CameraFromWorld transforms at the start and end of the shutter
 * (moving when they differ). */
static void set_camera_motion(const camera_entity *e, camera_config *cfg)
{
    cfg->camera_from_world = e->camera_from_world;
    cfg->camera_from_world_end = e->camera_from_world_end;
    cfg->motion = memcmp(&e->camera_from_world.m, &e->camera_from_world_end.m,
                         sizeof e->camera_from_world.m) != 0;
    cfg->transform_start_time = e->transform_start_time;
    cfg->transform_end_time = e->transform_end_time;
}

/* "frameaspectratio" (default the film's; *frame) and the screen window
 * it gives, unless "screenwindow" sets it. */
static hz_status read_screen_window(scene_entity *ent, const film_params *film, double *frame,
                                    camera_config *cfg, hz_error *err)
{
    param_list *pl = &ent->params;
    char msg[256];
    *frame = params_float(pl, "frameaspectratio", (double)film->xres / (double)film->yres);
    if (!positive_finite(*frame)) {
        snprintf(msg, sizeof msg, "\"frameaspectratio\" must be finite and > 0, got %g", *frame);
        return fail_param(err, ent, "frameaspectratio", msg);
    }
    camera_screen_window_from_frame(*frame, cfg->screen_window);
    size_t n = 0;
    const double *sw = params_floats(pl, "screenwindow", &n);
    if (sw) {
        if (n != 4) {
            snprintf(msg, sizeof msg,
                     "\"screenwindow\" takes four values (xmin xmax ymin ymax), got %zu", n);
            return fail_param(err, ent, "screenwindow", msg);
        }
        memcpy(cfg->screen_window, sw, sizeof cfg->screen_window);
    }
    return HZ_OK;
}

/* A perspective camera's field of view: "fov", or the physical lens's
 * (read_physical_lens) when "focallength" is given. */
static hz_status read_fov(scene_entity *ent, double frame, bool physical, camera_config *cfg,
                          hz_error *err)
{
    param_list *pl = &ent->params;
    if (physical)
        return read_physical_lens(ent, frame, cfg, err);
    if (params_has(pl, "fstop"))
        return fail_param(err, ent, "fstop", "\"fstop\" needs \"focallength\"");
    cfg->fov = params_float(pl, "fov", cfg->fov);
    return HZ_OK;
}

/* camera_config_check's verdict, at the parameter to blame: values derived
 * from the physical lens are blamed on what the user wrote. */
static hz_status check_config(const scene_entity *ent, const camera_config *cfg, bool physical,
                              hz_error *err)
{
    hz_error why;
    const char *bad = camera_config_check(cfg, &why);
    if (!bad)
        return HZ_OK;
    if (physical && strcmp(bad, "fov") == 0)
        bad = "focallength";
    if (physical && strcmp(bad, "lensradius") == 0 && params_has(&ent->params, "fstop"))
        bad = "fstop";
    return fail_param(err, ent, bad, why.message);
}

/* The realistic camera: only the shutter among the other cameras'
 * parameters (pbrt-v4's CameraBaseParameters); the rest are unused, so
 * params_finish refuses them. */
static hz_status create_realistic(scene_entity *ent, const film_params *film, camera_config *cfg,
                                  camera *out, hz_error *err)
{
    realistic_lens *lens = calloc(1, sizeof *lens);
    if (!lens)
        return hz_fail_at(err, ent->loc, "out of memory");
    hz_status st = read_realistic(ent, film, lens, err);
    cfg->realistic = lens;
    if (st == HZ_OK && params_finish(&ent->params, "Camera \"realistic\"", err))
        st = HZ_ERROR;
    if (st == HZ_OK)
        st = check_config(ent, cfg, false, err);
    hz_error why;
    if (st == HZ_OK && camera_init(cfg, out, &why))
        st = hz_fail_at(err, ent->loc, "%s", why.message);
    if (st != HZ_OK)
        realistic_lens_free(lens); /* else the camera owns its aperture image */
    free(lens);
    cfg->realistic = NULL;
    return st;
}

hz_status camera_create(camera_entity *e, const film_params *film, camera *out, hz_error *err)
{
    scene_entity *ent = &e->entity;
    param_list *pl = &ent->params;
    camera_kind kind = CAMERA_PERSPECTIVE;
    if (read_kind(ent, &kind, err) != HZ_OK)
        return HZ_ERROR;
    if (film->xres < 1 || film->yres < 1)
        return hz_fail_at(err, ent->loc, "film resolution %dx%d must be at least 1x1",
                          film->xres, film->yres);

    camera_config cfg = camera_config_default(kind, film->xres, film->yres);
    if (kind == CAMERA_SPHERICAL && read_spherical(ent, &cfg, err) != HZ_OK)
        return HZ_ERROR;
    set_camera_motion(e, &cfg);
    cfg.shutter_open = params_float(pl, "shutteropen", cfg.shutter_open);
    cfg.shutter_close = params_float(pl, "shutterclose", cfg.shutter_close);
    if (kind == CAMERA_REALISTIC)
        return create_realistic(ent, film, &cfg, out, err);
    cfg.lens_radius = params_float(pl, "lensradius", cfg.lens_radius);
    cfg.focal_distance = params_float(pl, "focaldistance", cfg.focal_distance);
    double frame;
    if (read_screen_window(ent, film, &frame, &cfg, err) != HZ_OK)
        return HZ_ERROR;
    bool physical = kind == CAMERA_PERSPECTIVE && params_has(pl, "focallength");
    if (kind == CAMERA_PERSPECTIVE && read_fov(ent, frame, physical, &cfg, err) != HZ_OK)
        return HZ_ERROR;
    cfg.blades = params_int(pl, "blades", cfg.blades);
    cfg.blade_rotation = params_float(pl, "bladerotation", cfg.blade_rotation);

    char what[160];
    snprintf(what, sizeof what, "Camera \"%s\"", ent->type);
    if (params_finish(pl, what, err))
        return HZ_ERROR;
    if (check_config(ent, &cfg, physical, err) != HZ_OK)
        return HZ_ERROR;
    hz_error why;
    if (camera_init(&cfg, out, &why))
        return hz_fail_at(err, ent->loc, "%s", why.message);
    return HZ_OK;
}
