#include "materials/bxdfs.h"

#include <math.h>

#include "core/sampling.h"

/* ---- diffuse ---- */

rgb bxdf_diffuse_f(rgb r, vec3 wo, vec3 wi)
{
    return same_hemisphere(wo, wi) ? rgb_scale(r, HZ_INV_PI) : rgb_grey(0.0);
}

double bxdf_diffuse_pdf(vec3 wo, vec3 wi, bxdf_flags flags)
{
    if (!(flags & BXDF_REFLECTION) || !same_hemisphere(wo, wi))
        return 0.0;
    return cosine_hemisphere_pdf(fabs(wi.z));
}

bool bxdf_diffuse_sample(rgb r, vec3 wo, vec2 u, bxdf_flags flags, bsdf_sample *out)
{
    if (!(flags & BXDF_REFLECTION) || wo.z == 0.0)
        return false;
    vec3 wi = sample_cosine_hemisphere(u);
    if (wo.z < 0.0)
        wi.z = -wi.z;
    *out = (bsdf_sample){wi, rgb_scale(r, HZ_INV_PI), cosine_hemisphere_pdf(fabs(wi.z)), false,
                         false, false, 1.0};
    return out->pdf > 0.0;
}

/* ---- conductor (pbrt-v4's ConductorBxDF) ---- */

bool bxdf_conductor_smooth(tr_distribution d) { return tr_effectively_smooth(d); }

rgb bxdf_conductor_f(tr_distribution d, rgb eta, rgb k, vec3 wo, vec3 wi)
{
    if (!same_hemisphere(wo, wi) || tr_effectively_smooth(d))
        return rgb_grey(0.0);
    double co = fabs(wo.z), ci = fabs(wi.z);
    vec3 wm = v3_add(wi, wo);
    if (ci == 0.0 || co == 0.0 || v3_length_sq(wm) == 0.0)
        return rgb_grey(0.0);
    wm = v3_normalize(wm);
    if (wm.z < 0.0)
        wm = v3_neg(wm);
    rgb F = fresnel_complex(fabs(v3_dot(wo, wm)), eta, k);
    return rgb_scale(F, tr_d(d, wm) * tr_g(d, wo, wi) / (4.0 * ci * co));
}

double bxdf_conductor_pdf(tr_distribution d, vec3 wo, vec3 wi, bxdf_flags flags)
{
    if (!(flags & BXDF_REFLECTION) || !same_hemisphere(wo, wi) || tr_effectively_smooth(d))
        return 0.0;
    vec3 wm = v3_add(wo, wi);
    if (v3_length_sq(wm) == 0.0)
        return 0.0;
    wm = v3_normalize(wm);
    if (wm.z < 0.0)
        wm = v3_neg(wm);
    return tr_d_visible(d, wo, wm) / (4.0 * fabs(v3_dot(wo, wm)));
}

bool bxdf_conductor_sample(tr_distribution d, rgb eta, rgb k, vec3 wo, vec2 u, bxdf_flags flags,
                           bsdf_sample *out)
{
    if (!(flags & BXDF_REFLECTION))
        return false;
    if (tr_effectively_smooth(d)) {
        vec3 wi = v3(-wo.x, -wo.y, wo.z);
        if (wi.z == 0.0)
            return false;
        *out = (bsdf_sample){wi, rgb_scale(fresnel_complex(fabs(wi.z), eta, k), 1.0 / fabs(wi.z)),
                             1.0, true, false, false, 1.0};
        return true;
    }
    if (wo.z == 0.0)
        return false;
    vec3 wm = tr_sample_wm(d, wo, u);
    vec3 wi = reflect_dir(wo, wm);
    if (!same_hemisphere(wo, wi))
        return false;
    double pdf = tr_d_visible(d, wo, wm) / (4.0 * fabs(v3_dot(wo, wm)));
    double co = fabs(wo.z), ci = fabs(wi.z);
    if (!(pdf > 0.0) || ci == 0.0 || co == 0.0)
        return false;
    rgb F = fresnel_complex(fabs(v3_dot(wo, wm)), eta, k);
    *out = (bsdf_sample){wi, rgb_scale(F, tr_d(d, wm) * tr_g(d, wo, wi) / (4.0 * ci * co)), pdf,
                         false, false, false, 1.0};
    return true;
}

/* ---- dielectric (pbrt-v4's DielectricBxDF) ---- */

bool bxdf_dielectric_smooth(tr_distribution d, double eta)
{
    return eta == 1.0 || tr_effectively_smooth(d);
}

/* The generalised half vector of a reflection or refraction pair, facing
 * +z; false when the pair has no valid microfacet. */
static bool dielectric_half(double eta, vec3 wo, vec3 wi, vec3 *wm, double *etap, bool *reflect)
{
    double co = wo.z, ci = wi.z;
    *reflect = co * ci > 0.0;
    *etap = 1.0;
    if (!*reflect)
        *etap = co > 0.0 ? eta : 1.0 / eta;
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

rgb bxdf_dielectric_f(tr_distribution d, double eta, vec3 wo, vec3 wi, bool radiance)
{
    if (bxdf_dielectric_smooth(d, eta))
        return rgb_grey(0.0);
    vec3 wm;
    double etap;
    bool reflect;
    if (!dielectric_half(eta, wo, wi, &wm, &etap, &reflect))
        return rgb_grey(0.0);
    double F = fresnel_dielectric(v3_dot(wo, wm), eta);
    double D = tr_d(d, wm), G = tr_g(d, wo, wi);
    if (reflect)
        return rgb_grey(D * G * F / fabs(4.0 * wi.z * wo.z));
    double denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    denom = denom * denom * wi.z * wo.z;
    double ft = D * (1.0 - F) * G * fabs(v3_dot(wi, wm) * v3_dot(wo, wm) / denom);
    return rgb_grey(radiance ? ft / (etap * etap) : ft);
}

/* The reflection and transmission probabilities a restricted sampler uses. */
static void split(double R, bxdf_flags flags, double *pr, double *pt)
{
    *pr = flags & BXDF_REFLECTION ? R : 0.0;
    *pt = flags & BXDF_TRANSMISSION ? 1.0 - R : 0.0;
}

double bxdf_dielectric_pdf(tr_distribution d, double eta, vec3 wo, vec3 wi, bxdf_flags flags)
{
    if (bxdf_dielectric_smooth(d, eta))
        return 0.0;
    vec3 wm;
    double etap;
    bool reflect;
    if (!dielectric_half(eta, wo, wi, &wm, &etap, &reflect))
        return 0.0;
    double pr, pt;
    split(fresnel_dielectric(v3_dot(wo, wm), eta), flags, &pr, &pt);
    if (pr == 0.0 && pt == 0.0)
        return 0.0;
    if (reflect)
        return tr_d_visible(d, wo, wm) / (4.0 * fabs(v3_dot(wo, wm))) * pr / (pr + pt);
    double denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    double dwm_dwi = fabs(v3_dot(wi, wm)) / (denom * denom);
    return tr_d_visible(d, wo, wm) * dwm_dwi * pt / (pr + pt);
}

bool bxdf_dielectric_sample(tr_distribution d, double eta, vec3 wo, double uc, vec2 u,
                            bxdf_flags flags, bool radiance, bsdf_sample *out)
{
    double pr, pt;
    if (bxdf_dielectric_smooth(d, eta)) {
        double R = fresnel_dielectric(wo.z, eta);
        split(R, flags, &pr, &pt);
        if (pr == 0.0 && pt == 0.0)
            return false;
        if (uc < pr / (pr + pt)) {
            vec3 wi = v3(-wo.x, -wo.y, wo.z);
            if (wi.z == 0.0)
                return false;
            *out = (bsdf_sample){wi, rgb_grey(R / fabs(wi.z)), pr / (pr + pt), true, false, false,
                                 1.0};
            return true;
        }
        vec3 wi;
        double etap;
        if (!refract_dir(wo, v3(0, 0, 1), eta, &etap, &wi) || wi.z == 0.0)
            return false;
        double ft = (1.0 - R) / fabs(wi.z);
        *out = (bsdf_sample){wi, rgb_grey(radiance ? ft / (etap * etap) : ft), pt / (pr + pt),
                             true, true, false, etap};
        return true;
    }
    if (wo.z == 0.0)
        return false;
    vec3 wm = tr_sample_wm(d, wo, u);
    double R = fresnel_dielectric(v3_dot(wo, wm), eta);
    split(R, flags, &pr, &pt);
    if (pr == 0.0 && pt == 0.0)
        return false;
    if (uc < pr / (pr + pt)) {
        vec3 wi = reflect_dir(wo, wm);
        if (!same_hemisphere(wo, wi))
            return false;
        double pdf = tr_d_visible(d, wo, wm) / (4.0 * fabs(v3_dot(wo, wm))) * pr / (pr + pt);
        double f = tr_d(d, wm) * tr_g(d, wo, wi) * R / (4.0 * wi.z * wo.z);
        if (!(pdf > 0.0))
            return false;
        *out = (bsdf_sample){wi, rgb_grey(f), pdf, false, false, false, 1.0};
        return true;
    }
    vec3 wi;
    double etap;
    if (!refract_dir(wo, wm, eta, &etap, &wi) || same_hemisphere(wo, wi) || wi.z == 0.0)
        return false;
    double denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    denom *= denom;
    double dwm_dwi = fabs(v3_dot(wi, wm)) / denom;
    double pdf = tr_d_visible(d, wo, wm) * dwm_dwi * pt / (pr + pt);
    double ft = (1.0 - R) * tr_d(d, wm) * tr_g(d, wo, wi) *
                fabs(v3_dot(wi, wm) * v3_dot(wo, wm) / (wi.z * wo.z * denom));
    if (!(pdf > 0.0))
        return false;
    *out = (bsdf_sample){wi, rgb_grey(radiance ? ft / (etap * etap) : ft), pdf, false, true,
                         false, etap};
    return true;
}

/* ---- thin dielectric (pbrt-v4's ThinDielectricBxDF): the interreflections
 * inside the sheet summed, transmission straight through ---- */

bool bxdf_thin_sample(double eta, vec3 wo, double uc, bsdf_sample *out)
{
    double R = fresnel_dielectric(fabs(wo.z), eta), T = 1.0 - R;
    if (R < 1.0) {
        R += T * T * R / (1.0 - R * R);
        T = 1.0 - R;
    }
    if (uc < R / (R + T)) {
        vec3 wi = v3(-wo.x, -wo.y, wo.z);
        if (wi.z == 0.0)
            return false;
        *out = (bsdf_sample){wi, rgb_grey(R / fabs(wi.z)), R / (R + T), true, false, false, 1.0};
        return true;
    }
    vec3 wi = v3_neg(wo);
    if (wi.z == 0.0)
        return false;
    /* Straight through the sheet: no index crossed. */
    *out = (bsdf_sample){wi, rgb_grey(T / fabs(wi.z)), T / (R + T), true, true, false, 1.0};
    return true;
}

/* ---- diffuse transmission (pbrt-v4's DiffuseTransmissionBxDF) ---- */

rgb bxdf_dt_f(rgb r, rgb t, vec3 wo, vec3 wi)
{
    return rgb_scale(same_hemisphere(wo, wi) ? r : t, HZ_INV_PI);
}

double bxdf_dt_pdf(rgb r, rgb t, vec3 wo, vec3 wi)
{
    double pr = rgb_max(r), pt = rgb_max(t);
    return (same_hemisphere(wo, wi) ? pr : pt) / (pr + pt) * cosine_hemisphere_pdf(fabs(wi.z));
}

bool bxdf_dt_sample(rgb r, rgb t, vec3 wo, double uc, vec2 u, bsdf_sample *out)
{
    double pr = rgb_max(r), pt = rgb_max(t);
    vec3 wi = sample_cosine_hemisphere(u);
    bool reflect = uc < pr / (pr + pt);
    /* Reflection on wo's side, transmission on the other. */
    if ((wo.z < 0.0) == reflect)
        wi.z = -wi.z;
    if (wi.z == 0.0)
        return false;
    *out = (bsdf_sample){wi, bxdf_dt_f(r, t, wo, wi), bxdf_dt_pdf(r, t, wo, wi), false, !reflect,
                         false, 1.0};
    return out->pdf > 0.0;
}
