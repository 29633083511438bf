/* Light sampling: a point or direction toward a light from a receiving
 * point, with its density, and that density for a given point on the light
 * (light_sample_li, light_pdf_li). */
#include "lights/lights.h"

#include <float.h>
#include <math.h>

#include "core/ray.h"
#include "core/sampling.h"
#include "lights/envmap.h"

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

/* A point on the mesh, chosen proportionally to area; pdf per unit area (in
 * the shape's space: object space for a moving shape). */
static bool sample_triangles(const light *l, vec2 u, vec3 *p, vec3 *n, vec2 *uv,
                             double *pdf_area)
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
    *uv = v2(h.u, h.v); /* set where the light has an image (its shape's hit_uv) */
    *pdf_area = 1.0 / l->area.area;
    return true;
}

/* Uniform by area in object space, with the exact area change of the
 * transform `render_from_object`, so non-uniform scales stay unbiased. */
static bool sample_sphere(const light *l, const transform *render_from_object, vec2 u, vec3 *p,
                          vec3 *n, vec2 *uv, double *pdf_area)
{
    const geom_shape *s = l->area.shape;
    vec3 n_obj = sample_uniform_sphere(u);
    vec3 po = v3_scale(n_obj, s->radius);
    *uv = l->area.image ? geometry_sphere_uv(s, po) : v2(0.0, 0.0);
    *p = transform_point(render_from_object, po);
    vec3 nt = transform_normal(render_from_object, n_obj);
    double jacobian =
        fabs(transform_det3(render_from_object)) * v3_length(nt); /* dA_render / dA_object */
    if (jacobian == 0.0)
        return false;
    *pdf_area = 1.0 / (4.0 * HZ_PI * s->radius * s->radius * jacobian);
    vec3 nn = v3_normalize(nt);
    *n = s->flip_normal ? v3_neg(nn) : nn;
    return true;
}

/* pbrt-v4's Sphere::Sample(ctx, u): uniform over the cone of directions from
 * `p` that the sphere (centre c, radius r, render space) subtends, pdf 1 / (2π (1 − cosθmax)) per
 * solid angle, with the point found through the angle α at the centre rather than by intersecting a
 * ray. Returns false when `p` is inside the sphere (or on it, up to rounding), which the caller
 * samples by area, as pbrt-v4 does.
 *
 * pbrt-v4 computes cosθ = 1 − u (1 − cosθmax) and sin²θ = 1 − cos²θ, which
 * cancel catastrophically for small cones, and switches to the Taylor
 * expansion sin²θ = u sin²θmax, 1 − cosθmax = sin²θmax / 2 below
 * sin²θmax = sin²(1.5°). Here every quantity comes from 1 − cos without a
 * subtraction, through the exact identities
 *     1 − cosθmax = sin²θmax / (1 + cosθmax),
 *     sin²θ = (1 − cosθ)(1 + cosθ),
 *     sin²θ / sin²θmax = u (1 + cosθ) / (1 + cosθmax),
 * (and 1 − sin²θ / sin²θmax likewise), whose small-angle limits are exactly
 * pbrt-v4's Taylor terms. So the one branch is the small-angle branch for
 * tiny cones and the general one elsewhere, accurate at every size (pbrt-v4's
 * truncated expansion is off by up to sin²θmax / 2 relative, 3e-4 at its
 * threshold), and a sphere of radius 1e-3 at 1e3 (sin²θmax = 1e-12) samples
 * and weighs correctly. */
static bool sample_sphere_cone(const light *l, vec3 c, double r, vec3 p, vec2 u, vec3 *pl,
                               vec3 *nl, double *pdf_dir)
{
    vec3 to_c = v3_sub(c, p);
    double dc2 = v3_length_sq(to_c);
    /* Inside or on the surface: area sampling. The margin only absorbs the
     * rounding of points on the sphere; both strategies are unbiased. */
    if (dc2 <= r * r * (1.0 + 1e-9))
        return false;
    double dc = sqrt(dc2);
    double sin_max = r / dc;
    double sin2_max = sin_max * sin_max;
    double cos_max = sqrt(fmax(0.0, 1.0 - sin2_max));
    double omc_max = sin2_max / (1.0 + cos_max); /* 1 - cos(theta_max) */
    if (!(omc_max >= DBL_MIN)) /* underflow: no representable solid angle */
        return false;

    double omc = u.x * omc_max;     /* 1 - cos(theta), uniform in cos(theta) */
    double cos_t = 1.0 - omc;
    /* sin2_t / sin2_max and its complement, both without cancellation (the
     * complement matters near the rim, u.x -> 1), using 1 + cos_max = 2 - omc_max. */
    double ratio = u.x * (2.0 - omc) / (2.0 - omc_max);
    double one_minus_ratio = (1.0 - u.x) * (2.0 - omc_max * (1.0 + u.x)) / (2.0 - omc_max);
    /* Angle α at the centre between the axis toward p and the sampled point:
     * pbrt-v4's cosα = sin²θ / sinθmax + cosθ sqrt(1 - sin²θ / sin²θmax). */
    double sqrt_omr = sqrt(fmax(0.0, one_minus_ratio));
    double cos_a = sin_max * ratio + cos_t * sqrt_omr;
    /* pbrt-v4 takes sinα = sqrt(1 - cos²α), which for points close to the
     * sphere (cosα -> 1 near the axis while the point is at distance
     * h << R) cannot resolve small α: at h = 1e-7 R samples near the axis
     * land ~1e-8 R off, a sizeable angle seen from h away. The law of sines
     * gives it without cancellation: sinα = t sinθ / R, with t the distance to
     * the near intersection, t = (dc² - R²) / (dc cosθ + R sqrt(1 - sin²θ / sin²θmax)).
     * cosα keeps pbrt-v4's form (accurate where it is small, at the rim). */
    double t = (dc2 - r * r) / (dc * cos_t + r * sqrt_omr);
    double sin_t = sqrt(omc * (2.0 - omc));
    double sin_a = t * sin_t / r;
    double phi = 2.0 * HZ_PI * u.y;

    vec3 z = v3_scale(to_c, 1.0 / dc), x, y;
    v3_basis(z, &x, &y);
    /* Outward normal at the point: -(sinα cosφ x + sinα sinφ y + cosα z),
     * renormalised since sinα and cosα come from different formulas. */
    vec3 nn = v3_neg(v3_add(v3_add(v3_scale(x, sin_a * cos(phi)), v3_scale(y, sin_a * sin(phi))),
                            v3_scale(z, cos_a)));
    nn = v3_normalize(nn);
    *pl = v3_add(c, v3_scale(nn, r));
    *nl = l->area.shape->flip_normal ? v3_neg(nn) : nn;
    *pdf_dir = 1.0 / (2.0 * HZ_PI * omc_max);
    return true;
}

/* out->dist and out->wi from p toward the light point pl; returns the squared
 * distance, 0 when they coincide (then out is unchanged). */
static double sample_direction(vec3 p, vec3 pl, light_sample *out)
{
    vec3 d = v3_sub(pl, p);
    double d2 = v3_length_sq(d);
    if (d2 == 0.0)
        return 0.0;
    out->dist = sqrt(d2);
    out->wi = v3_scale(d, 1.0 / out->dist);
    return d2;
}

/* Fills the geometry of a sample of a light at the single point p_light and
 * returns the squared distance (0: p sits on the light, no sample). */
static double toward_point(vec3 p_light, vec3 p, light_sample *out)
{
    double d2 = sample_direction(p, p_light, out);
    if (d2 == 0.0)
        return 0.0;
    out->p_light = p_light;
    out->pdf = 1.0;
    return d2;
}

/* The sample of point `pl` (normal `nl`) of an area light chosen with
 * density `pdf_dir` per solid angle at p (sphere cone sampling). */

static bool area_sample_solid_angle(const light *l, vec3 p, vec3 pl, vec3 nl, vec2 uv,
                                    double pdf_dir, light_sample *out)
{
    if (sample_direction(p, pl, out) == 0.0)
        return false;
    out->pdf = pdf_dir;
    /* One-sided: only the side the normal faces emits (for an outward normal
     * that is the whole cone but its rim). */
    out->L = light_area_le(l, nl, v3_neg(out->wi), uv, pl);
    if (rgb_is_black(out->L))
        return false;
    out->p_light = pl;
    out->n_light = nl;
    return true;
}

/* The sample of point `pl` (unit normal `nl`) of an area light chosen with
 * density `pdf_area` per unit area (render space). */
static bool area_sample_area(const light *l, vec3 p, vec3 pl, vec3 nl, vec2 uv,
                             double pdf_area, light_sample *out)
{
    double d2 = sample_direction(p, pl, out);
    if (d2 == 0.0)
        return false;
    double cos_l = fabs(v3_dot(nl, out->wi));
    if (cos_l == 0.0)
        return false;
    out->L = light_area_le(l, nl, v3_neg(out->wi), uv, pl);
    if (rgb_is_black(out->L))
        return false;
    out->pdf = pdf_area * d2 / cos_l;
    out->p_light = pl;
    out->n_light = nl;
    return true;
}

/* The (u, v) of render-space point pl on an image light's sphere. */
static vec2 sphere_uv_at(const light *l, const transform *render_from_object, vec3 pl)
{
    if (!l->area.image)
        return v2(0.0, 0.0);
    transform object_from_render = transform_inverse(*render_from_object);
    return geometry_sphere_uv(l->area.shape, transform_point(&object_from_render, pl));
}

/* An area light on a moving shape (kept in object space, geometry.h) at scene
 * time `time`: the shape sampled in object space and carried to render space
 * by render_from_object at that time, the transform Embree intersects. */
static bool sample_moving_area(const light *l, vec3 p, double time, vec2 u, light_sample *out)
{
    const geom_shape *s = l->area.shape;
    transform render_from_object = geom_motion_at(s->motion, time);
    vec3 pl, nl;
    vec2 uv;
    double pdf;
    if (s->kind == GEOMETRY_SPHERE) {
        /* Cone sampling while the transform is a similarity at this time. */
        double scale = light_uniform_scale(&render_from_object);
        double radius = scale * s->radius;
        if (scale > 0.0 && radius > 0.0 && isfinite(radius) &&
            sample_sphere_cone(l, transform_point(&render_from_object, v3(0, 0, 0)), radius, p, u,
                               &pl, &nl, &pdf))
            return area_sample_solid_angle(l, p, pl, nl,
                                           sphere_uv_at(l, &render_from_object, pl), pdf, out);
        return sample_sphere(l, &render_from_object, u, &pl, &nl, &uv, &pdf) &&
               area_sample_area(l, p, pl, nl, uv, pdf, out);
    }
    if (!sample_triangles(l, u, &pl, &nl, &uv, &pdf))
        return false;
    /* Per object-space area so far; dA_render = |det A| |A^-T n| dA_object
     * for the unit normal n (the triangle's area changes with a scale). */
    vec3 nt = transform_normal(&render_from_object, nl);
    double jacobian = fabs(transform_det3(&render_from_object)) * v3_length(nt);
    if (!(jacobian > 0.0) || !isfinite(jacobian))
        return false;
    return area_sample_area(l, p, transform_point(&render_from_object, pl), v3_normalize(nt), uv,
                            pdf / jacobian, out);
}

bool light_sample_li(const light *l, vec3 p, vec3 n, double time, vec2 u, light_sample *out)
{
    out->infinite = false;
    out->n_light = v3(0, 0, 0);
    switch (l->kind) {
    case LIGHT_POINT: {
        double d2 = toward_point(l->point.p, p, out);
        if (d2 == 0.0)
            return false;
        out->L = rgb_scale(l->emit, 1.0 / d2);
        if (l->point.image) /* goniometric, projection: the image toward p */
            out->L = rgb_mul(out->L, light_point_factor(l, v3_neg(out->wi)));
        return true;
    }
    case LIGHT_SPOT: {
        double d2 = toward_point(l->spot.p, p, out);
        if (d2 == 0.0)
            return false;
        vec3 d = v3_sub(l->spot.p, p);
        vec3 wl = v3_normalize(transform_vector(&l->spot.light_from_render, v3_neg(d)));
        double falloff = smooth_step(wl.z, l->spot.cos_falloff_end, l->spot.cos_falloff_start);
        if (falloff == 0.0)
            return false;
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
        if (l->infinite.image) { /* the map's density */
            double pdf_uv;
            vec2 uv = light_image_sample(l->infinite.image, u, &pdf_uv);
            if (!(pdf_uv > 0.0))
                return false;
            vec3 wl = equal_area_square_to_sphere(uv);
            out->wi = v3_normalize(transform_vector(&l->infinite.render_from_light, wl));
            if (!light_portal_passes(l, p, out->wi))
                return false; /* the map's density over every direction: unbiased */
            out->pdf = pdf_uv / (4.0 * HZ_PI);
            out->dist = INFINITY;
            out->infinite = true;
            out->L = rgb_mul(l->emit, light_image_lookup(l->infinite.image, uv));
            return true;
        }
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
        const geom_shape *s = l->area.shape;
        if (s->motion)
            return sample_moving_area(l, p, time, u, out);
        vec3 pl, nl;
        vec2 uv;
        double pdf;
        if (l->area.sphere_cone && sample_sphere_cone(l, l->area.sphere_center,
                                                      l->area.sphere_radius, p, u, &pl, &nl, &pdf))
            return area_sample_solid_angle(l, p, pl, nl, sphere_uv_at(l, &s->space_from_object, pl),
                                           pdf, out);
        bool ok = s->kind == GEOMETRY_SPHERE
                      ? sample_sphere(l, &s->space_from_object, u, &pl, &nl, &uv, &pdf)
                      : sample_triangles(l, u, &pl, &nl, &uv, &pdf);
        return ok && area_sample_area(l, p, pl, nl, uv, pdf, out);
    }
    }
    return false;
}

/* ---- density of a sample, power (volpath's MIS and light sampler) ---- */

/* 1 - cos(theta_max) of the cone a sphere (centre c, radius r) subtends at p,
 * as sample_sphere_cone computes it; 0 where that function refuses (p inside
 * or on the sphere, or an underflowing cone): area sampling then. */
static double sphere_cone_omc(vec3 c, double r, vec3 p)
{
    double dc2 = v3_length_sq(v3_sub(c, p));
    if (dc2 <= r * r * (1.0 + 1e-9))
        return 0.0;
    double sin_max = r / sqrt(dc2);
    double sin2_max = sin_max * sin_max;
    double cos_max = sqrt(fmax(0.0, 1.0 - sin2_max));
    double omc_max = sin2_max / (1.0 + cos_max);
    return omc_max >= DBL_MIN ? omc_max : 0.0;
}

/* Per render-space area: a density per object-space area `pdf_obj` carried
 * by render_from_object to the point with render-space unit normal nr. */
static double area_density_render(const transform *render_from_object, vec3 nr, double pdf_obj)
{
    transform object_from_render = transform_inverse(*render_from_object);
    vec3 no = v3_normalize(transform_normal(&object_from_render, nr));
    double jacobian = fabs(transform_det3(render_from_object)) *
                      v3_length(transform_normal(render_from_object, no));
    return jacobian > 0.0 && isfinite(jacobian) ? pdf_obj / jacobian : 0.0;
}

double light_pdf_li(const light *l, vec3 p, double time, vec3 pl, vec3 nl)
{
    if (l->kind != LIGHT_AREA)
        return 0.0;
    const geom_shape *s = l->area.shape;
    vec3 d = v3_sub(pl, p);
    double d2 = v3_length_sq(d);
    if (d2 == 0.0)
        return 0.0;
    double cos_l = fabs(v3_dot(nl, d)) / sqrt(d2);
    double pdf_area;
    if (s->kind == GEOMETRY_SPHERE) {
        transform render_from_object =
            s->motion ? geom_motion_at(s->motion, time) : s->space_from_object;
        double scale = 0.0;
        vec3 c = l->area.sphere_center;
        double r = l->area.sphere_radius;
        if (s->motion) {
            scale = light_uniform_scale(&render_from_object);
            r = scale * s->radius;
            c = transform_point(&render_from_object, v3(0, 0, 0));
        }
        bool cone = s->motion ? scale > 0.0 && r > 0.0 && isfinite(r) : l->area.sphere_cone;
        double omc = cone ? sphere_cone_omc(c, r, p) : 0.0;
        if (omc > 0.0)
            return 1.0 / (2.0 * HZ_PI * omc);
        pdf_area = area_density_render(&render_from_object, nl,
                                       1.0 / (4.0 * HZ_PI * s->radius * s->radius));
    } else {
        if (s->triangle_count == 0 || !(l->area.area > 0.0))
            return 0.0;
        pdf_area = 1.0 / l->area.area;
        if (s->motion) {
            transform render_from_object = geom_motion_at(s->motion, time);
            pdf_area = area_density_render(&render_from_object, nl, pdf_area);
        }
    }
    return cos_l > 0.0 ? pdf_area * d2 / cos_l : 0.0;
}
