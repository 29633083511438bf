#include "integrator/visible_surface.h"

#include "materials/bsdf.h"

/* The BSDF's directional albedo toward wo, as pbrt-v4's BSDF::rho: the mean
 * of f |cos| / pdf over 16 fixed stratified samples (exact for diffuse
 * reflection; 0 where the material scatters nothing). */
static rgb directional_albedo(const geom_hit *h, vec3 wo)
{
    enum { N = 16 };
    material scratch;
    bsdf b;
    const material *mat = geometry_material_at(h, wo, &scratch);
    if (!bsdf_from_material(mat, geometry_shading_normal(h, mat), h->dpdu, h->v, &b))
        return rgb_grey(0.0);
    rgb sum = rgb_grey(0.0);
    for (int i = 0; i < N; ++i) {
        vec2 u = v2(((i % 4) + 0.5) / 4.0, ((i / 4) + 0.5) / 4.0);
        double uc = ((i * 5) % N + 0.5) / N; /* a permutation: not aligned with u */
        bsdf_sample s;
        if (bsdf_sample_f(&b, wo, uc, u, &s) && s.pdf > 0.0)
            sum = rgb_add(sum, rgb_scale(s.f, fabs(v3_dot(s.wi, b.n)) / s.pdf));
    }
    return rgb_scale(sum, 1.0 / N);
}

void visible_surface_at(const geom_hit *h, const ray_differential *rd, film_surface *vs)
{
    vec3 wo = v3_neg(rd->r.d);
    vs->hit = true;
    vs->p = h->p;
    /* Both normals face the camera, as pbrt-v4's. */
    vs->n = v3_dot(h->ng, wo) < 0.0 ? v3_neg(h->ng) : h->ng;
    vs->ns = v3_dot(h->ns, wo) < 0.0 ? v3_neg(h->ns) : h->ns;
    vs->u = h->u;
    vs->v = h->v;
    vs->dpdx = vs->dpdy = v3(0.0, 0.0, 0.0);
    if (rd->has_differentials)
        geometry_hit_dpdxy(h, rd->rx_o, rd->rx_d, rd->ry_o, rd->ry_d, &vs->dpdx, &vs->dpdy);
    vs->albedo = directional_albedo(h, wo);
}
