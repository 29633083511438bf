#include "render/color_choice.h"

color_choice color_choice_auto(const color_choice_scene *sc)
{
    color_choice out = {false, NULL};
    if (sc->camera_sensor) {
        out.spectral = true;
        out.why = "a camera sensor";
        return out;
    }
    if (sc->clamped) {
        out.spectral = true;
        out.why = "a Film maxcomponentvalue (it clamps each sample's wavelengths)";
        return out;
    }
    for (size_t i = 0; i < sc->medium_count; ++i)
        if (medium_is_chromatic(&sc->media[i])) {
            out.spectral = true;
            out.why = "a coloured medium";
            return out;
        }
    bool dispersive = sc->volpath && sc->default_material->dispersive;
    for (size_t i = 0; i < sc->material_count && !dispersive; ++i)
        dispersive = sc->volpath && sc->materials[i].dispersive;
    if (dispersive) {
        out.spectral = true;
        out.why = "a dispersive glass";
        return out;
    }
    bool nonlinear = material_is_spectrally_nonlinear(sc->default_material);
    for (size_t i = 0; i < sc->material_count && !nonlinear; ++i)
        nonlinear = material_is_spectrally_nonlinear(&sc->materials[i]);
    if (nonlinear) {
        out.spectral = true;
        out.why = "a coloured metal, coating, hair or measured material";
    }
    return out;
}
