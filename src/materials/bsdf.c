#include "materials/bsdf.h"

#include <math.h>

#include "core/sampling.h"

bool bsdf_from_material(const material *m, vec3 ns, vec3 dpdu, double v, bsdf *out)
{
    /* Only the fields of the kind are set: the struct holds every kind's
     * (a coated one's layers too), too much to clear on every hit. */
    out->n = ns;
    /* Diffuse lobes work in render space; the others in the shading frame. */
    if (m->kind != MATERIAL_DIFFUSE)
        v3_basis(ns, &out->s, &out->t);
    tr_distribution d = {m->alpha_x, m->alpha_y};
    switch (m->kind) {
    case MATERIAL_DIFFUSE:
        if (rgb_is_black(m->reflectance))
            return false;
        out->kind = BSDF_DIFFUSE;
        out->reflectance = m->reflectance;
        return true;
    case MATERIAL_CONDUCTOR:
        out->kind = BSDF_CONDUCTOR;
        out->eta_rgb = m->eta_rgb;
        out->k = m->k;
        out->distrib = d;
        return true;
    case MATERIAL_DIELECTRIC:
        out->kind = BSDF_DIELECTRIC;
        out->eta = m->eta;
        out->distrib = d;
        return true;
    case MATERIAL_THIN_DIELECTRIC:
        out->kind = BSDF_THIN_DIELECTRIC;
        out->eta = m->eta;
        return true;
    case MATERIAL_DIFFUSE_TRANSMISSION:
        if (rgb_is_black(m->reflectance) && rgb_is_black(m->transmittance))
            return false;
        out->kind = BSDF_DIFFUSE_TRANSMISSION;
        out->reflectance = m->reflectance;
        out->transmittance = m->transmittance;
        return true;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
        out->kind = BSDF_COATED;
        out->coat = m->coat;
        return true;
    case MATERIAL_HAIR: {
        /* pbrt-v4's Frame::FromXZ(dp/du, ns): x along the hair. */
        vec3 s = v3_sub(dpdu, v3_scale(ns, v3_dot(dpdu, ns)));
        if (v3_length_sq(s) > 0.0) {
            out->s = v3_normalize(s);
            out->t = v3_cross(ns, out->s);
        }
        out->kind = BSDF_HAIR;
        out->hair = hair_make(2.0 * v - 1.0, m->eta, m->sigma_a, m->beta_m, m->beta_n,
                              m->hair_alpha);
        out->hair.lanes = m->spectral ? WAVELENGTH_LANES : 3;
        return true;
    }
    case MATERIAL_MEASURED:
        out->kind = BSDF_MEASURED;
        out->measured = m->measured;
        out->spectral = m->spectral;
        return m->measured != NULL;
    case MATERIAL_MIX: /* resolved by material_at before */
    case MATERIAL_INTERFACE:
        return false;
    }
    return false;
}

static vec3 to_local(const bsdf *b, vec3 w)
{
    return v3(v3_dot(w, b->s), v3_dot(w, b->t), v3_dot(w, b->n));
}

static vec3 from_local(const bsdf *b, vec3 w)
{
    return v3_add(v3_add(v3_scale(b->s, w.x), v3_scale(b->t, w.y)), v3_scale(b->n, w.z));
}

bool bsdf_is_non_specular(const bsdf *b)
{
    switch (b->kind) {
    case BSDF_DIFFUSE:
    case BSDF_DIFFUSE_TRANSMISSION:
        return true;
    case BSDF_CONDUCTOR:
        return !bxdf_conductor_smooth(b->distrib);
    case BSDF_DIELECTRIC:
        return !bxdf_dielectric_smooth(b->distrib, b->eta);
    case BSDF_THIN_DIELECTRIC:
        return false;
    case BSDF_COATED:
        return layered_is_non_specular(&b->coat);
    case BSDF_HAIR:
    case BSDF_MEASURED:
        return true;
    }
    return false;
}

/* Two-sided lobes (conductors, as pbrt-v4's) work on wo's side: a wo below
 * the surface flips both directions. */
static void to_wo_side(vec3 *wo, vec3 *wi)
{
    if (wo->z < 0.0) {
        *wo = v3_neg(*wo);
        *wi = v3_neg(*wi);
    }
}

/* Diffuse: reflection only, on wo's side of the surface (in render space:
 * only the normal matters). */
static bool same_side(vec3 n, vec3 wo, vec3 wi) { return v3_dot(n, wo) * v3_dot(n, wi) > 0.0; }

/* A measured BRDF's RGB value at the sample's wavelengths (spectral
 * rendering), as an unbounded spectrum; itself in RGB rendering. */
static rgb measured_lanes(const bsdf *b, rgb f)
{
    return b->spectral ? spectral_from_rgb(b->spectral, f, SPECTRAL_UNBOUNDED) : f;
}

rgb bsdf_f(const bsdf *b, vec3 wo_r, vec3 wi_r)
{
    if (b->kind == BSDF_DIFFUSE)
        return same_side(b->n, wo_r, wi_r) ? rgb_scale(b->reflectance, HZ_INV_PI)
                                           : rgb_grey(0.0);
    vec3 wo = to_local(b, wo_r), wi = to_local(b, wi_r);
    switch (b->kind) {
    case BSDF_DIFFUSE:
        break;
    case BSDF_CONDUCTOR:
        to_wo_side(&wo, &wi);
        return bxdf_conductor_f(b->distrib, b->eta_rgb, b->k, wo, wi);
    case BSDF_DIELECTRIC:
        return bxdf_dielectric_f(b->distrib, b->eta, wo, wi, true);
    case BSDF_THIN_DIELECTRIC:
        return rgb_grey(0.0);
    case BSDF_DIFFUSE_TRANSMISSION:
        return bxdf_dt_f(b->reflectance, b->transmittance, wo, wi);
    case BSDF_COATED:
        return layered_f(&b->coat, wo, wi);
    case BSDF_HAIR:
        return hair_f(&b->hair, wo, wi);
    case BSDF_MEASURED:
        return measured_lanes(b, bxdf_measured_f(b->measured, wo, wi));
    }
    return rgb_grey(0.0);
}

double bsdf_pdf(const bsdf *b, vec3 wo_r, vec3 wi_r)
{
    if (b->kind == BSDF_DIFFUSE)
        return same_side(b->n, wo_r, wi_r) ? fabs(v3_dot(b->n, wi_r)) * HZ_INV_PI : 0.0;
    vec3 wo = to_local(b, wo_r), wi = to_local(b, wi_r);
    switch (b->kind) {
    case BSDF_DIFFUSE:
        break;
    case BSDF_CONDUCTOR:
        to_wo_side(&wo, &wi);
        return bxdf_conductor_pdf(b->distrib, wo, wi, BXDF_ALL);
    case BSDF_DIELECTRIC:
        return bxdf_dielectric_pdf(b->distrib, b->eta, wo, wi, BXDF_ALL);
    case BSDF_THIN_DIELECTRIC:
        return 0.0;
    case BSDF_DIFFUSE_TRANSMISSION:
        return bxdf_dt_pdf(b->reflectance, b->transmittance, wo, wi);
    case BSDF_COATED:
        return layered_pdf(&b->coat, wo, wi);
    case BSDF_HAIR:
        return hair_pdf(&b->hair, wo, wi);
    case BSDF_MEASURED:
        return bxdf_measured_pdf(b->measured, wo, wi);
    }
    return 0.0;
}

/* Diffuse sampling around the normal on wo's side, in render space. */
static bool diffuse_sample(const bsdf *b, vec3 wo, vec2 u, bsdf_sample *out)
{
    double on = v3_dot(b->n, wo);
    if (on == 0.0)
        return false;
    vec3 n = on < 0.0 ? v3_neg(b->n) : b->n;
    vec3 w = sample_cosine_hemisphere(u);
    if (!(w.z > 0.0))
        return false;
    vec3 b1, b2;
    v3_basis(n, &b1, &b2);
    out->wi =
        v3_normalize(v3_add(v3_add(v3_scale(b1, w.x), v3_scale(b2, w.y)), v3_scale(n, w.z)));
    out->pdf = cosine_hemisphere_pdf(w.z);
    out->f = rgb_scale(b->reflectance, HZ_INV_PI);
    out->specular = out->transmission = out->pdf_proportional = false;
    out->eta = 1.0;
    return out->pdf > 0.0;
}

bool bsdf_sample_f(const bsdf *b, vec3 wo_r, double uc, vec2 u, bsdf_sample *out)
{
    if (b->kind == BSDF_DIFFUSE)
        return diffuse_sample(b, wo_r, u, out);
    vec3 wo = to_local(b, wo_r);
    bool ok = false, flip = false;
    switch (b->kind) {
    case BSDF_DIFFUSE:
        break;
    case BSDF_CONDUCTOR:
        flip = wo.z < 0.0;
        ok = bxdf_conductor_sample(b->distrib, b->eta_rgb, b->k, flip ? v3_neg(wo) : wo, u,
                                   BXDF_ALL, out);
        break;
    case BSDF_DIELECTRIC:
        ok = bxdf_dielectric_sample(b->distrib, b->eta, wo, uc, u, BXDF_ALL, true, out);
        break;
    case BSDF_THIN_DIELECTRIC:
        ok = bxdf_thin_sample(b->eta, wo, uc, out);
        break;
    case BSDF_DIFFUSE_TRANSMISSION:
        ok = bxdf_dt_sample(b->reflectance, b->transmittance, wo, uc, u, out);
        break;
    case BSDF_COATED:
        ok = layered_sample(&b->coat, wo, uc, u, out);
        break;
    case BSDF_HAIR:
        ok = hair_sample(&b->hair, wo, uc, u, out);
        break;
    case BSDF_MEASURED: /* flips a wo below the surface itself, as pbrt-v4 */
        ok = bxdf_measured_sample(b->measured, wo, u, out);
        if (ok)
            out->f = measured_lanes(b, out->f);
        break;
    }
    if (!ok)
        return false;
    vec3 wi = flip ? v3_neg(out->wi) : out->wi;
    out->wi = v3_normalize(from_local(b, wi));
    return true;
}

void bsdf_regularize(bsdf *b)
{
    switch (b->kind) {
    case BSDF_DIFFUSE:
    case BSDF_THIN_DIELECTRIC:
    case BSDF_DIFFUSE_TRANSMISSION:
    case BSDF_HAIR: /* pbrt-v4's HairBxDF::Regularize does nothing */
    case BSDF_MEASURED: /* nor does its MeasuredBxDF's */
        break;
    case BSDF_CONDUCTOR:
    case BSDF_DIELECTRIC:
        tr_regularize(&b->distrib);
        break;
    case BSDF_COATED:
        tr_regularize(&b->coat.top);
        if (b->coat.conductor)
            tr_regularize(&b->coat.bottom);
        break;
    }
}
