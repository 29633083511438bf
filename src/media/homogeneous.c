/* "homogeneous": constant coefficients everywhere (pbrt-v4's
 * HomogeneousMedium): sigma_a, sigma_s (spectra, default 1, or a measured
 * "preset"), scale (default 1), g (Henyey–Greenstein, default 0), Le (an
 * illuminant spectrum, default 0, normalised as a light's: "rgb Le" stays
 * that RGB, "blackbody Le" has luminance 1) times Lescale (default 1).
 * Integrators use closed forms in it; its majorant is sigma_t over the whole
 * ray. */
#include "media/medium.h"
#include "media/medium_params.h"

static hz_status create(medium_entity *e, const medium_build *b, medium *out, hz_error *err)
{
    (void)b;
    param_list *pl = &e->entity.params;
    medium_param_rules rules = {false, true, MEDIUM_LE_READ, true};
    medium_common_params c;
    medium_params_read(pl, &rules, &c);
    medium_params_check_emission(pl, &c);
    if (medium_params_finish(e, &c, out, err) != HZ_OK)
        return HZ_ERROR;
    out->Le = rgb_scale(c.Le, c.Le_scale);
    out->emissive = !rgb_is_black(out->Le) && !rgb_is_black(out->sigma_a);
    return HZ_OK;
}

static bool ray_start(const medium *m, vec3 o, vec3 d, double time, double *t0, double *t1,
                      medium_ray *r)
{
    (void)o, (void)d, (void)time;
    medium_ray_single(r, m, *t0, *t1, 1.0, 1.0);
    return true;
}

static void sample(medium_ray *r, double t, bool emission, medium_props *p, uint64_t *lookups)
{
    (void)t, (void)lookups;
    medium_props_scaled(r->m, 1.0, emission, p);
}

const medium_ops medium_homogeneous_ops = {
    .name = "homogeneous",
    .homogeneous = true,
    .create = create,
    .ray_start = ray_start,
    .sample = sample,
};
