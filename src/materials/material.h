/* Surface materials: a closed set (diffuse, interface). */
#ifndef HAZE_MATERIALS_MATERIAL_H
#define HAZE_MATERIALS_MATERIAL_H

#include "core/error.h"
#include "core/vec.h"
#include "scene/scene_desc.h"

typedef enum {
    MATERIAL_DIFFUSE,   /* Lambertian reflection, two-sided as in pbrt-v4 */
    MATERIAL_INTERFACE, /* a medium boundary: not a surface, rays pass through */
} material_kind;

typedef struct {
    material_kind kind;
    rgb reflectance;    /* diffuse */
} material;

/* pbrt-v4's default material: diffuse, reflectance 0.5. */
material material_default(void);

/* Material "diffuse" ("rgb reflectance", default 0.5) and "interface" (also
 * "" and "none", which pbrt-v4 treats alike: no surface); other types are
 * errors listing the supported ones. */
hz_status material_from_entity(material_entity *e, material *out, hz_error *err);

#endif
