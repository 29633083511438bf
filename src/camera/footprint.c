/* The camera's estimate of a point's footprint (pbrt-v4's
 * Approximate_dp_dxy and FindMinimumDifferentials). */
#include "camera/footprint.h"

#include <math.h>

static vec3 camera_space_offset(const transform *camera_from_render, vec3 v)
{
    return transform_vector(camera_from_render, v);
}

void camera_find_min_differentials(camera *c)
{
    if (c->kind == CAMERA_ORTHOGRAPHIC) {
        /* Parallel rays: the pixel step itself, no spread. */
        c->min_pos_dx = c->dx_camera;
        c->min_pos_dy = c->dy_camera;
        c->min_dir_dx = c->min_dir_dy = v3(0.0, 0.0, 0.0);
        return;
    }
    vec3 inf = v3(INFINITY, INFINITY, INFINITY);
    vec3 pos[2] = {inf, inf}, dir[2] = {inf, inf};
    enum { N = 512 };
    for (int i = 0; i < N; ++i) {
        double f = (double)i / (N - 1);
        camera_sample s = {v2(f * c->xres, f * c->yres), v2(0.5, 0.5), 0.5, 1.0};
        ray_differential rd;
        if (!camera_generate_ray_differential(c, s, &rd))
            continue;
        transform render_from_camera =
            c->motion ? animated_transform_at(&c->render_from_camera_motion, rd.r.time)
                      : c->render_from_camera;
        transform camera_from_render = transform_inverse(render_from_camera);
        vec3 d = v3_normalize(rd.r.d), b1, b2;
        v3_basis(d, &b1, &b2);
        const vec3 o_off[2] = {v3_sub(rd.rx_o, rd.r.o), v3_sub(rd.ry_o, rd.r.o)};
        const vec3 d_off[2] = {rd.rx_d, rd.ry_d};
        for (int k = 0; k < 2; ++k) {
            vec3 dp = camera_space_offset(&camera_from_render, o_off[k]);
            if (v3_length(dp) < v3_length(pos[k]))
                pos[k] = dp;
            vec3 w = v3_normalize(d_off[k]);
            /* In the ray's frame the ray itself is (0, 0, 1). */
            vec3 local = v3_normalize(v3(v3_dot(w, b1), v3_dot(w, b2), v3_dot(w, d)));
            vec3 dd = v3_sub(local, v3(v3_dot(d, b1), v3_dot(d, b2), v3_dot(d, d)));
            if (v3_length(dd) < v3_length(dir[k]))
                dir[k] = dd;
        }
    }
    /* No ray at all (a realistic camera that vignettes every sample): no
     * footprint, as pbrt-v4's infinite vectors give none usable. */
    for (int k = 0; k < 2; ++k) {
        if (!v3_is_finite(pos[k]) || !v3_is_finite(dir[k]))
            pos[k] = dir[k] = v3(0.0, 0.0, 0.0);
    }
    c->min_pos_dx = pos[0];
    c->min_pos_dy = pos[1];
    c->min_dir_dx = dir[0];
    c->min_dir_dy = dir[1];
}

/* The rotation taking unit `from` to +z, as pbrt-v4's RotateFromTo builds
 * it: two reflections, through a helper axis that neither vector is close
 * to. Its inverse applies the reflections in the other order. */
typedef struct {
    vec3 u, v;
    double uu, vv;
} to_z_rotation;

static to_z_rotation rotation_to_z(vec3 from)
{
    vec3 axis = fabs(from.x) < 0.72   ? v3(1.0, 0.0, 0.0)
                : fabs(from.y) < 0.72 ? v3(0.0, 1.0, 0.0)
                                      : v3(0.0, 0.0, 1.0);
    to_z_rotation r;
    r.u = v3_sub(axis, from);
    r.v = v3_sub(axis, v3(0.0, 0.0, 1.0));
    r.uu = v3_dot(r.u, r.u);
    r.vv = v3_dot(r.v, r.v);
    return r;
}

static vec3 reflect_across(vec3 x, vec3 a, double aa)
{
    return aa > 0.0 ? v3_sub(x, v3_scale(a, 2.0 * v3_dot(a, x) / aa)) : x;
}

static vec3 rotate_to_z(const to_z_rotation *r, vec3 x)
{
    return reflect_across(reflect_across(x, r->u, r->uu), r->v, r->vv);
}

static vec3 rotate_from_z(const to_z_rotation *r, vec3 x)
{
    return reflect_across(reflect_across(x, r->v, r->vv), r->u, r->uu);
}

void camera_approximate_dpdxy(const camera *c, vec3 p, vec3 n, double time, double scale,
                              vec3 *dpdx, vec3 *dpdy)
{
    *dpdx = *dpdy = v3(0.0, 0.0, 0.0);
    transform moving;
    const transform *render_from_camera = &c->render_from_camera;
    if (c->motion) {
        moving = animated_transform_at(&c->render_from_camera_motion, time);
        render_from_camera = &moving;
    }
    transform camera_from_render = transform_inverse(*render_from_camera);
    vec3 pc = transform_point(&camera_from_render, p);
    if (!(v3_length_sq(pc) > 0.0))
        return;
    to_z_rotation rot = rotation_to_z(v3_normalize(pc));
    vec3 pz = rotate_to_z(&rot, pc);
    vec3 nz = rotate_to_z(&rot, transform_normal(&camera_from_render, n));
    double plane = nz.z * pz.z;
    const vec3 o[2] = {c->min_pos_dx, c->min_pos_dy};
    const vec3 d[2] = {v3_add(v3(0.0, 0.0, 1.0), c->min_dir_dx),
                       v3_add(v3(0.0, 0.0, 1.0), c->min_dir_dy)};
    vec3 out[2];
    for (int k = 0; k < 2; ++k) {
        double t = -(v3_dot(nz, o[k]) - plane) / v3_dot(nz, d[k]);
        vec3 hit = v3_add(o[k], v3_scale(d[k], t));
        out[k] = v3_scale(transform_vector(render_from_camera, rotate_from_z(&rot, v3_sub(hit, pz))),
                          scale);
        if (!v3_is_finite(out[k]))
            return;
    }
    *dpdx = out[0];
    *dpdy = out[1];
}
