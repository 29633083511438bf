#include "render/lights.h"

#include "core/sampling.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Cosine-weighted direction around unit `n`. */
static vec3 cosine_around(vec3 n, vec2 u, double *cos_theta)
{
    vec3 w = sample_cosine_hemisphere(u);
    vec3 b1, b2;
    v3_basis(n, &b1, &b2);
    *cos_theta = w.z;
    return v3_add(v3_add(v3_scale(b1, w.x), v3_scale(b2, w.y)), v3_scale(n, w.z));
}

/* pbrt's SmoothStep. */
static double smooth_step(double x, double a, double b)
{
    if (a == b)
        return x < a ? 0.0 : 1.0;
    double t = hz_clamp((x - a) / (b - a), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

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

static hz_status refuse(param_list *pl, const char *name, const char *why, hz_error *err)
{
    if (!params_has(pl, name))
        return HZ_OK;
    return hz_fail_at(err, params_loc(pl, name), "%s", why);
}

hz_status light_from_entity(light_entity *e, transform render_from_world, light *out,
                            hz_error *err)
{
    memset(out, 0, sizeof *out);
    param_list *pl = &e->entity.params;
    const char *type = e->entity.type ? e->entity.type : "";
    transform render_from_light = transform_compose(render_from_world, e->world_from_light);

    if (strcmp(type, "point") == 0) {
        rgb I = params_rgb(pl, "I", rgb_grey(1.0));
        double scale = params_float(pl, "scale", 1.0);
        double power = params_float(pl, "power", -1.0);
        vec3 from = params_point3(pl, "from", v3(0, 0, 0));
        out->kind = LIGHT_POINT;
        out->emit = apply_power(I, scale, power, 4.0 * HZ_PI);
        out->point.p = transform_point(&render_from_light, from);
    } else if (strcmp(type, "spot") == 0) {
        rgb I = params_rgb(pl, "I", rgb_grey(1.0));
        double scale = params_float(pl, "scale", 1.0);
        double power = params_float(pl, "power", -1.0);
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
        out->emit = apply_power(I, scale, power, k_e);
        /* pbrt-v4: renderFromLight * Translate(from) * Inverse(Frame::FromZ(dir)). */
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
        transform final = transform_compose(render_from_light,
                                            transform_compose(transform_translate(from), frame));
        out->spot.p = transform_point(&final, v3(0, 0, 0));
        out->spot.light_from_render = transform_inverse(final);
    } else if (strcmp(type, "distant") == 0) {
        rgb L = params_rgb(pl, "L", rgb_grey(1.0));
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
        vec3 w = transform_vector(&render_from_light, v3_sub(from, to));
        out->distant.w = v3_length(w) > 0.0 ? v3_normalize(w) : v3(0, 0, 1);
    } else if (strcmp(type, "infinite") == 0) {
        if (refuse(pl, "filename",
                   "image-based infinite lights (\"filename\") are not supported yet; use "
                   "\"rgb L\"",
                   err) != HZ_OK ||
            refuse(pl, "portal", "infinite light \"portal\" is not supported", err) != HZ_OK)
            return HZ_ERROR;
        rgb L = params_rgb(pl, "L", rgb_grey(1.0));
        double scale = params_float(pl, "scale", 1.0);
        /* pbrt-v4: illuminance of a uniform sky on an upward patch is π L. */
        double illum = params_float(pl, "illuminance", -1.0);
        if (illum > 0.0)
            scale *= illum / HZ_PI;
        out->kind = LIGHT_INFINITE;
        out->emit = rgb_scale(L, scale);
    } else {
        return hz_fail_at(err, e->entity.loc,
                          "LightSource \"%s\" is not supported (supported: \"point\", \"spot\", "
                          "\"distant\", \"infinite\")",
                          type);
    }
    char what[128];
    snprintf(what, sizeof what, "LightSource \"%s\"", type);
    return params_finish(pl, what, err);
}

static double triangle_area(const geom_shape *s, size_t t)
{
    const uint32_t *i = &s->indices[3 * t];
    vec3 p0 = v3(s->p[3 * i[0]], s->p[3 * i[0] + 1], s->p[3 * i[0] + 2]);
    vec3 p1 = v3(s->p[3 * i[1]], s->p[3 * i[1] + 1], s->p[3 * i[1] + 2]);
    vec3 p2 = v3(s->p[3 * i[2]], s->p[3 * i[2] + 1], s->p[3 * i[2] + 2]);
    return 0.5 * v3_length(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
}

hz_status light_area_from_entity(scene_entity *e, const geom_shape *shape, light *out,
                                 hz_error *err)
{
    memset(out, 0, sizeof *out);
    param_list *pl = &e->params;
    const char *type = e->type ? e->type : "";
    if (strcmp(type, "diffuse") != 0)
        return hz_fail_at(err, e->loc,
                          "AreaLightSource \"%s\" is not supported (supported: \"diffuse\")",
                          type);
    if (refuse(pl, "filename", "image area lights (\"filename\") are not supported yet",
               err) != HZ_OK ||
        refuse(pl, "power",
               "\"power\" on area lights is not supported yet (pbrt-v4 applies it per "
               "triangle); use \"rgb L\" and \"scale\"",
               err) != HZ_OK)
        return HZ_ERROR;
    rgb L = params_rgb(pl, "L", rgb_grey(1.0));
    double scale = params_float(pl, "scale", 1.0);
    out->kind = LIGHT_AREA;
    out->emit = rgb_scale(L, scale);
    out->area.two_sided = params_bool(pl, "twosided", false);
    out->area.shape = shape;
    if (params_finish(pl, "AreaLightSource \"diffuse\"", err) != HZ_OK)
        return HZ_ERROR;

    if (shape->kind == GEOMETRY_SPHERE) {
        out->area.area = 0.0; /* sampled by area in object space; see sample_sphere */
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

void light_free(light *l)
{
    if (l && l->kind == LIGHT_AREA) {
        free(l->area.cdf);
        l->area.cdf = NULL;
    }
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

rgb light_area_le(const light *l, vec3 n, vec3 w)
{
    if (!l->area.two_sided && v3_dot(n, w) <= 0.0)
        return rgb_grey(0.0);
    return l->emit;
}

/* A point on the mesh, chosen proportionally to area; pdf per unit area. */
static bool sample_triangles(const light *l, vec2 u, vec3 *p, vec3 *n, double *pdf_area)
{
    const geom_shape *s = l->area.shape;
    if (s->triangle_count == 0 || l->area.area <= 0.0)
        return false;
    size_t lo = 0, hi = s->triangle_count - 1;
    while (lo < hi) { /* first t with cdf[t] > u.x */
        size_t mid = (lo + hi) / 2;
        if (l->area.cdf[mid] > u.x)
            hi = mid;
        else
            lo = mid + 1;
    }
    double c0 = lo > 0 ? l->area.cdf[lo - 1] : 0.0;
    double w = l->area.cdf[lo] - c0;
    double ux = w > 0.0 ? hz_clamp((u.x - c0) / w, 0.0, 0x1.fffffffffffffp-1) : 0.5;
    vec2 b = sample_uniform_triangle(v2(ux, u.y)); /* (b0, b1) */
    geom_hit h;
    geometry_triangle_point(s, (unsigned)lo, b.y, 1.0 - b.x - b.y, &h);
    *p = h.p;
    *n = h.ng;
    *pdf_area = 1.0 / l->area.area;
    return true;
}

/* Uniform by area in object space, with the exact area change of the
 * transform, so non-uniform scales stay unbiased. */
static bool sample_sphere(const light *l, vec2 u, vec3 *p, vec3 *n, double *pdf_area)
{
    const geom_shape *s = l->area.shape;
    vec3 n_obj = sample_uniform_sphere(u);
    vec3 po = v3_scale(n_obj, s->radius);
    *p = transform_point(&s->space_from_object, po);
    vec3 nt = transform_normal(&s->space_from_object, n_obj);
    const double(*m)[4] = s->space_from_object.m.m;
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    double jacobian = fabs(det) * v3_length(nt); /* dA_render / dA_object */
    if (jacobian == 0.0)
        return false;
    *pdf_area = 1.0 / (4.0 * HZ_PI * s->radius * s->radius * jacobian);
    vec3 nn = v3_normalize(nt);
    *n = s->flip_normal ? v3_neg(nn) : nn;
    return true;
}

bool light_sample_li(const light *l, vec3 p, vec3 n, vec2 u, light_sample *out)
{
    out->infinite = false;
    out->n_light = v3(0, 0, 0);
    switch (l->kind) {
    case LIGHT_POINT: {
        vec3 d = v3_sub(l->point.p, p);
        double d2 = v3_length_sq(d);
        if (d2 == 0.0)
            return false;
        out->dist = sqrt(d2);
        out->wi = v3_scale(d, 1.0 / out->dist);
        out->p_light = l->point.p;
        out->pdf = 1.0;
        out->L = rgb_scale(l->emit, 1.0 / d2);
        return true;
    }
    case LIGHT_SPOT: {
        vec3 d = v3_sub(l->spot.p, p);
        double d2 = v3_length_sq(d);
        if (d2 == 0.0)
            return false;
        out->dist = sqrt(d2);
        out->wi = v3_scale(d, 1.0 / out->dist);
        vec3 wl = v3_normalize(transform_vector(&l->spot.light_from_render, v3_neg(d)));
        double falloff = smooth_step(wl.z, l->spot.cos_falloff_end, l->spot.cos_falloff_start);
        if (falloff == 0.0)
            return false;
        out->p_light = l->spot.p;
        out->pdf = 1.0;
        out->L = rgb_scale(l->emit, falloff / d2);
        return true;
    }
    case LIGHT_DISTANT:
        out->wi = l->distant.w;
        out->dist = INFINITY;
        out->infinite = true;
        out->pdf = 1.0;
        out->L = l->emit;
        return true;
    case LIGHT_INFINITE: {
        /* Cosine sampling around the normal: for a constant sky the
         * estimator's only variance is visibility. */
        double c;
        out->wi = cosine_around(n, u, &c);
        if (c <= 0.0)
            return false;
        out->pdf = c * HZ_INV_PI;
        out->dist = INFINITY;
        out->infinite = true;
        out->L = l->emit;
        return true;
    }
    case LIGHT_AREA: {
        vec3 pl, nl;
        double pdf_area;
        bool ok = l->area.shape->kind == GEOMETRY_SPHERE
                      ? sample_sphere(l, u, &pl, &nl, &pdf_area)
                      : sample_triangles(l, u, &pl, &nl, &pdf_area);
        if (!ok)
            return false;
        vec3 d = v3_sub(pl, p);
        double d2 = v3_length_sq(d);
        if (d2 == 0.0)
            return false;
        out->dist = sqrt(d2);
        out->wi = v3_scale(d, 1.0 / out->dist);
        double cos_l = fabs(v3_dot(nl, out->wi));
        if (cos_l == 0.0)
            return false;
        out->L = light_area_le(l, nl, v3_neg(out->wi));
        if (rgb_is_black(out->L))
            return false;
        out->pdf = pdf_area * d2 / cos_l;
        out->p_light = pl;
        out->n_light = nl;
        return true;
    }
    }
    return false;
}
