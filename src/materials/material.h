/* Surface materials: a closed set, pbrt-v4's "diffuse", "conductor",
 * "dielectric", "thindielectric", "diffusetransmission", "coateddiffuse",
 * "coatedconductor" and "interface" (also "" and "none"), with constant
 * parameters. */
#ifndef HAZE_MATERIALS_MATERIAL_H
#define HAZE_MATERIALS_MATERIAL_H

#include "core/error.h"
#include "core/vec.h"
#include "materials/layered.h"
#include "scene/scene_desc.h"

typedef enum {
    MATERIAL_DIFFUSE,         /* Lambertian reflection, two-sided as in pbrt-v4 */
    MATERIAL_CONDUCTOR,       /* a metal: complex Fresnel, smooth or rough */
    MATERIAL_DIELECTRIC,      /* glass, water: reflection and refraction */
    MATERIAL_THIN_DIELECTRIC, /* a thin sheet of glass: straight through */
    MATERIAL_DIFFUSE_TRANSMISSION, /* Lambertian reflection and transmission (leaves, paper) */
    MATERIAL_COATED_DIFFUSE,   /* varnish over a diffuse base (plastic, paint) */
    MATERIAL_COATED_CONDUCTOR, /* varnish over a metal */
    MATERIAL_INTERFACE,       /* a medium boundary: not a surface, rays pass through */
} material_kind;

typedef struct {
    material_kind kind;
    rgb reflectance;          /* diffuse, diffuse transmission */
    rgb transmittance;        /* diffuse transmission */
    rgb eta_rgb, k;           /* conductor, per channel */
    double eta;               /* dielectric, thin dielectric */
    double alpha_x, alpha_y;  /* conductor, dielectric: Trowbridge-Reitz alphas */
    layered coat;             /* coated diffuse, coated conductor */
} material;

/* pbrt-v4's default material: diffuse, reflectance 0.5. */
material material_default(void);

/* True for the materials whose light transport needs "volpath" (anything
 * but diffuse and interface). */
bool material_needs_volpath(const material *m);

/* The material of a Material or MakeNamedMaterial entity, with pbrt-v4's
 * parameters and defaults; other types and parameters are errors naming
 * their place. */
hz_status material_from_entity(material_entity *e, material *out, hz_error *err);

#endif
