/* Surface materials: a closed set, pbrt-v4's "diffuse", "conductor",
 * "dielectric", "thindielectric", "diffusetransmission", "coateddiffuse",
 * "coatedconductor", "measured" and "interface" (also "" and "none"), with
 * constant parameters. */
#ifndef HAZE_MATERIALS_MATERIAL_H
#define HAZE_MATERIALS_MATERIAL_H

#include "color/spectral.h"
#include "core/error.h"
#include "core/vec.h"
#include "materials/layered.h"
#include "materials/measured_data.h"
#include "scene/scene_desc.h"
#include "textures/texture.h"

typedef enum {
    MATERIAL_DIFFUSE,         /* Lambertian reflection, two-sided as in pbrt-v4 */
    MATERIAL_CONDUCTOR,       /* a metal: complex Fresnel, smooth or rough */
    MATERIAL_DIELECTRIC,      /* glass, water: reflection and refraction */
    MATERIAL_THIN_DIELECTRIC, /* a thin sheet of glass: straight through */
    MATERIAL_DIFFUSE_TRANSMISSION, /* Lambertian reflection and transmission (leaves, paper) */
    MATERIAL_COATED_DIFFUSE,   /* varnish over a diffuse base (plastic, paint) */
    MATERIAL_COATED_CONDUCTOR, /* varnish over a metal */
    MATERIAL_MIX,              /* one of two materials per hit, chosen at random */
    MATERIAL_HAIR,            /* pbrt-v4's hair: a rough absorbing dielectric cylinder */
    MATERIAL_MEASURED,        /* a measured BRDF read from an RGL .bsdf file */
    MATERIAL_INTERFACE,       /* a medium boundary: not a surface, rays pass through */
} material_kind;

typedef struct material_s {
    material_kind kind;
    rgb reflectance;          /* diffuse, diffuse transmission */
    rgb transmittance;        /* diffuse transmission */
    rgb eta_rgb, k;           /* conductor, per channel */
    double eta;               /* dielectric, thin dielectric */
    double alpha_x, alpha_y;  /* conductor, dielectric: Trowbridge-Reitz alphas */
    layered coat;             /* coated diffuse, coated conductor */
    /* hair: absorption inside the fibre (from "sigma_a", "reflectance" (or
     * "color") at beta_n, or the melanin concentrations), the longitudinal
     * and azimuthal roughnesses and the scale tilt in degrees; eta above */
    rgb sigma_a;
    double beta_m, beta_n, hair_alpha;
    /* measured: the file's tables, owned by the scene's measured_cache */
    const measured_brdf *measured;
    /* mix: the second material with probability `amount`, decided per hit
     * by a hash of the point and direction (pbrt-v4's MixMaterial); the
     * names until material_resolve_mixes points them at the materials. */
    double amount;
    const char *mix_names[2];
    const struct material_s *mix[2];
    const texture *amount_tex; /* mix: "texture amount" (a float texture), or NULL */
    /* Textured parameters ("texture reflectance" "name"; NULL = the constant
     * above), evaluated per hit by material_textured. rough[0..1]: u and v
     * roughness (a coated material's top interface); rough[2..3]: a coated
     * conductor's base. metal_r: a conductor's "reflectance". */
    bool textured;
    bool remap_roughness;
    const texture *reflectance_tex, *transmittance_tex;
    const texture *eta_tex, *k_tex, *metal_r_tex;
    const texture *rough[4];
    const texture *thickness_tex, *albedo_tex, *g_tex; /* coated: the layer's */
    /* "texture displacement": a float texture that bumps the shading normal
     * (pbrt-v4's BumpMap, geometry_shading_normal); NULL: none. */
    const texture *displacement;
    /* "string normalmap": the image's tangent-space normals replace the
     * shading normal (pbrt-v4's NormalMap; it wins over displacement) */
    const texture *normal_map;
    /* Conductors given by "reflectance": that reflectance (at the hit once
     * textured), which spectral rendering turns into k per wavelength. */
    bool metal_by_reflectance;
    rgb metal_r;
    /* Conductors given by eta and k: the spectra as given (the copper
     * default: pbrt-v4's metal-Cu-eta/k), which spectral rendering
     * evaluates per wavelength unless a texture gives the value. A
     * dielectric or thin dielectric whose "eta" is a spectrum that varies
     * (a named glass): that spectrum in eta_spec, and `dispersive`
     * (material_disperse); a coated material's coating of such an index:
     * interface_eta_spec, and `dispersive`. */
    spectrum_value eta_spec, k_spec, interface_eta_spec;
    bool dispersive;
    /* Spectral rendering (material_spectral): the sample's wavelengths,
     * which a measured BRDF's RGB values are turned into; NULL: RGB. */
    const spectral_ctx *spectral;
    /* Spectral rendering: the constant (untextured) colours' spectra looked
     * up once (material_prepare_spectral): the reflectance (diffuse ones, a
     * coated diffuse's base, a conductor's "reflectance"), the second colour
     * (transmittance, a coating's albedo), a conductor's eta and k (RGB
     * ones), hair's sigma_a. */
    struct {
        spectral_color first, second, eta, k;
    } prepared;
} material;

/* m or (for a mix) any material it may pick has textures. */
bool material_has_textures(const material *m);
/* m or any material it may pick is hair: its hits need (u, v) and dp/du. */
bool material_needs_hair_frame(const material *m);

/* m with its textures evaluated at c: m itself when it has none, otherwise
 * *scratch filled with the values there. */
const material *material_textured(const material *m, const texture_ctx *c, material *scratch);

/* m (as material_textured gave it) at the wavelengths of `sp`: its colours
 * become the lanes of color/spectral.h (reflectances as albedo spectra,
 * conductor indices and absorption as unbounded ones, a "reflectance"
 * conductor's k from its reflectance per wavelength). m itself when sp is
 * NULL; otherwise *scratch (which may be m) filled. */
const material *material_spectral(const material *m, const spectral_ctx *sp, material *scratch);
/* pbrt-v4's dispersion: a dispersive dielectric or coating (m->dispersive)
 * refracts each wavelength by its own index, so a path through it keeps one
 * wavelength, lane `lane` (the caller drops the others and counts it for
 * all, as pbrt-v4's TerminateSecondary): m (a copy from material_spectral,
 * not the scene's) gets that lane's index (a coated conductor's base stays
 * relative to it). */
void material_disperse(material *m, const spectral_ctx *sp, int lane);

/* Looks up the spectra of m's constant colours once (m->prepared), for
 * material_spectral. */
void material_prepare_spectral(material *m, const rgb2spec_table *t);

/* Whether m (or a material a mix may pick) has a colour that is not grey
 * (constant or textured) and enters its BSDF other than as a factor: a
 * metal's Fresnel term of coloured eta and k, the interreflections inside a
 * coating, hair's absorption, a measured BRDF. There one scattering event
 * already differs between spectral and RGB rendering (render_scene's
 * automatic choice); a diffuse colour only scales it. */
bool material_is_spectrally_nonlinear(const material *m);

/* The material a hit at p seen from wo uses: m itself, or for a mix the
 * component its hash picks (mixes of mixes followed), with the amount its
 * texture gives at c (NULL: no textures at this hit). Deterministic. */
const material *material_at(const material *m, vec3 p, vec3 wo, const texture_ctx *c);

/* Points every mix of `materials` (n, the scene's named and anonymous ones,
 * in scene_desc order with their entities) at its components, found by name
 * among the named materials defined before it. Errors name the mix's place. */
hz_status material_resolve_mixes(material *materials, const material_entity *entities, size_t n,
                                 hz_error *err);

/* pbrt-v4's default material: diffuse, reflectance 0.5. */
material material_default(void);

/* True for the materials light passes through (dielectric, thindielectric,
 * diffusetransmission; not a mix, which material_at resolves first). */
bool material_transmits(const material *m);

/* The material of a Material or MakeNamedMaterial entity, with pbrt-v4's
 * parameters and defaults; other types and parameters are errors naming
 * their place. A "measured" material's file is read into `measured` (once
 * per file; NULL: such materials are refused). */
hz_status material_from_entity(material_entity *e, const texture_set *textures,
                               measured_cache *measured, material *out, hz_error *err);

#endif
