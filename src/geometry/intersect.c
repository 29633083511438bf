/* Ray queries through Embree: the closest hit (geometry_intersect, carried
 * back from an instance's space as it was at the ray's time) and shadow rays
 * (geometry_occluded). */
#include "geometry/intersect.h"
#include "geometry/surface_hit.h"

/* The ray time Embree sees: the scene time over TransformTimes, in [0, 1];
 * 0 in a scene without motion, as before motion existed. */
static float embree_time(const geometry *g, double time)
{
    if (!g->motion)
        return 0.0f;
    return (float)hz_clamp((time - g->start_time) / (g->end_time - g->start_time), 0.0, 1.0);
}

static void init_ray(struct RTCRay *r, vec3 o, vec3 d, double tmax, float time)
{
    r->org_x = (float)o.x;
    r->org_y = (float)o.y;
    r->org_z = (float)o.z;
    r->tnear = 0.0f;
    r->dir_x = (float)d.x;
    r->dir_y = (float)d.y;
    r->dir_z = (float)d.z;
    r->time = time;
    r->tfar = tmax >= (double)INFINITY ? INFINITY : (float)tmax;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

bool geometry_intersect(const geometry *g, vec3 o, vec3 d, double tmin, double tmax, double time,
                        geom_hit *hit)
{
    /* Either test's "no" means no hit, so their order changes no answer;
     * the world box first spares most rays of a small subject the other. */
    return !geom_misses_world_box(g, o, d, tmin, tmax) &&
           geom_trace(g, o, d, tmin, tmax, time, hit);
}

bool geom_trace(const geometry *g, vec3 o, vec3 d, double tmin, double tmax, double time,
                geom_hit *hit)
{
    if (!geom_embree_can_trace(o, d, tmin, tmax))
        return false;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    init_ray(&rh.ray, o, d, tmax, embree_time(g, time));
    /* Rounded up, so Embree searches no nearer than tmin: rounded to the
     * nearest, a step past a hit far from the origin (step_past's few ulps
     * of double) could land on the hit's own float t and find it again. */
    float tnear = (float)tmin;
    if ((double)tnear < tmin)
        tnear = nextafterf(tnear, INFINITY);
    rh.ray.tnear = tnear;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(g->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return false;

    hit->t = rh.ray.tfar;
    hit->prim = rh.hit.primID;
    if (rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID) {
        const geom_shape *s = &g->shapes[rh.hit.geomID];
        hit->shape = s;
        geom_surface_at(s, rh.hit.primID, rh.hit.u, rh.hit.v, o, d, rh.ray.tfar, hit);
        return true;
    }
    unsigned id = rh.hit.instID[0];
    const instance *in = id < g->shape_count ? g->shape_instances[id]
                                             : &g->instances[id - g->shape_count];
    const geom_shape *s = &in->shapes[rh.hit.geomID];
    hit->shape = s;
    /* A moving instance at the ray's time, as Embree moved it. */
    transform render_from_instance =
        in->motion.steps ? geom_motion_at(&in->motion, time) : in->render_from_instance;
    transform instance_from_render = transform_inverse(render_from_instance);
    geom_surface_at(s, rh.hit.primID, rh.hit.u, rh.hit.v, transform_point(&instance_from_render, o),
                    transform_vector(&instance_from_render, d), rh.ray.tfar, hit);
    hit->p = transform_point(&render_from_instance, hit->p);
    hit->p_error *= cbrt(fabs(transform_det3(&render_from_instance)));
    hit->ng = v3_normalize(transform_normal(&render_from_instance, hit->ng));
    hit->ns = v3_normalize(transform_normal(&render_from_instance, hit->ns));
    if (s->hit_uv) {
        hit->dpdu = transform_vector(&render_from_instance, hit->dpdu);
        hit->dpdv = transform_vector(&render_from_instance, hit->dpdv);
    }
    return true;
}

bool geometry_occluded(const geometry *g, vec3 o, vec3 d, double tmax, double time)
{
    if (!geom_embree_can_trace(o, d, 0.0, tmax))
        return true;
    if (geom_misses_world_box(g, o, d, 0.0, tmax))
        return false;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r;
    init_ray(&r, o, d, tmax, embree_time(g, time));
    rtcOccluded1(g->scene, &ctx, &r);
    return r.tfar == -INFINITY;
}
