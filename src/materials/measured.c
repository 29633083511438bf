#include "materials/measured.h"

#include <math.h>

#include "materials/microfacet.h"

/* What a lookup needs of wo (on the upper side) and the normal wm. */
typedef struct {
    vec3 wo, wi, wm;
    double phi_o;
    vec2 u_wo, u_wm;
    warp2d_slice slice; /* of (phi_o, theta_o): vndf, luminance and rgb share it */
} lookup_at;

/* The elevation of a unit vector, accurate near the pole (Mitsuba's form
 * of acos(z)). */
static double elevation(vec3 d)
{
    double half = 0.5 * sqrt(d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0));
    return 2.0 * asin(fmin(half, 1.0));
}

/* The tables' axes: x = sqrt(2 theta / pi) (finer near the normal), y the
 * azimuth over [-pi, pi]. */
static double theta_to_u(double theta) { return sqrt(theta * (2.0 / HZ_PI)); }
static double phi_to_u(double phi) { return phi * (0.5 / HZ_PI) + 0.5; }
static double u_to_theta(double u) { return u * u * (0.5 * HZ_PI); }
static double u_to_phi(double u) { return (2.0 * u - 1.0) * HZ_PI; }

static void set_wo(const measured_brdf *m, vec3 wo, lookup_at *g)
{
    double theta_o = elevation(wo);
    g->wo = wo;
    g->phi_o = atan2(wo.y, wo.x);
    g->u_wo = v2(theta_to_u(theta_o), phi_to_u(g->phi_o));
    const double params[2] = {g->phi_o, theta_o};
    g->slice = warp2d_slice_at(&m->vndf, params);
}

/* wo and wi moved to the upper side, and their half vector; false when
 * they are on different sides or opposite. */
static bool set_pair(const measured_brdf *m, vec3 wo, vec3 wi, lookup_at *g)
{
    if (!same_hemisphere(wo, wi))
        return false;
    if (wo.z < 0.0) {
        wo = v3_neg(wo);
        wi = v3_neg(wi);
    }
    vec3 wm = v3_add(wo, wi);
    if (v3_length_sq(wm) == 0.0)
        return false;
    wm = v3_normalize(wm);
    set_wo(m, wo, g);
    g->wi = wi;
    g->wm = wm;
    double phi_m = atan2(wm.y, wm.x);
    g->u_wm = v2(theta_to_u(elevation(wm)), phi_to_u(m->isotropic ? phi_m - g->phi_o : phi_m));
    g->u_wm.y -= floor(g->u_wm.y);
    return true;
}

/* f at the sample-square point u for the light direction's cosine cos_i. */
static rgb reflectance(const measured_brdf *m, const lookup_at *g, vec2 u, double cos_i)
{
    double c[3];
    for (int i = 0; i < 3; ++i)
        c[i] = fmax(warp2d_eval(&m->rgb[i], &g->slice, u), 0.0);
    double k = 1.0 / cos_i;
    if (m->jacobian) {
        const warp2d_slice none = warp2d_slice_none();
        double sigma = warp2d_eval(&m->sigma, &none, g->u_wo);
        if (!(sigma > 0.0))
            return rgb_grey(0.0);
        k *= warp2d_eval(&m->ndf, &none, g->u_wm) / (4.0 * sigma);
    }
    rgb f = rgb_make(c[0] * k, c[1] * k, c[2] * k);
    return isfinite(f.r + f.g + f.b) ? f : rgb_grey(0.0);
}

/* From the density of u_wm over the square to the density of wi per solid
 * angle: dw_m = 2 pi^2 x sin(theta_m) dx dy, and dw_i = 4 (wo.wm) dw_m. */
static double square_to_wi(const lookup_at *g, double sin_theta_m)
{
    return 4.0 * v3_dot(g->wo, g->wm) *
           fmax(2.0 * HZ_PI * HZ_PI * g->u_wm.x * sin_theta_m, 1e-6);
}

rgb bxdf_measured_f(const measured_brdf *m, vec3 wo, vec3 wi)
{
    lookup_at g;
    if (!set_pair(m, wo, wi, &g))
        return rgb_grey(0.0);
    double pdf;
    vec2 u = warp2d_invert(&m->vndf, &g.slice, g.u_wm, &pdf);
    return reflectance(m, &g, u, g.wi.z);
}

double bxdf_measured_pdf(const measured_brdf *m, vec3 wo, vec3 wi)
{
    lookup_at g;
    if (!set_pair(m, wo, wi, &g))
        return 0.0;
    double vndf_pdf;
    vec2 u = warp2d_invert(&m->vndf, &g.slice, g.u_wm, &vndf_pdf);
    double lum_pdf = warp2d_eval(&m->luminance, &g.slice, u);
    double sin_m = sqrt(g.wm.x * g.wm.x + g.wm.y * g.wm.y);
    double pdf = vndf_pdf * lum_pdf / square_to_wi(&g, sin_m);
    return pdf > 0.0 && isfinite(pdf) ? pdf : 0.0;
}

bool bxdf_measured_sample(const measured_brdf *m, vec3 wo, vec2 u, bsdf_sample *out)
{
    bool flip = wo.z <= 0.0;
    lookup_at g;
    set_wo(m, flip ? v3_neg(wo) : wo, &g);
    vec2 us;
    double lum_pdf, vndf_pdf;
    if (!warp2d_sample(&m->luminance, &g.slice, u, &us, &lum_pdf) ||
        !warp2d_sample(&m->vndf, &g.slice, us, &g.u_wm, &vndf_pdf))
        return false;
    double phi_m = u_to_phi(g.u_wm.y) + (m->isotropic ? g.phi_o : 0.0);
    double theta_m = u_to_theta(g.u_wm.x), sin_m = sin(theta_m);
    g.wm = v3(sin_m * cos(phi_m), sin_m * sin(phi_m), cos(theta_m));
    g.wi = reflect_dir(g.wo, g.wm);
    if (!(g.wi.z > 0.0))
        return false;
    out->f = reflectance(m, &g, us, g.wi.z);
    out->pdf = vndf_pdf * lum_pdf / square_to_wi(&g, sin_m);
    out->wi = flip ? v3_neg(g.wi) : g.wi;
    out->specular = out->transmission = out->pdf_proportional = false;
    out->eta = 1.0;
    return out->pdf > 0.0 && isfinite(out->pdf);
}
