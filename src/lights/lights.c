/* Lights from the scene's LightSource and AreaLightSource entities (their
 * parameters, images and power), and what the integrators ask of a light
 * besides its samples (light_sample.c): emitted radiance, portals, the
 * intensity of point lights with an image, delta lights, power. */
#include "lights/lights.h"

#include "core/path.h"
#include "core/ray.h"
#include "lights/envmap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- factories ---- */

/* pbrt-v4 `power` for point and spot lights: scale *= power / k_e, where k_e
 * is the power of a unit-intensity light (4π for a point light). pbrt-v4
 * first divides scale by SpectrumToPhotometric(I), which for an RGB
 * illuminant looks only at the colour space's illuminant and ignores the RGB
 * value; so in RGB terms I_final = I_rgb * scale * power / k_e (the RGB value
 * is not normalised to unit luminance). */
static rgb apply_power(rgb I, double scale, double power, double k_e)
{
    if (power > 0.0)
        scale *= power / k_e;
    return rgb_scale(I, scale);
}

/* The image of a light, named relative to the scene file that names it.
 * Negative texels are read as 0, as pbrt-v4 clamps the RGB it looks up, but
 * with a warning: they are most likely an error in the file. */
static hz_status load_image(param_list *pl, const char *filename, bool square,
                            light_image **out, FILE *warn, hz_error *err)
{
    file_loc at = params_loc(pl, "filename");
    char *path = path_of_scene_file(at, filename);
    if (!path)
        return hz_fail_at(err, at, "out of memory");
    hz_error e;
    hz_status st = light_image_from_exr(path, square, out, &e);
    if (st != HZ_OK)
        hz_fail_at(err, at, "light \"filename\": %s", e.message);
    size_t negative = st == HZ_OK ? light_image_negative_texels(*out) : 0;
    if (negative > 0) {
        int w, h;
        light_image_size(*out, &w, &h);
        hz_warn_at(warn, at,
                   "light \"filename\": %s: %zu of %zu texels have a negative value; read as 0",
                   path, negative, (size_t)w * (size_t)h);
    }
    free(path);
    return st;
}

/* What each kind's factory reads: the LightSource's parameters and place,
 * and its frames. */
typedef struct {
    param_list *pl;
    file_loc loc;
    transform render_from_world, render_from_light;
    FILE *warn; /* warnings (NULL: none) */
} light_source;

/* The "I", "scale" and "power" of the lights that have an intensity. */
typedef struct {
    rgb I;
    double scale, power;
} light_intensity;

static light_intensity read_intensity(param_list *pl)
{
    light_intensity in;
    in.I = params_illuminant(pl, "I", rgb_grey(1.0));
    in.scale = params_float(pl, "scale", 1.0);
    in.power = params_float(pl, "power", -1.0);
    return in;
}

static hz_status point_from_params(const light_source *src, light *out, hz_error *err)
{
    (void)err;
    param_list *pl = src->pl;
    light_intensity in = read_intensity(pl);
    vec3 from = params_point3(pl, "from", v3(0, 0, 0));
    out->kind = LIGHT_POINT;
    out->emit = apply_power(in.I, in.scale, in.power, 4.0 * HZ_PI);
    out->point.p = transform_point(&src->render_from_light, from);
    return HZ_OK;
}

/* pbrt-v4's GoniometricLight: a point light at the light space's origin
 * whose intensity toward w is I scale times the image's channel average at
 * the equal-area point of w, with y and z swapped. */
static hz_status goniometric_from_params(const light_source *src, light *out, hz_error *err)
{
    param_list *pl = src->pl;
    light_intensity in = read_intensity(pl);
    const char *filename = params_string(pl, "filename", NULL);
    if (!filename)
        return hz_fail_at(err, src->loc,
                          "goniometric light needs \"string filename\" (pbrt-v4 renders "
                          "it black without one)");
    if (load_image(pl, filename, true, &out->point.image, src->warn, err) != HZ_OK)
        return HZ_ERROR;
    out->kind = LIGHT_POINT;
    double mean = light_image_mean(out->point.image);
    double scale = in.scale;
    if (in.power > 0.0 && mean > 0.0)
        scale *= in.power / (4.0 * HZ_PI * mean);
    out->emit = rgb_scale(in.I, scale);
    out->point.p = transform_point(&src->render_from_light, v3(0, 0, 0));
    /* its own inverse */
    const mat4 swap = {{{1, 0, 0, 0}, {0, 0, 1, 0}, {0, 1, 0, 0}, {0, 0, 0, 1}}};
    const transform swap_yz = {swap, swap};
    out->point.light_from_render =
        transform_compose(swap_yz, transform_inverse(src->render_from_light));
    return HZ_OK;
}

/* pbrt-v4's ProjectionLight: a point light at the light space's origin
 * (y flipped) that projects its image through a perspective window of `fov`
 * (the image's aspect ratio; the shorter side spans [-1, 1]) along +z; the
 * intensity toward w is scale times the nearest texel, no cosine falloff.
 * "power": scale *= power / (A mean(luminance cos^3)), A the window's area
 * at unit distance. */
static hz_status projection_from_params(const light_source *src, light *out, hz_error *err)
{
    param_list *pl = src->pl;
    transform render_from_light = src->render_from_light;
    double scale = params_float(pl, "scale", 1.0);
    double power = params_float(pl, "power", -1.0);
    double fov = params_float(pl, "fov", 90.0);
    if (!(fov > 0.0 && fov < 180.0))
        params_reject(pl, "fov", "projection light \"fov\" must be in (0, 180), got %g", fov);
    const char *filename = params_string(pl, "filename", NULL);
    if (!filename)
        return hz_fail_at(err, src->loc, "projection light needs \"string filename\"");
    if (pl->failed)
        return HZ_OK; /* params_finish reports it */
    if (load_image(pl, filename, false, &out->point.image, src->warn, err) != HZ_OK)
        return HZ_ERROR;
    int w, h;
    light_image_size(out->point.image, &w, &h);
    double aspect = (double)w / h;
    double *sc = out->point.screen;
    if (aspect > 1.0) {
        sc[0] = -aspect, sc[1] = aspect, sc[2] = -1.0, sc[3] = 1.0;
    } else {
        sc[0] = -1.0, sc[1] = 1.0, sc[2] = -1.0 / aspect, sc[3] = 1.0 / aspect;
    }
    double t = tan(fov * HZ_PI / 360.0);
    out->point.inv_tan = 1.0 / t;
    if (power > 0.0) {
        double sum = 0.0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                double px = sc[0] + (sc[1] - sc[0]) * (x + 0.5) / w;
                double py = sc[2] + (sc[3] - sc[2]) * (y + 0.5) / h;
                double c = 1.0 / sqrt(1.0 + (px * px + py * py) * t * t); /* cos theta */
                rgb v = light_image_lookup(out->point.image, v2((x + 0.5) / w, (y + 0.5) / h));
                sum += (0.2126 * v.r + 0.7152 * v.g + 0.0722 * v.b) * c * c * c;
            }
        double area = 4.0 * t * t * (aspect > 1.0 ? aspect : 1.0 / aspect);
        if (sum > 0.0)
            scale *= power / (area * sum / ((double)w * h));
    }
    out->kind = LIGHT_POINT;
    out->emit = rgb_grey(scale);
    out->point.p = transform_point(&render_from_light, v3(0, 0, 0));
    out->point.projection = true;
    const mat4 flip = {{{1, 0, 0, 0}, {0, -1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
    const transform flip_y = {flip, flip}; /* its own inverse */
    out->point.light_from_render = transform_compose(flip_y, transform_inverse(render_from_light));
    return HZ_OK;
}

/* A spot light's frame: pbrt-v4's renderFromLight * Translate(from) *
 * Inverse(Frame::FromZ(dir)), its cone along +z. */
static transform spot_render_from_cone(transform render_from_light, vec3 from, vec3 to)
{
    vec3 z = v3_sub(to, from);
    z = v3_length(z) > 0.0 ? v3_normalize(z) : v3(0, 0, 1);
    vec3 x, y;
    v3_basis(z, &x, &y);
    mat4 world_from_frame = mat4_identity();
    vec3 cols[3] = {x, y, z};
    for (int c = 0; c < 3; ++c) {
        world_from_frame.m[0][c] = cols[c].x;
        world_from_frame.m[1][c] = cols[c].y;
        world_from_frame.m[2][c] = cols[c].z;
    }
    transform frame = {world_from_frame, mat4_transpose(world_from_frame)};
    return transform_compose(render_from_light,
                             transform_compose(transform_translate(from), frame));
}

static hz_status spot_from_params(const light_source *src, light *out, hz_error *err)
{
    (void)err;
    param_list *pl = src->pl;
    light_intensity in = read_intensity(pl);
    double cone = params_float(pl, "coneangle", 30.0);
    double delta = params_float(pl, "conedeltaangle", 5.0);
    vec3 from = params_point3(pl, "from", v3(0, 0, 0));
    vec3 to = params_point3(pl, "to", v3(0, 0, 1));
    if (v3_length(v3_sub(to, from)) == 0.0)
        params_reject(pl, "to", "spot light \"from\" and \"to\" coincide");
    if (delta < 0.0 || delta > cone)
        params_reject(pl, "conedeltaangle", "must be within [0, coneangle]");
    out->kind = LIGHT_SPOT;
    out->spot.cos_falloff_end = cos(hz_radians(cone));
    out->spot.cos_falloff_start = cos(hz_radians(cone - delta));
    double k_e = 2.0 * HZ_PI *
                 ((1.0 - out->spot.cos_falloff_start) +
                  (out->spot.cos_falloff_start - out->spot.cos_falloff_end) / 2.0);
    out->emit = apply_power(in.I, in.scale, in.power, k_e);
    transform final = spot_render_from_cone(src->render_from_light, from, to);
    out->spot.p = transform_point(&final, v3(0, 0, 0));
    out->spot.light_from_render = transform_inverse(final);
    return HZ_OK;
}

static hz_status distant_from_params(const light_source *src, light *out, hz_error *err)
{
    (void)err;
    param_list *pl = src->pl;
    rgb L = params_illuminant(pl, "L", rgb_grey(1.0));
    double scale = params_float(pl, "scale", 1.0);
    vec3 from = params_point3(pl, "from", v3(0, 0, 0));
    vec3 to = params_point3(pl, "to", v3(0, 0, 1));
    /* pbrt-v4's distant light takes "illuminance" (not "power"): the
     * illuminance on a patch facing the light, so L *= E_v. */
    double illum = params_float(pl, "illuminance", -1.0);
    if (v3_length(v3_sub(from, to)) == 0.0)
        params_reject(pl, "to", "distant light \"from\" and \"to\" coincide");
    if (illum > 0.0)
        scale *= illum;
    out->kind = LIGHT_DISTANT;
    out->emit = rgb_scale(L, scale);
    vec3 w = transform_vector(&src->render_from_light, v3_sub(from, to));
    out->distant.w = v3_length(w) > 0.0 ? v3_normalize(w) : v3(0, 0, 1);
    return HZ_OK;
}

/* pbrt-v4's "point3 portal" (four world-space corners of a rectangle): the
 * light then arrives only through it. A constant sky becomes a 1x1 image,
 * as pbrt-v4 does, so that the image lights' paths (which know the ray's
 * origin) handle it. */
static hz_status read_portal(param_list *pl, transform render_from_world,
                             transform render_from_light, light *out, hz_error *err)
{
    size_t n = 0;
    const double *c = params_point3s(pl, "portal", &n);
    if (!c)
        return HZ_OK; /* a type error, reported by params_finish */
    if (n != 4)
        return hz_fail_at(err, params_loc(pl, "portal"),
                          "infinite light \"portal\" takes 4 points, got %zu", n);
    vec3 p[4];
    for (int i = 0; i < 4; ++i)
        p[i] = transform_point(&render_from_world, v3(c[3 * i], c[3 * i + 1], c[3 * i + 2]));
    vec3 e01 = v3_sub(p[1], p[0]), e03 = v3_sub(p[3], p[0]);
    vec3 e32 = v3_sub(p[2], p[3]), e12 = v3_sub(p[2], p[1]);
    double lx = v3_length(e03), ly = v3_length(e01);
    /* A rectangle, as pbrt-v4 expects (it only warns): opposite edges equal,
     * adjacent ones perpendicular. */
    double tol = 1e-3 * fmax(lx, ly);
    if (!(lx > 0.0 && ly > 0.0) || v3_length(v3_sub(e01, e32)) > tol ||
        v3_length(v3_sub(e03, e12)) > tol || fabs(v3_dot(e01, e03)) > tol * fmax(lx, ly))
        return hz_fail_at(err, params_loc(pl, "portal"),
                          "infinite light \"portal\" must be a rectangle (corners in order)");
    if (!out->infinite.image) {
        if (light_image_white(&out->infinite.image, err) != HZ_OK)
            return HZ_ERROR;
        out->infinite.render_from_light = render_from_light;
        out->infinite.light_from_render = transform_inverse(render_from_light);
    }
    out->infinite.portal = true;
    out->infinite.portal_p0 = p[0];
    out->infinite.portal_ex = v3_scale(e03, 1.0 / lx);
    out->infinite.portal_ey = v3_scale(e01, 1.0 / ly);
    out->infinite.portal_ez = v3_normalize(v3_cross(e03, e01));
    out->infinite.portal_len_x = lx;
    out->infinite.portal_len_y = ly;
    return HZ_OK;
}

static hz_status infinite_from_params(const light_source *src, light *out, hz_error *err)
{
    param_list *pl = src->pl;
    const char *filename = params_string(pl, "filename", NULL);
    if (filename && params_has(pl, "L"))
        return hz_fail_at(err, params_loc(pl, "L"),
                          "infinite light: \"L\" and \"filename\" cannot both be given");
    rgb L = params_illuminant(pl, "L", rgb_grey(1.0));
    double scale = params_float(pl, "scale", 1.0);
    double illum = params_float(pl, "illuminance", -1.0);
    out->kind = LIGHT_INFINITE;
    if (filename) {
        if (load_image(pl, filename, true, &out->infinite.image, src->warn, err) != HZ_OK)
            return HZ_ERROR;
        L = rgb_grey(1.0);
        /* pbrt-v4 scales the map to the asked illuminance on an upward
         * patch (light_image_illuminance). */
        double k_e = illum > 0.0 ? light_image_illuminance(out->infinite.image) : 0.0;
        if (illum > 0.0 && k_e > 0.0)
            scale *= illum / k_e;
        out->infinite.render_from_light = src->render_from_light;
        out->infinite.light_from_render = transform_inverse(src->render_from_light);
    } else if (illum > 0.0) {
        /* pbrt-v4: illuminance of a uniform sky on an upward patch is π L. */
        scale *= illum / HZ_PI;
    }
    /* pbrt-v4 makes an "L" with a portal a 1x1 image of the spectrum's
     * RGB as it holds it, without the division by its luminance that
     * its other lights make: a blackbody's luminance at peak 1, a
     * sampled spectrum's own. */
    if (!filename && params_has(pl, "portal"))
        L = rgb_scale(L, params_illuminant_luminance(pl, "L"));
    out->emit = rgb_scale(L, scale);
    if (params_has(pl, "portal") &&
        read_portal(pl, src->render_from_world, src->render_from_light, out, err) != HZ_OK)
        return HZ_ERROR;
    return HZ_OK;
}

static const struct {
    const char *type;
    hz_status (*make)(const light_source *src, light *out, hz_error *err);
} light_kinds[] = {
    {"point", point_from_params},
    {"goniometric", goniometric_from_params},
    {"projection", projection_from_params},
    {"spot", spot_from_params},
    {"distant", distant_from_params},
    {"infinite", infinite_from_params},
};

/* A light haze can trace (its position within HZ_MAX_COORD) whose every
 * parameter was used; on failure frees what `out` holds (an image). */
/* out->spectrum from parameter `name` ("I" or "L"), and the factor that
 * makes emit of it. */
static void light_keep_spectrum(param_list *pl, const char *name, light *out)
{
    out->spectrum = params_spectrum(pl, name, SPECTRUM_USE_ILLUMINANT, rgb_grey(1.0));
    double m = rgb_max(out->spectrum.rgb);
    out->spectrum_factor = m > 0.0 ? rgb_max(out->emit) / m : 0.0;
}

static hz_status light_finish(param_list *pl, const char *type, light *out, hz_error *err)
{
    light_keep_spectrum(pl, out->kind == LIGHT_POINT || out->kind == LIGHT_SPOT ? "I" : "L", out);
    vec3 p = out->kind == LIGHT_POINT  ? out->point.p
             : out->kind == LIGHT_SPOT ? out->spot.p
                                       : v3(0, 0, 0);
    if (!point_within(p, HZ_MAX_COORD))
        params_reject(pl, "from",
                      "light position (%g, %g, %g) in render space is beyond +-%g, where haze "
                      "cannot trace rays",
                      p.x, p.y, p.z, HZ_MAX_COORD);
    char what[128];
    snprintf(what, sizeof what, "LightSource \"%s\"", type);
    if (params_finish(pl, what, err) != HZ_OK) {
        light_free(out);
        return HZ_ERROR;
    }
    return HZ_OK;
}

hz_status light_from_entity(light_entity *e, transform render_from_world, light *out,
                            FILE *warn, hz_error *err)
{
    memset(out, 0, sizeof *out);
    const char *type = e->entity.type ? e->entity.type : "";
    light_source src = {&e->entity.params, e->entity.loc, render_from_world,
                        transform_compose(render_from_world, e->world_from_light), warn};
    for (size_t i = 0; i < sizeof light_kinds / sizeof light_kinds[0]; ++i)
        if (strcmp(type, light_kinds[i].type) == 0) {
            if (light_kinds[i].make(&src, out, err) != HZ_OK)
                return HZ_ERROR;
            return light_finish(src.pl, type, out, err);
        }
    return hz_fail_at(err, e->entity.loc,
                      "LightSource \"%s\" is not supported (supported: \"point\", \"spot\", "
                      "\"goniometric\", \"projection\", \"distant\", \"infinite\")",
                      type);
}

static double triangle_area(const geom_shape *s, size_t t)
{
    const uint32_t *i = &s->indices[3 * t];
    vec3 p0 = v3(s->p[3 * i[0]], s->p[3 * i[0] + 1], s->p[3 * i[0] + 2]);
    vec3 p1 = v3(s->p[3 * i[1]], s->p[3 * i[1] + 1], s->p[3 * i[1] + 2]);
    vec3 p2 = v3(s->p[3 * i[2]], s->p[3 * i[2] + 1], s->p[3 * i[2] + 2]);
    return 0.5 * v3_length(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
}

/* The area of emitter k of a mesh (triangle k, or quad k's two halves) in
 * the shape's space. */
static double mesh_unit_area(const geom_shape *s, size_t k)
{
    return s->quads ? triangle_area(s, 2 * k) + triangle_area(s, 2 * k + 1)
                    : triangle_area(s, k);
}

/* pbrt-v4's "power" on a diffuse area light: scale *= power / (A π), twice A
 * when two-sided, A the Area() of one emitter: the analytic shape's (object
 * space), or each triangle's (quad's) of a mesh, where pbrt-v4 makes one light
 * per triangle. haze's mesh is one light of one radiance, so its emitters
 * must share one area (as a quad's two triangles do); otherwise, and on
 * moving shapes (pbrt-v4 has no moving area lights), "power" is refused
 * (pl's error). Returns the factor (1 when refused). */
static double area_power_scale(param_list *pl, const geom_shape *shape, double power,
                               bool two_sided)
{
    double A = shape->unit_area;
    if (shape->motion) {
        params_reject(pl, "power", "\"power\" on a moving area light is not supported "
                                   "(pbrt-v4 has no moving area lights); use \"L\" and "
                                   "\"scale\"");
        return 1.0;
    }
    if (!(A > 0.0) && shape->kind == GEOMETRY_TRIANGLES) {
        size_t units = shape->quads ? shape->triangle_count / 2 : shape->triangle_count;
        double lo = HUGE_VAL, hi = 0.0;
        for (size_t k = 0; k < units; ++k) {
            double a = mesh_unit_area(shape, k);
            lo = fmin(lo, a);
            hi = fmax(hi, a);
        }
        if (units > 0 && !(hi - lo <= 1e-4 * hi)) {
            params_reject(pl, "power",
                          "\"power\" on a mesh whose %s differ in area (%g to %g) is not "
                          "supported: pbrt-v4 gives each its own radiance, haze one radiance "
                          "per mesh; use \"L\" and \"scale\"",
                          shape->quads ? "quads" : "triangles", lo, hi);
            return 1.0;
        }
        A = hi;
    }
    if (!(A > 0.0)) {
        params_reject(pl, "power", "\"power\" on an area light of zero area");
        return 1.0;
    }
    return power / (A * HZ_PI * (two_sided ? 2.0 : 1.0));
}

static hz_status area_from_entity(scene_entity *e, const geom_shape *shape, light *out,
                                  FILE *warn, hz_error *err);

hz_status light_area_from_entity(scene_entity *e, const geom_shape *shape, light *out,
                                 FILE *warn, hz_error *err)
{
    hz_status st = area_from_entity(e, shape, out, warn, err);
    if (st != HZ_OK) { /* what it allocated before the error */
        out->kind = LIGHT_AREA;
        light_free(out);
    }
    return st;
}

static hz_status area_from_entity(scene_entity *e, const geom_shape *shape, light *out,
                                  FILE *warn, hz_error *err)
{
    memset(out, 0, sizeof *out);
    param_list *pl = &e->params;
    const char *type = e->type ? e->type : "";
    if (strcmp(type, "diffuse") != 0)
        return hz_fail_at(err, e->loc,
                          "AreaLightSource \"%s\" is not supported (supported: \"diffuse\")",
                          type);
    if (shape->kind == GEOMETRY_CURVES)
        return hz_fail_at(err, e->loc,
                          "AreaLightSource on a curve is not supported (pbrt-v4 cannot sample "
                          "curves either: it stops on such a light)");
    const char *filename = params_string(pl, "filename", NULL);
    if (filename && params_has(pl, "L"))
        return hz_fail_at(err, params_loc(pl, "L"),
                          "AreaLightSource: \"L\" and \"filename\" cannot both be given");
    if (filename && load_image(pl, filename, false, &out->area.image, warn, err) != HZ_OK)
        return HZ_ERROR;
    rgb L = params_illuminant(pl, "L", rgb_grey(1.0));
    double scale = params_float(pl, "scale", 1.0);
    double power = params_float(pl, "power", -1.0);
    out->kind = LIGHT_AREA;
    out->area.two_sided = params_bool(pl, "twosided", false);
    out->area.shape = shape;
    out->area.invisible = shape->has_alpha && !shape->alpha_tex && !(shape->alpha > 0.0);
    if (power > 0.0)
        scale *= area_power_scale(pl, shape, power, out->area.two_sided) /
                 (out->area.image ? light_image_luminance(out->area.image) : 1.0);
    out->emit = rgb_scale(L, scale);
    light_keep_spectrum(pl, "L", out);
    if (params_finish(pl, "AreaLightSource \"diffuse\"", err) != HZ_OK)
        return HZ_ERROR;

    if (shape->kind == GEOMETRY_SPHERE && shape->partial)
        return hz_fail_at(err, e->loc,
                          "AreaLightSource on a partial sphere (zmin, zmax or phimax) is not "
                          "supported: its light sampling covers whole spheres");
    if (shape->kind == GEOMETRY_SPHERE) {
        out->area.area = 0.0; /* see sample_sphere_cone and sample_sphere */
        if (shape->motion)
            return HZ_OK; /* decided at each sample's time (sample_moving_area) */
        double scale = light_uniform_scale(&shape->space_from_object);
        double radius = scale * shape->radius;
        if (scale > 0.0 && radius > 0.0 && isfinite(radius)) {
            out->area.sphere_cone = true;
            out->area.sphere_center = transform_point(&shape->space_from_object, v3(0, 0, 0));
            out->area.sphere_radius = radius;
        }
        return HZ_OK;
    }
    if (shape->triangle_count == 0)
        return HZ_OK;
    out->area.cdf = malloc(shape->triangle_count * sizeof(double));
    if (!out->area.cdf)
        return hz_fail(err, "out of memory");
    double sum = 0.0;
    for (size_t t = 0; t < shape->triangle_count; ++t) {
        sum += triangle_area(shape, t);
        out->area.cdf[t] = sum;
    }
    out->area.area = sum;
    for (size_t t = 0; t < shape->triangle_count; ++t)
        out->area.cdf[t] = sum > 0.0 ? out->area.cdf[t] / sum
                                     : (double)(t + 1) / (double)shape->triangle_count;
    return HZ_OK;
}

double light_uniform_scale(const transform *t)
{
    const double(*m)[4] = t->m.m;
    /* Affine only: compositions of affine transforms keep this row exact. */
    if (m[3][0] != 0.0 || m[3][1] != 0.0 || m[3][2] != 0.0 || m[3][3] != 1.0)
        return 0.0;
    double g[3][3]; /* Gram matrix of the columns: AᵀA = s² I for A = s Q */
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            g[i][j] = m[0][i] * m[0][j] + m[1][i] * m[1][j] + m[2][i] * m[2][j];
    double s2 = (g[0][0] + g[1][1] + g[2][2]) / 3.0;
    if (!(s2 > 0.0) || !isfinite(s2))
        return 0.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (!(fabs(g[i][j] - (i == j ? s2 : 0.0)) <= LIGHT_UNIFORM_SCALE_TOL * s2))
                return 0.0;
    return sqrt(s2);
}

void light_free(light *l)
{
    if (l && l->kind == LIGHT_AREA) {
        free(l->area.cdf);
        l->area.cdf = NULL;
        light_image_destroy(l->area.image);
        l->area.image = NULL;
    }
    if (l && l->kind == LIGHT_INFINITE) {
        light_image_destroy(l->infinite.image);
        l->infinite.image = NULL;
    }
    if (l && l->kind == LIGHT_POINT) {
        light_image_destroy(l->point.image);
        l->point.image = NULL;
    }
}

bool light_portal_passes(const light *l, vec3 o, vec3 w)
{
    if (l->kind != LIGHT_INFINITE || !l->infinite.portal)
        return true;
    vec3 z = l->infinite.portal_ez, to = v3_sub(l->infinite.portal_p0, o);
    double wz = v3_dot(w, z), oz = v3_dot(to, z);
    if (!(wz > 0.0) || !(oz > 0.0)) /* away from it, or o beyond it */
        return false;
    vec3 q = v3_sub(v3_scale(w, oz / wz), to); /* the crossing, from p0 */
    double a = v3_dot(q, l->infinite.portal_ex), b = v3_dot(q, l->infinite.portal_ey);
    return a >= 0.0 && a <= l->infinite.portal_len_x && b >= 0.0 &&
           b <= l->infinite.portal_len_y;
}

rgb light_infinite_le(const light *l, vec3 o, vec3 w)
{
    if (!light_portal_passes(l, o, w))
        return rgb_grey(0.0);
    if (!l->infinite.image)
        return l->emit;
    vec3 wl = v3_normalize(transform_vector(&l->infinite.light_from_render, w));
    return rgb_mul(l->emit, light_image_lookup(l->infinite.image,
                                               equal_area_sphere_to_square(wl)));
}

double light_infinite_pdf(const light *l, vec3 w)
{
    if (!l->infinite.image)
        return 0.0;
    vec3 wl = v3_normalize(transform_vector(&l->infinite.light_from_render, w));
    return light_image_pdf(l->infinite.image, equal_area_sphere_to_square(wl)) /
           (4.0 * HZ_PI);
}

bool light_is_delta(const light *l)
{
    switch (l->kind) {
    case LIGHT_POINT:
    case LIGHT_SPOT:
    case LIGHT_DISTANT:
        return true;
    case LIGHT_INFINITE:
    case LIGHT_AREA:
        return false;
    }
    return false;
}

bool light_only_sampled(const light *l)
{
    return light_is_delta(l) || (l->kind == LIGHT_AREA && l->area.invisible);
}

rgb light_area_le(const light *l, vec3 n, vec3 w, vec2 uv, vec3 p)
{
    if (!l->area.two_sided && v3_dot(n, w) <= 0.0)
        return rgb_grey(0.0);
    if (!l->area.invisible && geometry_alpha_masked(l->area.shape, uv, p))
        return rgb_grey(0.0);
    if (!l->area.image)
        return l->emit;
    return rgb_mul(l->emit, light_image_bilerp(l->area.image, v2(uv.x, 1.0 - uv.y)));
}

/* The power of a projection light per unit of emit: the window's area at
 * unit distance times the mean of the texels weighted by cos^3. */
static rgb projection_power(const light *l)
{
    int w, h;
    light_image_size(l->point.image, &w, &h);
    const double *sc = l->point.screen;
    double t = 1.0 / l->point.inv_tan, s[3] = {0, 0, 0};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double px = sc[0] + (sc[1] - sc[0]) * (x + 0.5) / w;
            double py = sc[2] + (sc[3] - sc[2]) * (y + 0.5) / h;
            double c = 1.0 / sqrt(1.0 + (px * px + py * py) * t * t);
            rgb v = light_image_lookup(l->point.image, v2((x + 0.5) / w, (y + 0.5) / h));
            s[0] += v.r * c * c * c;
            s[1] += v.g * c * c * c;
            s[2] += v.b * c * c * c;
        }
    double area = (sc[1] - sc[0]) * (sc[3] - sc[2]) * t * t / ((double)w * h);
    return rgb_make(s[0] * area, s[1] * area, s[2] * area);
}

rgb light_point_factor(const light *l, vec3 w)
{
    const light_image *m = l->point.image;
    if (!m)
        return rgb_grey(1.0);
    vec3 wl = v3_normalize(transform_vector(&l->point.light_from_render, w));
    if (!l->point.projection)
        return rgb_grey(light_image_value(m, equal_area_sphere_to_square(wl)));
    if (wl.z < 1e-3) /* pbrt-v4's hither */
        return rgb_grey(0.0);
    const double *sc = l->point.screen;
    double px = wl.x / wl.z * l->point.inv_tan, py = wl.y / wl.z * l->point.inv_tan;
    if (!(px >= sc[0] && px <= sc[1] && py >= sc[2] && py <= sc[3]))
        return rgb_grey(0.0);
    return light_image_lookup(m, v2((px - sc[0]) / (sc[1] - sc[0]), (py - sc[2]) / (sc[3] - sc[2])));
}

rgb light_phi(const light *l, double scene_radius)
{
    switch (l->kind) {
    case LIGHT_POINT:
        if (l->point.projection)
            return rgb_mul(l->emit, projection_power(l));
        return rgb_scale(l->emit, 4.0 * HZ_PI *
                                      (l->point.image ? light_image_mean(l->point.image) : 1.0));
    case LIGHT_SPOT:
        return rgb_scale(l->emit, 2.0 * HZ_PI *
                                      (1.0 - 0.5 * (l->spot.cos_falloff_start +
                                                    l->spot.cos_falloff_end)));
    case LIGHT_DISTANT:
        return rgb_scale(l->emit, HZ_PI * scene_radius * scene_radius);
    case LIGHT_INFINITE: {
        rgb L = l->infinite.image ? rgb_mul(l->emit, light_image_average(l->infinite.image))
                                  : l->emit;
        return rgb_scale(L, 4.0 * HZ_PI * HZ_PI * scene_radius * scene_radius);
    }
    case LIGHT_AREA: {
        const geom_shape *s = l->area.shape;
        double area = l->area.area;
        if (s->kind == GEOMETRY_SPHERE) {
            transform render_from_object =
                s->motion ? geom_motion_at(s->motion, s->motion->start_time) : s->space_from_object;
            double scale = light_uniform_scale(&render_from_object);
            /* A sphere under a non-uniform scale: its area is not needed
             * exactly to choose among lights; the mean axis scale will do. */
            if (!(scale > 0.0))
                scale = cbrt(fabs(transform_det3(&render_from_object)));
            area = 4.0 * HZ_PI * s->radius * s->radius * scale * scale;
        }
        return rgb_scale(l->emit, (l->area.two_sided ? 2.0 : 1.0) * HZ_PI * area);
    }
    }
    return rgb_grey(0.0);
}

void light_prepare_spectral(light *l, const rgb2spec_table *t)
{
    if (l->spectrum.kind == SPECTRUM_VALUE_RGB)
        l->emit_prepared = spectral_prepare(t, l->emit, SPECTRAL_ILLUMINANT);
}

rgb light_emit_spectral(const light *l, const spectral_ctx *sp)
{
    if (l->emit_prepared.ready)
        return spectral_eval(sp, &l->emit_prepared);
    if (l->spectrum.kind == SPECTRUM_VALUE_RGB)
        return spectral_from_rgb(sp, l->emit, SPECTRAL_ILLUMINANT);
    return rgb_scale(spectral_from_value(sp, &l->spectrum), l->spectrum_factor);
}

static bool light_has_image(const light *l)
{
    switch (l->kind) {
    case LIGHT_POINT:
        return l->point.image != NULL;
    case LIGHT_INFINITE:
        return l->infinite.image != NULL;
    case LIGHT_AREA:
        return l->area.image != NULL;
    case LIGHT_SPOT:
    case LIGHT_DISTANT:
        break;
    }
    return false;
}

rgb light_spectral(const light *l, rgb L, const spectral_ctx *sp)
{
    if (!sp || rgb_is_black(L))
        return L;
    if (light_has_image(l))
        return spectral_from_rgb(sp, L, SPECTRAL_ILLUMINANT);
    /* L = emit * s: s from emit's largest channel. */
    rgb e = l->emit;
    double em = rgb_max(e);
    if (!(em > 0.0))
        return rgb_grey(0.0);
    double s = em == e.r ? L.r / e.r : (em == e.g ? L.g / e.g : L.b / e.b);
    return rgb_scale(light_emit_spectral(l, sp), s);
}
