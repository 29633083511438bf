/* pbrt-v4's ProjectiveCamera, PerspectiveCamera and OrthographicCamera
 * (cameras.h, cameras.cpp) with camera-world render space. One deliberate
 * difference: the orthographic thin lens offsets the lens point by the ray's
 * film position (pbrt-v4 places every lens ray around the optical axis, the
 * bug reported as mmp/pbrt-v3#315 and carried into v4). */
#include "camera/camera.h"
#include "core/sampling.h"

#include <assert.h>
#include <math.h>

#include "camera/lens.h"

/* pbrt-v4's clip planes: they set screen z, which no ray uses, but keep
 * camera_from_raster identical to pbrt-v4's. */
#define PERSPECTIVE_NEAR 1e-2
#define PERSPECTIVE_FAR 1000.0

void camera_screen_window_from_frame(double frame, double out[4])
{
    if (frame > 1.0) {
        out[0] = -frame;
        out[1] = frame;
        out[2] = -1.0;
        out[3] = 1.0;
    } else {
        out[0] = -1.0;
        out[1] = 1.0;
        out[2] = -1.0 / frame;
        out[3] = 1.0 / frame;
    }
}

camera_config camera_config_default(camera_kind kind, int xres, int yres)
{
    camera_config c = {
        .kind = kind,
        .camera_from_world = transform_identity(),
        .camera_from_world_end = transform_identity(),
        .transform_start_time = 0.0,
        .transform_end_time = 1.0,
        .shutter_open = 0.0,
        .shutter_close = 1.0,
        .lens_radius = 0.0,
        .focal_distance = 1e6,
        .fov = 90.0,
        .blades = 0,
        .blade_rotation = 0.0,
        .xres = xres,
        .yres = yres,
    };
    camera_screen_window_from_frame((double)xres / (double)yres, c.screen_window);
    return c;
}

static bool mat4_is_finite(const mat4 *m)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (!isfinite(m->m[i][j]))
                return false;
    return true;
}

/* The kind, resolution and transforms: faults of no one parameter (""). */
static const char *check_kind_and_transforms(const camera_config *c, hz_error *err)
{
    if (c->kind != CAMERA_PERSPECTIVE && c->kind != CAMERA_ORTHOGRAPHIC &&
        c->kind != CAMERA_SPHERICAL && c->kind != CAMERA_REALISTIC) {
        hz_fail(err, "unknown camera kind %d", (int)c->kind);
        return "";
    }
    if (c->kind == CAMERA_REALISTIC && (!c->realistic || c->realistic->count < 1)) {
        hz_fail(err, "the realistic camera has no lens system");
        return "lensfile";
    }
    if (c->xres < 1 || c->yres < 1) {
        hz_fail(err, "film resolution %dx%d must be at least 1x1", c->xres, c->yres);
        return "";
    }
    if (!mat4_is_finite(&c->camera_from_world.m) || !mat4_is_finite(&c->camera_from_world.m_inv)) {
        hz_fail(err, "the camera transform is not finite or not invertible");
        return "";
    }
    if (c->motion && (!mat4_is_finite(&c->camera_from_world_end.m) ||
                      !mat4_is_finite(&c->camera_from_world_end.m_inv))) {
        hz_fail(err, "the camera's end transform is not finite or not invertible");
        return "";
    }
    if (c->motion && !(isfinite(c->transform_start_time) && isfinite(c->transform_end_time) &&
                       c->transform_end_time >= c->transform_start_time)) {
        hz_fail(err, "TransformTimes %g %g must be finite and increasing", c->transform_start_time,
                c->transform_end_time);
        return "";
    }
    return NULL;
}

static const char *check_shutter(const camera_config *c, hz_error *err)
{
    if (!isfinite(c->shutter_open)) {
        hz_fail(err, "\"shutteropen\" must be finite, got %g", c->shutter_open);
        return "shutteropen";
    }
    if (!isfinite(c->shutter_close)) {
        hz_fail(err, "\"shutterclose\" must be finite, got %g", c->shutter_close);
        return "shutterclose";
    }
    /* pbrt-v4 swaps the two with a warning; a reversed shutter is far more
     * likely a typo than an intent, and it silently changes the exposure. */
    if (c->shutter_open > c->shutter_close) {
        hz_fail(err, "\"shutteropen\" %g is after \"shutterclose\" %g", c->shutter_open,
                c->shutter_close);
        return "shutteropen";
    }
    return NULL;
}

static const char *check_screen_window(const double w[4], hz_error *err)
{
    for (int i = 0; i < 4; ++i) {
        if (!isfinite(w[i])) {
            hz_fail(err, "\"screenwindow\" values must be finite");
            return "screenwindow";
        }
    }
    if (!(w[1] > w[0]) || !(w[3] > w[2]) || !isfinite(w[1] - w[0]) || !isfinite(w[3] - w[2])) {
        hz_fail(err,
                "\"screenwindow\" [%g %g %g %g] has an empty extent (need xmin < xmax and "
                "ymin < ymax)",
                w[0], w[1], w[2], w[3]);
        return "screenwindow";
    }
    return NULL;
}

/* The lens, focus, field of view and aperture. */
static const char *check_lens(const camera_config *c, hz_error *err)
{
    if ((c->kind == CAMERA_SPHERICAL || c->kind == CAMERA_REALISTIC) && c->lens_radius != 0.0) {
        hz_fail(err, "the spherical and realistic cameras have no thin lens (\"lensradius\" "
                     "must be 0)");
        return "lensradius";
    }
    if (!isfinite(c->lens_radius) || c->lens_radius < 0.0 || c->lens_radius > HZ_MAX_COORD) {
        hz_fail(err, "\"lensradius\" must be in [0, %g], got %g", HZ_MAX_COORD, c->lens_radius);
        return "lensradius";
    }
    if (!isfinite(c->focal_distance) || c->focal_distance <= 0.0) {
        hz_fail(err, "\"focaldistance\" must be finite and > 0, got %g", c->focal_distance);
        return "focaldistance";
    }
    if (c->kind == CAMERA_PERSPECTIVE && !(c->fov > 0.0 && c->fov < 180.0)) {
        hz_fail(err, "\"fov\" must be in (0, 180) degrees, got %g", c->fov);
        return "fov";
    }
    if (c->blades < 0 || c->blades == 1 || c->blades == 2) {
        hz_fail(err, "\"blades\" must be 0 (round aperture) or at least 3, got %d", c->blades);
        return "blades";
    }
    if (!isfinite(c->blade_rotation)) {
        hz_fail(err, "\"bladerotation\" must be finite, got %g", c->blade_rotation);
        return "bladerotation";
    }
    return NULL;
}

const char *camera_config_check(const camera_config *c, hz_error *err)
{
    const char *bad = check_kind_and_transforms(c, err);
    if (!bad)
        bad = check_shutter(c, err);
    if (!bad)
        bad = check_screen_window(c->screen_window, err);
    if (!bad)
        bad = check_lens(c, err);
    return bad;
}

/* pbrt-v4 ProjectiveCamera: screen -> NDC ([0,1]^2, y flipped so raster y grows
 * downwards from the top-left corner) -> raster. */
static transform raster_from_screen(const double w[4], int xres, int yres)
{
    transform ndc_from_screen =
        transform_compose(transform_scale(v3(1.0 / (w[1] - w[0]), 1.0 / (w[3] - w[2]), 1.0)),
                          transform_translate(v3(-w[0], -w[3], 0.0)));
    transform raster_from_ndc = transform_scale(v3((double)xres, -(double)yres, 1.0));
    return transform_compose(raster_from_ndc, ndc_from_screen);
}

/* camera.pinhole: camera_from_raster maps film point (x, y, 0) to the
 * homogeneous h = A (x, y, 1), the camera-space point h / w with w constant
 * over the film (the perspective's inverse at z = 0) and positive, so the
 * direction is normalize(A (x, y, 1)); render_from_camera's rotation R
 * (affine: no homogeneous row) folds in as R A. */
static void pinhole_fold(camera *c)
{
    const transform *cr = &c->camera_from_raster, *rc = &c->render_from_camera;
    const double(*m)[4] = cr->m.m;
    const double(*r)[4] = rc->m.m;
    c->pinhole = false;
    if (c->kind != CAMERA_PERSPECTIVE || c->lens_radius > 0.0 || c->motion)
        return;
    if (m[3][0] != 0.0 || m[3][1] != 0.0 || !(m[3][3] > 0.0) || r[3][0] != 0.0 ||
        r[3][1] != 0.0 || r[3][2] != 0.0 || r[3][3] != 1.0)
        return;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            int col = j == 2 ? 3 : j; /* film z is 0: A's columns x, y and the constant */
            c->pinhole_from_film[i][j] =
                r[i][0] * m[0][col] + r[i][1] * m[1][col] + r[i][2] * m[2][col];
        }
    c->pinhole_o = v3(r[0][3], r[1][3], r[2][3]);
    c->pinhole = true;
}

hz_status camera_init(const camera_config *cfg, camera *out, hz_error *err)
{
    if (camera_config_check(cfg, err))
        return HZ_ERROR;
    camera c = {0};
    c.kind = cfg->kind;
    c.shutter_open = cfg->shutter_open;
    c.shutter_close = cfg->shutter_close;
    c.medium = -1;

    /* Camera-world render space: world translated so the camera sits at the
     * origin. Both factors are exact here (the translation cancels the camera
     * position bit for bit), so a camera far from the world origin gets the
     * same render-space rays as one at the origin. */
    transform world_from_camera = transform_inverse(cfg->camera_from_world);
    animated_transform world_from_camera_motion = animated_transform_static(world_from_camera);
    if (cfg->motion)
        world_from_camera_motion = animated_transform_make(
            world_from_camera, cfg->transform_start_time,
            transform_inverse(cfg->camera_from_world_end), cfg->transform_end_time);
    c.motion = world_from_camera_motion.animated;
    /* pbrt-v4: the camera's position at the middle of the transform times. */
    transform world_from_camera_mid = animated_transform_at(
        &world_from_camera_motion, 0.5 * (cfg->transform_start_time + cfg->transform_end_time));
    vec3 p_camera = transform_point(&world_from_camera_mid, v3(0.0, 0.0, 0.0));
    c.world_from_render = transform_translate(p_camera);
    transform render_from_world = transform_inverse(c.world_from_render);
    c.render_from_camera = transform_compose(render_from_world, world_from_camera);
    c.render_from_camera_motion = animated_transform_static(c.render_from_camera);
    if (c.motion)
        c.render_from_camera_motion = animated_transform_make(
            c.render_from_camera, cfg->transform_start_time,
            transform_compose(render_from_world, world_from_camera_motion.end),
            cfg->transform_end_time);

    for (int i = 0; i < 4; ++i)
        c.screen_window[i] = cfg->screen_window[i];
    c.lens_radius = cfg->lens_radius;
    c.focal_distance = cfg->focal_distance;
    c.fov = cfg->kind == CAMERA_PERSPECTIVE ? cfg->fov : 0.0;
    c.blades = cfg->blades;
    c.blade_rotation = hz_radians(cfg->blade_rotation);
    c.xres = cfg->xres;
    c.yres = cfg->yres;
    c.equirect = cfg->equirect;
    if (cfg->kind == CAMERA_REALISTIC)
        c.realistic = *cfg->realistic;
    if (cfg->kind == CAMERA_SPHERICAL || cfg->kind == CAMERA_REALISTIC) {
        /* no projection: directions from the film point (spherical) or
         * through the lens system (realistic) */
        c.screen_from_camera = c.camera_from_raster = c.raster_from_camera = transform_identity();
        *out = c;
        return HZ_OK;
    }

    c.screen_from_camera = cfg->kind == CAMERA_PERSPECTIVE
                               ? transform_perspective(cfg->fov, PERSPECTIVE_NEAR, PERSPECTIVE_FAR)
                               : transform_orthographic(0.0, 1.0);
    transform screen_from_raster =
        transform_inverse(raster_from_screen(c.screen_window, c.xres, c.yres));
    c.camera_from_raster =
        transform_compose(transform_inverse(c.screen_from_camera), screen_from_raster);
    c.raster_from_camera = transform_inverse(c.camera_from_raster);

    vec3 p0 = transform_point(&c.camera_from_raster, v3(0.0, 0.0, 0.0));
    c.dx_camera = v3_sub(transform_point(&c.camera_from_raster, v3(1.0, 0.0, 0.0)), p0);
    c.dy_camera = v3_sub(transform_point(&c.camera_from_raster, v3(0.0, 1.0, 0.0)), p0);

    if (!mat4_is_finite(&c.camera_from_raster.m) || !v3_is_finite(c.dx_camera) ||
        !v3_is_finite(c.dy_camera))
        return hz_fail(err, "the camera's projection is degenerate (fov %g, screen window "
                            "[%g %g %g %g], %dx%d)",
                       cfg->fov, c.screen_window[0], c.screen_window[1], c.screen_window[2],
                       c.screen_window[3], c.xres, c.yres);
    pinhole_fold(&c);
    *out = c;
    return HZ_OK;
}

void camera_free(camera *c)
{
    if (c->kind == CAMERA_REALISTIC)
        realistic_lens_free(&c->realistic);
}

double camera_imaging_ratio(const camera *c, const film_params *film)
{
    return (c->shutter_close - c->shutter_open) * film->iso / 100.0;
}

/* pbrt-v4's SphericalCamera direction through film point p (raster units):
 * (u, v) = p / resolution on the equal-area square (wrapped across its edges)
 * or as longitude 2 pi u and colatitude pi v, then y and z swapped so that
 * the image's centre row circles the camera's horizon. */
static vec3 spherical_direction(const camera *c, vec2 p)
{
    vec2 uv = v2(p.x / c->xres, p.y / c->yres);
    vec3 d;
    if (c->equirect) {
        double theta = HZ_PI * uv.y, phi = 2.0 * HZ_PI * uv.x;
        d = v3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
    } else {
        d = equal_area_square_to_sphere(equal_area_wrap(uv));
    }
    return v3(d.x, d.z, d.y);
}

/* The camera-space ray, pbrt-v4's GenerateRay before RenderFromCamera. Also
 * hands back the film point and lens point the differentials reuse. */
static void camera_space_ray(const camera *c, camera_sample s, vec3 *o, vec3 *d, vec3 *p_camera,
                             vec2 *p_lens)
{
    *p_camera = transform_point(&c->camera_from_raster, v3(s.p_film.x, s.p_film.y, 0.0));
    switch (c->kind) {
    case CAMERA_REALISTIC: /* realistic_render_ray: never here */
    case CAMERA_SPHERICAL:
        *o = v3(0.0, 0.0, 0.0);
        *d = spherical_direction(c, s.p_film);
        break;
    case CAMERA_PERSPECTIVE:
        *o = v3(0.0, 0.0, 0.0);
        *d = v3_normalize(*p_camera);
        break;
    case CAMERA_ORTHOGRAPHIC:
        *o = *p_camera;
        *d = v3(0.0, 0.0, 1.0);
        break;
    }
    /* Branch rather than scale by a zero radius: lensradius 0 stays exactly the
     * pinhole ray (and skips the aperture sample). */
    if (c->lens_radius > 0.0) {
        *p_lens = lens_sample_aperture(c->lens_radius, c->blades, c->blade_rotation, s.p_lens);
        double ft = c->focal_distance / d->z;
        vec3 p_focus = v3_add(*o, v3_scale(*d, ft));
        *o = c->kind == CAMERA_PERSPECTIVE
                 ? v3(p_lens->x, p_lens->y, 0.0)
                 : v3(p_camera->x + p_lens->x, p_camera->y + p_lens->y, 0.0);
        *d = v3_normalize(v3_sub(p_focus, *o));
    }
}

/* render_from_camera at the ray's time: a moving camera interpolates into
 * *moving; a static one is used in place (not copied for every ray). */
static const transform *render_from_camera_at(const camera *c, double time, transform *moving)
{
    if (!c->motion)
        return &c->render_from_camera;
    *moving = animated_transform_at(&c->render_from_camera_motion, time);
    return moving;
}

static ray render_ray(const camera *c, const transform *render_from_camera, vec3 o, vec3 d,
                      double time)
{
    ray r;
    r.o = transform_point(render_from_camera, o);
    r.d = v3_normalize(transform_vector(render_from_camera, d));
    r.time = time;
    r.medium = c->medium;
    return r;
}

bool camera_raster_bounds(const camera *c, vec3 lo, vec3 hi, double out[4])
{
    if (c->motion || camera_has_lens(c) ||
        (c->kind != CAMERA_PERSPECTIVE && c->kind != CAMERA_ORTHOGRAPHIC))
        return false;
    transform camera_from_render = transform_inverse(c->render_from_camera);
    out[0] = out[2] = INFINITY;
    out[1] = out[3] = -INFINITY;
    for (int k = 0; k < 8; ++k) {
        vec3 p = v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
        vec3 pc = transform_point(&camera_from_render, p);
        /* A perspective camera's rays leave the eye toward z > 0: a corner
         * at or behind it has no image (the box may surround the eye). */
        if (c->kind == CAMERA_PERSPECTIVE && !(pc.z > 1e-9 * v3_length(pc)))
            return false;
        vec3 r = transform_point(&c->raster_from_camera, pc);
        if (!(isfinite(r.x) && isfinite(r.y)))
            return false;
        out[0] = fmin(out[0], r.x);
        out[1] = fmax(out[1], r.x);
        out[2] = fmin(out[2], r.y);
        out[3] = fmax(out[3], r.y);
    }
    return true;
}

/* The realistic camera's ray for s, in render space, and its weight (0: none). */
static double realistic_render_ray(const camera *c, camera_sample s, ray *out)
{
    lens_ray r;
    double w = realistic_generate(&c->realistic, s.p_film, s.p_lens, c->xres, c->yres, &r);
    if (!(w > 0.0) || !isfinite(w))
        return 0.0;
    double time = hz_lerp(s.time, c->shutter_open, c->shutter_close);
    transform moving;
    const transform *rfc = render_from_camera_at(c, time, &moving);
    *out = render_ray(c, rfc, r.o, r.d, time);
    return w;
}

double camera_generate_ray_weighted(const camera *c, camera_sample s, ray *out)
{
    if (c->kind == CAMERA_REALISTIC)
        return realistic_render_ray(c, s, out);
    return camera_generate_ray(c, s, out) ? 1.0 : 0.0;
}

/* pbrt-v4's CameraBase::GenerateRayDifferential: the ray a twentieth of a
 * pixel over (or back, if that one is blocked), its difference scaled up to
 * a pixel. */
static bool realistic_differential(const camera *c, camera_sample s, const ray *main, int axis,
                                   vec3 *o, vec3 *d)
{
    const double eps[2] = {0.05, -0.05};
    for (int k = 0; k < 2; ++k) {
        camera_sample shifted = s;
        if (axis == 0)
            shifted.p_film.x += eps[k];
        else
            shifted.p_film.y += eps[k];
        ray r;
        if (realistic_render_ray(c, shifted, &r) > 0.0) {
            *o = v3_add(main->o, v3_scale(v3_sub(r.o, main->o), 1.0 / eps[k]));
            *d = v3_add(main->d, v3_scale(v3_sub(r.d, main->d), 1.0 / eps[k]));
            return true;
        }
    }
    return false;
}

double camera_generate_ray_differential_weighted(const camera *c, camera_sample s,
                                                 ray_differential *out)
{
    if (c->kind != CAMERA_REALISTIC)
        return camera_generate_ray_differential(c, s, out) ? 1.0 : 0.0;
    double w = realistic_render_ray(c, s, &out->r);
    if (w == 0.0)
        return 0.0;
    out->has_differentials =
        realistic_differential(c, s, &out->r, 0, &out->rx_o, &out->rx_d) &&
        realistic_differential(c, s, &out->r, 1, &out->ry_o, &out->ry_d);
    return w;
}

bool camera_generate_ray(const camera *c, camera_sample s, ray *out)
{
    if (c->kind == CAMERA_REALISTIC)
        return realistic_render_ray(c, s, out) > 0.0;
    if (c->pinhole) {
        const double(*a)[3] = c->pinhole_from_film;
        double x = s.p_film.x, y = s.p_film.y;
        out->o = c->pinhole_o;
        out->d = v3_normalize(v3(a[0][0] * x + a[0][1] * y + a[0][2],
                                 a[1][0] * x + a[1][1] * y + a[1][2],
                                 a[2][0] * x + a[2][1] * y + a[2][2]));
        out->time = hz_lerp(s.time, c->shutter_open, c->shutter_close);
        out->medium = c->medium;
        return true;
    }
    vec3 o, d, p_camera;
    vec2 p_lens;
    camera_space_ray(c, s, &o, &d, &p_camera, &p_lens);
    double time = hz_lerp(s.time, c->shutter_open, c->shutter_close);
    transform moving;
    const transform *rfc = render_from_camera_at(c, time, &moving);
    *out = render_ray(c, rfc, o, d, time);
    return true;
}

/* The ray through film point p_camera + delta and the same lens point. */
static void shifted_ray(const camera *c, vec3 p_camera, vec3 delta, vec2 p_lens, vec3 o_main,
                        vec3 d_main, vec3 *o, vec3 *d)
{
    vec3 p = v3_add(p_camera, delta);
    switch (c->kind) {
    case CAMERA_REALISTIC:
    case CAMERA_SPHERICAL:
        assert(!"spherical and realistic differentials are finite differences");
        break;
    case CAMERA_PERSPECTIVE:
        if (c->lens_radius > 0.0) {
            vec3 dir = v3_normalize(p);
            vec3 p_focus = v3_scale(dir, c->focal_distance / dir.z);
            *o = v3(p_lens.x, p_lens.y, 0.0);
            *d = v3_normalize(v3_sub(p_focus, *o));
        } else {
            *o = o_main;
            *d = v3_normalize(p);
        }
        break;
    case CAMERA_ORTHOGRAPHIC:
        if (c->lens_radius > 0.0) {
            vec3 p_focus = v3_add(p, v3(0.0, 0.0, c->focal_distance));
            *o = v3(p.x + p_lens.x, p.y + p_lens.y, 0.0);
            *d = v3_normalize(v3_sub(p_focus, *o));
        } else {
            *o = v3_add(o_main, delta);
            *d = d_main;
        }
        break;
    }
}

bool camera_generate_ray_differential(const camera *c, camera_sample s, ray_differential *out)
{
    if (c->kind == CAMERA_REALISTIC)
        return camera_generate_ray_differential_weighted(c, s, out) > 0.0;
    if (c->pinhole) { /* the rays through the film points one pixel over */
        camera_sample sx = s, sy = s;
        sx.p_film.x += 1.0;
        sy.p_film.y += 1.0;
        ray rx, ry;
        camera_generate_ray(c, s, &out->r);
        camera_generate_ray(c, sx, &rx);
        camera_generate_ray(c, sy, &ry);
        out->rx_o = rx.o;
        out->rx_d = rx.d;
        out->ry_o = ry.o;
        out->ry_d = ry.d;
        out->has_differentials = true;
        return true;
    }
    vec3 o, d, p_camera;
    vec2 p_lens = v2(0.0, 0.0);
    camera_space_ray(c, s, &o, &d, &p_camera, &p_lens);
    double time = hz_lerp(s.time, c->shutter_open, c->shutter_close);
    transform moving;
    const transform *rfc = render_from_camera_at(c, time, &moving);
    out->r = render_ray(c, rfc, o, d, time);

    vec3 ox, dx, oy, dy;
    if (c->kind == CAMERA_SPHERICAL) {
        /* pbrt-v4's finite difference: a twentieth of a pixel, scaled up. */
        const double eps = 0.05;
        vec3 ddx = v3_sub(spherical_direction(c, v2(s.p_film.x + eps, s.p_film.y)), d);
        vec3 ddy = v3_sub(spherical_direction(c, v2(s.p_film.x, s.p_film.y + eps)), d);
        ox = oy = o;
        dx = v3_add(d, v3_scale(ddx, 1.0 / eps));
        dy = v3_add(d, v3_scale(ddy, 1.0 / eps));
    } else {
        shifted_ray(c, p_camera, c->dx_camera, p_lens, o, d, &ox, &dx);
        shifted_ray(c, p_camera, c->dy_camera, p_lens, o, d, &oy, &dy);
    }
    out->rx_o = transform_point(rfc, ox);
    out->rx_d = v3_normalize(transform_vector(rfc, dx));
    out->ry_o = transform_point(rfc, oy);
    out->ry_d = v3_normalize(transform_vector(rfc, dy));
    out->has_differentials = true;
    return true;
}
