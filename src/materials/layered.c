#include "materials/layered.h"

#include <math.h>

#include "core/hash.h"
#include "core/phase.h"
#include "core/rng.h"

/* ---- the two interfaces ---- */

typedef enum { TOP, BOTTOM } iface;

static rgb if_f(const layered *l, iface i, vec3 wo, vec3 wi, bool radiance)
{
    if (i == TOP)
        return bxdf_dielectric_f(l->top, l->eta, wo, wi, radiance);
    return l->conductor ? bxdf_conductor_f(l->bottom, l->eta_rgb, l->k, wo, wi)
                        : bxdf_diffuse_f(l->reflectance, wo, wi);
}

static double if_pdf(const layered *l, iface i, vec3 wo, vec3 wi, bxdf_flags flags)
{
    if (i == TOP)
        return bxdf_dielectric_pdf(l->top, l->eta, wo, wi, flags);
    return l->conductor ? bxdf_conductor_pdf(l->bottom, wo, wi, flags)
                        : bxdf_diffuse_pdf(wo, wi, flags);
}

static bool if_sample(const layered *l, iface i, vec3 wo, double uc, vec2 u, bxdf_flags flags,
                      bool radiance, bsdf_sample *out)
{
    bool ok;
    if (i == TOP)
        ok = bxdf_dielectric_sample(l->top, l->eta, wo, uc, u, flags, radiance, out);
    else if (l->conductor)
        ok = bxdf_conductor_sample(l->bottom, l->eta_rgb, l->k, wo, u, flags, out);
    else
        ok = bxdf_diffuse_sample(l->reflectance, wo, u, flags, out);
    /* pbrt-v4 drops samples with no value, no density or a grazing wi. */
    return ok && !rgb_is_black(out->f) && out->pdf > 0.0 && out->wi.z != 0.0;
}

static bool if_specular(const layered *l, iface i)
{
    if (i == TOP)
        return bxdf_dielectric_smooth(l->top, l->eta);
    return l->conductor && bxdf_conductor_smooth(l->bottom);
}

/* ---- helpers ---- */

/* Transmittance through a layer of thickness dz along w (unit mean free
 * path). */
static double tr(double dz, vec3 w)
{
    if (fabs(dz) <= 1e-300)
        return 1.0;
    return exp(-fabs(dz / w.z));
}

static double power_heuristic(double f, double g)
{
    if (isinf(f * f))
        return 1.0;
    return f * f / (f * f + g * g);
}

/* A stream seeded by the directions (and numbers) it estimates for. */
static rng stream(vec3 a, vec3 b, double c)
{
    const double v[7] = {a.x, a.y, a.z, b.x, b.y, b.z, c};
    return rng_seeded(fnv1a(HZ_FNV_OFFSET, v, sizeof v));
}

static inline vec2 r2(rng *r)
{
    double a = rng_uniform(r);
    return v2(a, rng_uniform(r));
}

bool layered_is_non_specular(const layered *l)
{
    /* pbrt-v4: diffuse if the base is, or a medium scatters; glossy if
     * either interface is rough. */
    return !rgb_is_black(l->albedo) || !if_specular(l, TOP) || !if_specular(l, BOTTOM);
}

/* ---- f: random walks from wo into the layers, joined to wi ---- */

/* The state of layered_f's walks: the fixed ends, the estimate they add
 * to, and the walk under way. */
typedef struct {
    const layered *l;
    vec3 wi;
    iface exit_if, non_exit; /* the exit is the top for reflection */
    double exit_z;
    rng r;
    rgb f;           /* the sum over the walks */
    bsdf_sample wis; /* wi's transmission through the exit, presampled per walk */
    rgb beta;        /* the walk's throughput */
    double z;        /* its height, in [0, thickness] */
    vec3 w;          /* its direction */
} f_walk;

/* Russian roulette from the fifth vertex on; false: the walk ends. */
static inline bool f_survives_roulette(f_walk *fw, int depth)
{
    if (depth > 3 && rgb_max(fw->beta) < 0.25) {
        double q = fmax(0.0, 1.0 - rgb_max(fw->beta));
        if (rng_uniform(&fw->r) < q)
            return false;
        fw->beta = rgb_scale(fw->beta, 1.0 / (1.0 - q));
    }
    return true;
}

/* A scattering event in the medium at zp: toward wi through the exit, then
 * a phase-function sample, joined to wi when it heads for the exit. */
static inline void f_scatter_in_medium(f_walk *fw, double zp)
{
    const layered *l = fw->l;
    const bsdf_sample *wis = &fw->wis;
    double ph = hg_phase(v3_dot(v3_neg(fw->w), v3_neg(wis->wi)), l->g);
    double wt = if_specular(l, fw->exit_if) ? 1.0 : power_heuristic(wis->pdf, ph);
    fw->f = rgb_add(fw->f, rgb_scale(rgb_mul(rgb_mul(fw->beta, l->albedo), wis->f),
                                     ph * wt * tr(zp - fw->exit_z, wis->wi) / wis->pdf));
    double ppdf;
    vec3 pw = hg_sample(v3_neg(fw->w), l->g, r2(&fw->r), &ppdf);
    if (!(ppdf > 0.0) || pw.z == 0.0)
        return;
    fw->beta = rgb_mul(fw->beta, l->albedo); /* p / pdf = 1: exact HG sampling */
    fw->w = pw;
    fw->z = zp;
    if (((fw->z < fw->exit_z && fw->w.z > 0.0) || (fw->z > fw->exit_z && fw->w.z < 0.0)) &&
        !if_specular(l, fw->exit_if)) {
        rgb fe = if_f(l, fw->exit_if, v3_neg(fw->w), fw->wi, true);
        if (!rgb_is_black(fe)) {
            double epdf = if_pdf(l, fw->exit_if, v3_neg(fw->w), fw->wi, BXDF_TRANSMISSION);
            fw->f = rgb_add(fw->f, rgb_scale(rgb_mul(fw->beta, fe),
                                             tr(zp - fw->exit_z, pw) *
                                                 power_heuristic(ppdf, epdf)));
        }
    }
}

/* A reflection at interface `at` back into the layers; false: none was
 * sampled, the walk ends. */
static inline bool f_reflect_at(f_walk *fw, iface at, bsdf_sample *bs)
{
    double uc = rng_uniform(&fw->r);
    if (!if_sample(fw->l, at, v3_neg(fw->w), uc, r2(&fw->r), BXDF_REFLECTION, true, bs))
        return false;
    fw->beta = rgb_mul(fw->beta, rgb_scale(bs->f, fabs(bs->wi.z) / bs->pdf));
    fw->w = bs->wi;
    return true;
}

/* Light from wi through the exit (along the presampled wis), scattered at
 * the other interface toward -w. */
static inline void f_add_non_exit_light(f_walk *fw)
{
    const layered *l = fw->l;
    const bsdf_sample *wis = &fw->wis;
    double wt = if_specular(l, fw->exit_if)
                    ? 1.0
                    : power_heuristic(wis->pdf, if_pdf(l, fw->non_exit, v3_neg(fw->w),
                                                       v3_neg(wis->wi), BXDF_ALL));
    rgb fn = if_f(l, fw->non_exit, v3_neg(fw->w), v3_neg(wis->wi), true);
    fw->f = rgb_add(fw->f, rgb_scale(rgb_mul(rgb_mul(fw->beta, fn), wis->f),
                                     fabs(wis->wi.z) * wt * tr(l->thickness, wis->wi) /
                                         wis->pdf));
}

/* The walk's new direction w, just reflected at the other interface (`bs`),
 * joined to wi through a rough exit. */
static inline void f_add_exit_light(f_walk *fw, const bsdf_sample *bs)
{
    const layered *l = fw->l;
    rgb fe = if_f(l, fw->exit_if, v3_neg(fw->w), fw->wi, true);
    if (rgb_is_black(fe))
        return;
    /* pbrt-v4 weighs this against the exit's pdf of wi from -w, not of -w
     * from wi (the density the wis strategy has): with a rough coating its
     * f is then up to ~10% above what its sampling reflects. Kept for
     * pbrt-v4's images (docs/differences-from-pbrt.md). */
    double wt = 1.0;
    if (!if_specular(l, fw->non_exit))
        wt = power_heuristic(bs->pdf, if_pdf(l, fw->exit_if, v3_neg(fw->w), fw->wi,
                                             BXDF_TRANSMISSION));
    fw->f = rgb_add(fw->f, rgb_scale(rgb_mul(fw->beta, fe), tr(l->thickness, bs->wi) * wt));
}

/* One walk between the interfaces from the top (fw->beta, z, w set),
 * adding what reaches wi at each vertex to fw->f. */
static inline void f_walk_layers(f_walk *fw)
{
    const layered *l = fw->l;
    bool scatters = !rgb_is_black(l->albedo);
    for (int depth = 0; depth < l->max_depth; ++depth) {
        if (!f_survives_roulette(fw, depth))
            break;
        if (!scatters) {
            fw->z = fw->z == l->thickness ? 0.0 : l->thickness;
            fw->beta = rgb_scale(fw->beta, tr(l->thickness, fw->w));
        } else {
            double dz = rng_exp1(&fw->r) * fabs(fw->w.z);
            double zp = fw->w.z > 0.0 ? fw->z + dz : fw->z - dz;
            if (zp == fw->z)
                continue;
            if (0.0 < zp && zp < l->thickness) {
                f_scatter_in_medium(fw, zp);
                continue;
            }
            fw->z = zp < 0.0 ? 0.0 : zp > l->thickness ? l->thickness : zp;
        }
        bsdf_sample bs;
        if (fw->z == fw->exit_z) {
            if (!f_reflect_at(fw, fw->exit_if, &bs))
                break;
            continue;
        }
        /* Scattering at the other interface: light from wi through the
         * exit, then a new direction. */
        if (!if_specular(l, fw->non_exit))
            f_add_non_exit_light(fw);
        if (!f_reflect_at(fw, fw->non_exit, &bs))
            break;
        if (!if_specular(l, fw->exit_if))
            f_add_exit_light(fw, &bs);
    }
}

rgb layered_f(const layered *l, vec3 wo, vec3 wi)
{
    if (wo.z < 0.0) { /* two-sided */
        wo = v3_neg(wo);
        wi = v3_neg(wi);
    }
    /* Entered at the top; the exit is the top for reflection. */
    bool reflect = same_hemisphere(wo, wi);
    f_walk fw;
    fw.l = l;
    fw.wi = wi;
    fw.exit_if = reflect ? TOP : BOTTOM;
    fw.non_exit = reflect ? BOTTOM : TOP;
    fw.exit_z = reflect ? l->thickness : 0.0;
    fw.f = rgb_grey(0.0);
    if (reflect)
        fw.f = rgb_scale(if_f(l, TOP, wo, wi, true), l->n_samples);
    fw.r = stream(wo, wi, 0.0);
    for (int s = 0; s < l->n_samples; ++s) {
        bsdf_sample wos;
        double uc = rng_uniform(&fw.r);
        if (!if_sample(l, TOP, wo, uc, r2(&fw.r), BXDF_TRANSMISSION, true, &wos))
            continue;
        uc = rng_uniform(&fw.r);
        if (!if_sample(l, fw.exit_if, wi, uc, r2(&fw.r), BXDF_TRANSMISSION, false, &fw.wis))
            continue;
        fw.beta = rgb_scale(wos.f, fabs(wos.wi.z) / wos.pdf);
        fw.z = l->thickness;
        fw.w = wos.wi;
        f_walk_layers(&fw);
    }
    return rgb_scale(fw.f, 1.0 / l->n_samples);
}

/* ---- sampling: one random walk from wo until it leaves ---- */

bool layered_sample(const layered *l, vec3 wo, double uc, vec2 u, bsdf_sample *out)
{
    bool flip = wo.z < 0.0;
    if (flip)
        wo = v3_neg(wo);
    bsdf_sample bs;
    if (!if_sample(l, TOP, wo, uc, u, BXDF_ALL, true, &bs))
        return false;
    if (!bs.transmission) {
        *out = bs;
        out->pdf_proportional = true;
        if (flip)
            out->wi = v3_neg(out->wi);
        return true;
    }
    vec3 w = bs.wi;
    bool specular = bs.specular;
    rng r = stream(wo, v3(u.x, u.y, 0.0), uc);
    rgb f = rgb_scale(bs.f, fabs(bs.wi.z));
    double pdf = bs.pdf;
    double z = l->thickness;
    bool scatters = !rgb_is_black(l->albedo);
    for (int depth = 0; depth < l->max_depth; ++depth) {
        double rr = rgb_max(f) / pdf;
        if (depth > 3 && rr < 0.25) {
            double q = fmax(0.0, 1.0 - rr);
            if (rng_uniform(&r) < q)
                return false;
            pdf *= 1.0 - q;
        }
        if (w.z == 0.0)
            return false;
        if (scatters) {
            double dz = rng_exp1(&r) * fabs(w.z);
            double zp = w.z > 0.0 ? z + dz : z - dz;
            if (zp == z)
                return false;
            if (0.0 < zp && zp < l->thickness) {
                double ppdf;
                vec3 pw = hg_sample(v3_neg(w), l->g, r2(&r), &ppdf);
                if (!(ppdf > 0.0) || pw.z == 0.0)
                    return false;
                f = rgb_scale(rgb_mul(f, l->albedo), ppdf);
                pdf *= ppdf;
                specular = false;
                w = pw;
                z = zp;
                continue;
            }
            z = zp < 0.0 ? 0.0 : zp > l->thickness ? l->thickness : zp;
        } else {
            z = z == l->thickness ? 0.0 : l->thickness;
            f = rgb_scale(f, tr(l->thickness, w));
        }
        iface at = z == 0.0 ? BOTTOM : TOP;
        uc = rng_uniform(&r);
        if (!if_sample(l, at, v3_neg(w), uc, r2(&r), BXDF_ALL, true, &bs))
            return false;
        f = rgb_mul(f, bs.f);
        pdf *= bs.pdf;
        specular = specular && bs.specular;
        w = bs.wi;
        if (bs.transmission) { /* left the layers */
            /* pbrt-v4's LayeredBxDF: eta 1 (the layers' indices are inside). */
            *out = (bsdf_sample){flip ? v3_neg(w) : w, f, pdf, specular,
                                 !same_hemisphere(wo, w), true, 1.0};
            return true;
        }
        f = rgb_scale(f, fabs(bs.wi.z));
    }
    return false;
}

/* ---- pdf: an estimate mixed with the uniform density ---- */

double layered_pdf(const layered *l, vec3 wo, vec3 wi)
{
    if (wo.z < 0.0) {
        wo = v3_neg(wo);
        wi = v3_neg(wi);
    }
    rng r = stream(wi, wo, 1.0);
    double sum = 0.0;
    bool reflect = same_hemisphere(wo, wi);
    if (reflect)
        sum += l->n_samples * if_pdf(l, TOP, wo, wi, BXDF_REFLECTION);
    for (int s = 0; s < l->n_samples; ++s) {
        if (reflect) {
            /* Transmission down, reflection at the base, transmission up. */
            bsdf_sample wos, wis;
            double a = rng_uniform(&r);
            bool ok_o = if_sample(l, TOP, wo, a, r2(&r), BXDF_TRANSMISSION, true, &wos);
            a = rng_uniform(&r);
            bool ok_i = if_sample(l, TOP, wi, a, r2(&r), BXDF_TRANSMISSION, false, &wis);
            if (!ok_o || !ok_i)
                continue;
            if (if_specular(l, TOP)) {
                sum += if_pdf(l, BOTTOM, v3_neg(wos.wi), v3_neg(wis.wi), BXDF_ALL);
                continue;
            }
            bsdf_sample rs;
            a = rng_uniform(&r);
            if (!if_sample(l, BOTTOM, v3_neg(wos.wi), a, r2(&r), BXDF_ALL, true, &rs))
                continue;
            if (if_specular(l, BOTTOM)) {
                sum += if_pdf(l, TOP, v3_neg(rs.wi), wi, BXDF_ALL);
                continue;
            }
            double rpdf = if_pdf(l, BOTTOM, v3_neg(wos.wi), v3_neg(wis.wi), BXDF_ALL);
            sum += power_heuristic(wis.pdf, rpdf) * rpdf;
            double tpdf = if_pdf(l, TOP, v3_neg(rs.wi), wi, BXDF_ALL);
            sum += power_heuristic(rs.pdf, tpdf) * tpdf;
        }
        /* The coated materials' bases do not transmit: no TT term. */
    }
    return hz_lerp(0.9, 1.0 / (4.0 * HZ_PI), sum / l->n_samples);
}
