/* "cloud": pbrt-v4's procedural cloud (media/cloud.h): density (1),
 * wispiness (1), frequency (5), p0, p1 (0 0 0, 1 1 1), and sigma_a, sigma_s,
 * scale, g as every medium. Its density is at most 1: sigma_t is the
 * majorant over the box. Rendered by volpath only. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/box.h"
#include "media/cloud.h"
#include "media/medium.h"
#include "media/medium_params.h"

typedef struct {
    cloud_params params;
    vec3 p0, p1; /* the box, medium space */
    transform medium_from_render;
} cloud_medium;

/* The cloud's own parameters (problems are recorded in pl). */
static void read_cloud(medium_entity *e, cloud_medium *cm)
{
    param_list *pl = &e->entity.params;
    double v[3] = {params_float(pl, "density", 1.0), params_float(pl, "wispiness", 1.0),
                   params_float(pl, "frequency", 5.0)};
    const char *names[3] = {"density", "wispiness", "frequency"};
    for (int k = 0; k < 3; ++k)
        if (!(isfinite(v[k]) && v[k] >= 0.0 && v[k] < 1e30))
            params_reject(pl, names[k], "\"%s\" must be finite and >= 0", names[k]);
    cm->params = (cloud_params){(float)v[0], (float)v[1], (float)v[2]};
    cm->p0 = params_point3(pl, "p0", v3(0, 0, 0));
    cm->p1 = params_point3(pl, "p1", v3(1, 1, 1));
    if (!(cm->p0.x < cm->p1.x && cm->p0.y < cm->p1.y && cm->p0.z < cm->p1.z) ||
        !v3_is_finite(cm->p0) || !v3_is_finite(cm->p1))
        params_reject(pl, "p1", "the box \"p0\" .. \"p1\" must be finite and non-empty");
    if (memcmp(&e->world_from_medium.m, &e->world_from_medium_end.m,
               sizeof e->world_from_medium.m) != 0)
        params_reject(pl, "density", "a moving \"cloud\" medium is not supported");
}

static hz_status create(medium_entity *e, const medium_build *b, medium *out, hz_error *err)
{
    param_list *pl = &e->entity.params;
    medium_param_rules rules = {true, true, MEDIUM_LE_NONE, false};
    medium_common_params c;
    medium_params_read(pl, &rules, &c);
    medium_params_check_emission(pl, &c);
    cloud_medium cm;
    read_cloud(e, &cm);
    if (medium_params_finish(e, &c, out, err) != HZ_OK)
        return HZ_ERROR;
    cm.medium_from_render =
        transform_inverse(transform_compose(b->render_from_world, e->world_from_medium));
    if (!medium_transform_is_finite(&cm.medium_from_render))
        return hz_fail_at(err, e->entity.loc,
                          "MakeNamedMedium \"%s\": the cloud's placement is singular or not "
                          "finite",
                          medium_entity_name(e));
    cloud_medium *state = malloc(sizeof *state);
    if (!state)
        return hz_fail(err, "out of memory");
    *state = cm;
    out->state = state;
    return HZ_OK;
}

static void destroy(medium *m) { free(m->state); }

static bool clip(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1)
{
    (void)time;
    const cloud_medium *cm = m->state;
    return box_clip_ray(transform_point(&cm->medium_from_render, o),
                        transform_vector(&cm->medium_from_render, d), cm->p0, cm->p1, t0, t1);
}

static bool ray_start(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1,
                      medium_ray *r)
{
    (void)time;
    const cloud_medium *cm = m->state;
    vec3 om = transform_point(&cm->medium_from_render, o);
    vec3 dm = transform_vector(&cm->medium_from_render, d);
    if (!box_clip_ray(om, dm, cm->p0, cm->p1, t0, t1))
        return false;
    medium_ray_single(r, m, *t0, *t1, 1.0, 0.0);
    r->at.cloud.o = om;
    r->at.cloud.d = dm;
    return true;
}

static void sample(medium_ray *r, double t, bool emission, medium_props *p, uint64_t *lookups)
{
    const medium *m = r->m;
    const cloud_medium *cm = m->state;
    double d = cloud_density(&cm->params, v3_add(r->at.cloud.o, v3_scale(r->at.cloud.d, t)));
    ++*lookups;
    medium_props_scaled(m, d, emission, p);
}

const medium_ops medium_cloud_ops = {
    .name = "cloud",
    .create = create,
    .destroy = destroy,
    .clip = clip,
    .ray_start = ray_start,
    .sample = sample,
};
