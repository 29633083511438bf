#include "materials/bsdf.h"

#include <math.h>

#include "core/sampling.h"

bool bsdf_from_material(const material *m, vec3 ns, bsdf *out)
{
    switch (m->kind) {
    case MATERIAL_DIFFUSE:
        if (rgb_is_black(m->reflectance))
            return false;
        *out = (bsdf){BSDF_DIFFUSE, ns, m->reflectance};
        return true;
    case MATERIAL_INTERFACE:
        return false;
    }
    return false;
}

bool bsdf_is_non_specular(const bsdf *b)
{
    switch (b->kind) {
    case BSDF_DIFFUSE:
        return true;
    }
    return false;
}

/* Diffuse: reflection only, so wi must lie on wo's side of the surface. */
static bool same_side(vec3 n, vec3 wo, vec3 wi)
{
    return v3_dot(n, wo) * v3_dot(n, wi) > 0.0;
}

rgb bsdf_f(const bsdf *b, vec3 wo, vec3 wi)
{
    switch (b->kind) {
    case BSDF_DIFFUSE:
        return same_side(b->n, wo, wi) ? rgb_scale(b->reflectance, HZ_INV_PI) : rgb_grey(0.0);
    }
    return rgb_grey(0.0);
}

double bsdf_pdf(const bsdf *b, vec3 wo, vec3 wi)
{
    switch (b->kind) {
    case BSDF_DIFFUSE:
        return same_side(b->n, wo, wi) ? fabs(v3_dot(b->n, wi)) * HZ_INV_PI : 0.0;
    }
    return 0.0;
}

bool bsdf_sample_f(const bsdf *b, vec3 wo, double uc, vec2 u, bsdf_sample *out)
{
    (void)uc; /* one lobe: nothing to choose */
    switch (b->kind) {
    case BSDF_DIFFUSE: {
        double on = v3_dot(b->n, wo);
        if (on == 0.0)
            return false;
        vec3 n = on < 0.0 ? v3_neg(b->n) : b->n;
        vec3 w = sample_cosine_hemisphere(u);
        if (!(w.z > 0.0))
            return false;
        vec3 b1, b2;
        v3_basis(n, &b1, &b2);
        out->wi = v3_normalize(
            v3_add(v3_add(v3_scale(b1, w.x), v3_scale(b2, w.y)), v3_scale(n, w.z)));
        out->pdf = cosine_hemisphere_pdf(w.z);
        out->f = rgb_scale(b->reflectance, HZ_INV_PI);
        out->specular = false;
        return out->pdf > 0.0;
    }
    }
    return false;
}

void bsdf_regularize(bsdf *b)
{
    switch (b->kind) {
    case BSDF_DIFFUSE:
        break;
    }
}
