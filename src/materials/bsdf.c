#include "materials/bsdf.h"

#include <math.h>

#include "core/sampling.h"

bool bsdf_from_material(const material *m, vec3 ns, bsdf *out)
{
    *out = (bsdf){.n = ns};
    v3_basis(ns, &out->s, &out->t);
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
        out->distrib = (tr_distribution){m->alpha_x, m->alpha_y};
        return true;
    case MATERIAL_DIELECTRIC:
        out->kind = BSDF_DIELECTRIC;
        out->eta = m->eta;
        out->distrib = (tr_distribution){m->alpha_x, m->alpha_y};
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

static bool same_hemisphere(vec3 a, vec3 b) { return a.z * b.z > 0.0; }

/* Dielectric with eta 1 lets light through unchanged: a smooth interface. */
static bool smooth(const bsdf *b)
{
    return b->kind == BSDF_THIN_DIELECTRIC || tr_effectively_smooth(b->distrib) ||
           (b->kind == BSDF_DIELECTRIC && b->eta == 1.0);
}

bool bsdf_is_non_specular(const bsdf *b)
{
    switch (b->kind) {
    case BSDF_DIFFUSE:
    case BSDF_DIFFUSE_TRANSMISSION:
        return true;
    case BSDF_CONDUCTOR:
    case BSDF_DIELECTRIC:
    case BSDF_THIN_DIELECTRIC:
        return !smooth(b);
    }
    return false;
}

/* ---- conductor (pbrt-v4's ConductorBxDF) ---- */

static rgb conductor_f(const bsdf *b, vec3 wo, vec3 wi)
{
    if (!same_hemisphere(wo, wi) || smooth(b))
        return rgb_grey(0.0);
    double co = fabs(wo.z), ci = fabs(wi.z);
    vec3 wm = v3_add(wi, wo);
    if (ci == 0.0 || co == 0.0 || v3_length_sq(wm) == 0.0)
        return rgb_grey(0.0);
    wm = v3_normalize(wm);
    if (wm.z < 0.0)
        wm = v3_neg(wm);
    rgb F = fresnel_complex(fabs(v3_dot(wo, wm)), b->eta_rgb, b->k);
    return rgb_scale(F, tr_d(b->distrib, wm) * tr_g(b->distrib, wo, wi) / (4.0 * ci * co));
}

static double conductor_pdf(const bsdf *b, vec3 wo, vec3 wi)
{
    if (!same_hemisphere(wo, wi) || smooth(b))
        return 0.0;
    vec3 wm = v3_add(wo, wi);
    if (v3_length_sq(wm) == 0.0)
        return 0.0;
    wm = v3_normalize(wm);
    if (wm.z < 0.0)
        wm = v3_neg(wm);
    return tr_d_visible(b->distrib, wo, wm) / (4.0 * fabs(v3_dot(wo, wm)));
}

static bool conductor_sample(const bsdf *b, vec3 wo, vec2 u, bsdf_sample *out)
{
    if (smooth(b)) {
        vec3 wi = v3(-wo.x, -wo.y, wo.z);
        if (wi.z == 0.0)
            return false;
        out->wi = wi;
        out->f = rgb_scale(fresnel_complex(fabs(wi.z), b->eta_rgb, b->k), 1.0 / fabs(wi.z));
        out->pdf = 1.0;
        out->specular = true;
        return true;
    }
    if (wo.z == 0.0)
        return false;
    vec3 wm = tr_sample_wm(b->distrib, wo, u);
    vec3 wi = reflect_dir(wo, wm);
    if (!same_hemisphere(wo, wi))
        return false;
    double pdf = tr_d_visible(b->distrib, wo, wm) / (4.0 * fabs(v3_dot(wo, wm)));
    double co = fabs(wo.z), ci = fabs(wi.z);
    if (!(pdf > 0.0) || ci == 0.0 || co == 0.0)
        return false;
    rgb F = fresnel_complex(fabs(v3_dot(wo, wm)), b->eta_rgb, b->k);
    out->wi = wi;
    out->f = rgb_scale(F, tr_d(b->distrib, wm) * tr_g(b->distrib, wo, wi) / (4.0 * ci * co));
    out->pdf = pdf;
    out->specular = false;
    return true;
}

/* ---- dielectric (pbrt-v4's DielectricBxDF) ---- */

/* The generalised half vector of a reflection or refraction pair, facing
 * +z; false when the pair has no valid microfacet. */
static bool dielectric_half(const bsdf *b, vec3 wo, vec3 wi, vec3 *wm, double *etap,
                            bool *reflect)
{
    double co = wo.z, ci = wi.z;
    *reflect = co * ci > 0.0;
    *etap = 1.0;
    if (!*reflect)
        *etap = co > 0.0 ? b->eta : 1.0 / b->eta;
    vec3 h = v3_add(v3_scale(wi, *etap), wo);
    if (ci == 0.0 || co == 0.0 || v3_length_sq(h) == 0.0)
        return false;
    h = v3_normalize(h);
    if (h.z < 0.0)
        h = v3_neg(h);
    /* Microfacets seen from behind contribute nothing. */
    if (v3_dot(h, wi) * ci < 0.0 || v3_dot(h, wo) * co < 0.0)
        return false;
    *wm = h;
    return true;
}

static rgb dielectric_f(const bsdf *b, vec3 wo, vec3 wi)
{
    if (smooth(b))
        return rgb_grey(0.0);
    vec3 wm;
    double etap;
    bool reflect;
    if (!dielectric_half(b, wo, wi, &wm, &etap, &reflect))
        return rgb_grey(0.0);
    double F = fresnel_dielectric(v3_dot(wo, wm), b->eta);
    double D = tr_d(b->distrib, wm), G = tr_g(b->distrib, wo, wi);
    if (reflect)
        return rgb_grey(D * G * F / fabs(4.0 * wi.z * wo.z));
    double denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    denom = denom * denom * wi.z * wo.z;
    double ft = D * (1.0 - F) * G * fabs(v3_dot(wi, wm) * v3_dot(wo, wm) / denom);
    return rgb_grey(ft / (etap * etap));
}

static double dielectric_pdf(const bsdf *b, vec3 wo, vec3 wi)
{
    if (smooth(b))
        return 0.0;
    vec3 wm;
    double etap;
    bool reflect;
    if (!dielectric_half(b, wo, wi, &wm, &etap, &reflect))
        return 0.0;
    double R = fresnel_dielectric(v3_dot(wo, wm), b->eta), T = 1.0 - R;
    if (reflect)
        return tr_d_visible(b->distrib, wo, wm) / (4.0 * fabs(v3_dot(wo, wm))) * R / (R + T);
    double denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    double dwm_dwi = fabs(v3_dot(wi, wm)) / (denom * denom);
    return tr_d_visible(b->distrib, wo, wm) * dwm_dwi * T / (R + T);
}

static bool dielectric_sample(const bsdf *b, vec3 wo, double uc, vec2 u, bsdf_sample *out)
{
    if (smooth(b)) {
        double R = fresnel_dielectric(wo.z, b->eta), T = 1.0 - R;
        if (uc < R / (R + T)) {
            vec3 wi = v3(-wo.x, -wo.y, wo.z);
            if (wi.z == 0.0)
                return false;
            *out = (bsdf_sample){wi, rgb_grey(R / fabs(wi.z)), R / (R + T), true, false};
            return true;
        }
        vec3 wi;
        double etap;
        if (!refract_dir(wo, v3(0, 0, 1), b->eta, &etap, &wi) || wi.z == 0.0)
            return false;
        *out = (bsdf_sample){wi, rgb_grey(T / fabs(wi.z) / (etap * etap)), T / (R + T), true,
                             true};
        return true;
    }
    if (wo.z == 0.0)
        return false;
    vec3 wm = tr_sample_wm(b->distrib, wo, u);
    double R = fresnel_dielectric(v3_dot(wo, wm), b->eta), T = 1.0 - R;
    if (uc < R / (R + T)) {
        vec3 wi = reflect_dir(wo, wm);
        if (!same_hemisphere(wo, wi))
            return false;
        double pdf = tr_d_visible(b->distrib, wo, wm) / (4.0 * fabs(v3_dot(wo, wm))) * R / (R + T);
        double f = tr_d(b->distrib, wm) * tr_g(b->distrib, wo, wi) * R / (4.0 * wi.z * wo.z);
        if (!(pdf > 0.0))
            return false;
        *out = (bsdf_sample){wi, rgb_grey(f), pdf, false, false};
        return true;
    }
    vec3 wi;
    double etap;
    if (!refract_dir(wo, wm, b->eta, &etap, &wi) || same_hemisphere(wo, wi) || wi.z == 0.0)
        return false;
    double denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    denom *= denom;
    double dwm_dwi = fabs(v3_dot(wi, wm)) / denom;
    double pdf = tr_d_visible(b->distrib, wo, wm) * dwm_dwi * T / (R + T);
    double ft = T * tr_d(b->distrib, wm) * tr_g(b->distrib, wo, wi) *
                fabs(v3_dot(wi, wm) * v3_dot(wo, wm) / (wi.z * wo.z * denom)) / (etap * etap);
    if (!(pdf > 0.0))
        return false;
    *out = (bsdf_sample){wi, rgb_grey(ft), pdf, false, true};
    return true;
}

/* ---- thin dielectric (pbrt-v4's ThinDielectricBxDF): the interreflections
 * inside the sheet summed, transmission straight through ---- */

static bool thin_sample(const bsdf *b, vec3 wo, double uc, bsdf_sample *out)
{
    double R = fresnel_dielectric(fabs(wo.z), b->eta), T = 1.0 - R;
    if (R < 1.0) {
        R += T * T * R / (1.0 - R * R);
        T = 1.0 - R;
    }
    if (uc < R / (R + T)) {
        vec3 wi = v3(-wo.x, -wo.y, wo.z);
        if (wi.z == 0.0)
            return false;
        *out = (bsdf_sample){wi, rgb_grey(R / fabs(wi.z)), R / (R + T), true, false};
        return true;
    }
    vec3 wi = v3_neg(wo);
    if (wi.z == 0.0)
        return false;
    *out = (bsdf_sample){wi, rgb_grey(T / fabs(wi.z)), T / (R + T), true, true};
    return true;
}

/* ---- diffuse transmission (pbrt-v4's DiffuseTransmissionBxDF): the lobe
 * on each side chosen by its largest channel ---- */

static void dt_probs(const bsdf *b, double *pr, double *pt)
{
    *pr = rgb_max(b->reflectance);
    *pt = rgb_max(b->transmittance);
}

static rgb dt_f(const bsdf *b, vec3 wo, vec3 wi)
{
    return rgb_scale(same_hemisphere(wo, wi) ? b->reflectance : b->transmittance, HZ_INV_PI);
}

static double dt_pdf(const bsdf *b, vec3 wo, vec3 wi)
{
    double pr, pt;
    dt_probs(b, &pr, &pt);
    return (same_hemisphere(wo, wi) ? pr : pt) / (pr + pt) * cosine_hemisphere_pdf(fabs(wi.z));
}

static bool dt_sample(const bsdf *b, vec3 wo, double uc, vec2 u, bsdf_sample *out)
{
    double pr, pt;
    dt_probs(b, &pr, &pt);
    vec3 wi = sample_cosine_hemisphere(u);
    bool reflect = uc < pr / (pr + pt);
    /* Reflection on wo's side, transmission on the other. */
    if ((wo.z < 0.0) == reflect)
        wi.z = -wi.z;
    if (wi.z == 0.0)
        return false;
    *out = (bsdf_sample){wi, dt_f(b, wo, wi), dt_pdf(b, wo, wi), false, !reflect};
    return out->pdf > 0.0;
}

/* ---- dispatch ---- */

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
        return conductor_f(b, wo, wi);
    case BSDF_DIELECTRIC:
        return dielectric_f(b, wo, wi);
    case BSDF_THIN_DIELECTRIC:
        return rgb_grey(0.0);
    case BSDF_DIFFUSE_TRANSMISSION:
        return dt_f(b, wo, wi);
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
        return conductor_pdf(b, wo, wi);
    case BSDF_DIELECTRIC:
        return dielectric_pdf(b, wo, wi);
    case BSDF_THIN_DIELECTRIC:
        return 0.0;
    case BSDF_DIFFUSE_TRANSMISSION:
        return dt_pdf(b, wo, wi);
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
    out->specular = out->transmission = false;
    return out->pdf > 0.0;
}

bool bsdf_sample_f(const bsdf *b, vec3 wo_r, double uc, vec2 u, bsdf_sample *out)
{
    if (b->kind == BSDF_DIFFUSE)
        return diffuse_sample(b, wo_r, u, out);
    vec3 wo = to_local(b, wo_r);
    bool ok = false, flip = false;
    out->transmission = false;
    switch (b->kind) {
    case BSDF_DIFFUSE:
        break;
    case BSDF_CONDUCTOR:
        flip = wo.z < 0.0;
        ok = conductor_sample(b, flip ? v3_neg(wo) : wo, u, out);
        break;
    case BSDF_DIELECTRIC:
        ok = dielectric_sample(b, wo, uc, u, out);
        break;
    case BSDF_THIN_DIELECTRIC:
        ok = thin_sample(b, wo, uc, out);
        break;
    case BSDF_DIFFUSE_TRANSMISSION:
        ok = dt_sample(b, wo, uc, u, out);
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
        break;
    case BSDF_CONDUCTOR:
    case BSDF_DIELECTRIC:
        tr_regularize(&b->distrib);
        break;
    }
}
