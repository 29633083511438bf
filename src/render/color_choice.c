#include "render/color_choice.h"

#include <stdlib.h>

#include "color/rgb2spec_module.h"
#include "textures/texture.h"

/* The colours whose products are checked, each once: at most this many
 * reflectances and emissions (the first ones met; a scene of more colours
 * is checked on those). */
enum { MAX_REFLECTANCES = 64, MAX_EMISSIONS = 16, TEXTURE_GRID = 4 };

typedef struct {
    spectrum_value v[MAX_REFLECTANCES + MAX_EMISSIONS];
    int count, reflectances, emissions;
} colour_set;

static bool same(const spectrum_value *a, const spectrum_value *b)
{
    return a->kind == b->kind && a->use == b->use && a->rgb.r == b->rgb.r &&
           a->rgb.g == b->rgb.g && a->rgb.b == b->rgb.b && a->kelvin == b->kelvin &&
           a->value == b->value && a->scale == b->scale;
}

static void add(colour_set *s, spectrum_value v)
{
    bool emission = v.use == SPECTRUM_USE_ILLUMINANT;
    if (emission ? s->emissions >= MAX_EMISSIONS : s->reflectances >= MAX_REFLECTANCES)
        return;
    if (rgb_max(v.rgb) <= 0.0)
        return;
    for (int i = 0; i < s->count; ++i)
        if (same(&s->v[i], &v))
            return;
    s->v[s->count++] = v;
    if (emission)
        s->emissions++;
    else
        s->reflectances++;
}

/* A reflectance: a constant, or what its texture gives on a grid of (u, v). */
static void add_reflectance(colour_set *s, rgb constant, const texture *tex)
{
    if (!tex) {
        add(s, spectrum_value_rgb(constant, SPECTRUM_USE_ALBEDO));
        return;
    }
    for (int j = 0; j < TEXTURE_GRID; ++j)
        for (int i = 0; i < TEXTURE_GRID; ++i) {
            texture_ctx c = {0};
            c.u = (i + 0.5) / TEXTURE_GRID;
            c.v = (j + 0.5) / TEXTURE_GRID;
            c.p = v3(c.u, c.v, 0.5);
            c.n = v3(0.0, 0.0, 1.0);
            rgb v = texture_eval(tex, &c);
            v = rgb_make(v.r < 0 ? 0 : (v.r > 1 ? 1 : v.r), v.g < 0 ? 0 : (v.g > 1 ? 1 : v.g),
                         v.b < 0 ? 0 : (v.b > 1 ? 1 : v.b));
            add(s, spectrum_value_rgb(v, SPECTRUM_USE_ALBEDO));
        }
}

static void add_material(colour_set *s, const material *m)
{
    switch (m->kind) {
    case MATERIAL_DIFFUSE_TRANSMISSION:
        add_reflectance(s, m->transmittance, m->transmittance_tex);
        /* fall through */
    case MATERIAL_DIFFUSE:
        add_reflectance(s, m->reflectance, m->reflectance_tex);
        break;
    case MATERIAL_CONDUCTOR: /* nonlinear colours: decided before */
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
    case MATERIAL_HAIR:
    case MATERIAL_MEASURED:
    case MATERIAL_DIELECTRIC: /* no colour */
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_MIX: /* its components are in the list */
    case MATERIAL_INTERFACE:
        break;
    }
}

static void add_light(colour_set *s, const light *l)
{
    const light_image *img = l->kind == LIGHT_INFINITE ? l->infinite.image
                             : l->kind == LIGHT_AREA   ? l->area.image
                             : l->kind == LIGHT_POINT  ? l->point.image
                                                       : NULL;
    if (img) /* its average colour, as an RGB emission */
        add(s, spectrum_value_rgb(rgb_mul(l->emit, light_image_average(img)),
                                  SPECTRUM_USE_ILLUMINANT));
    else
        add(s, l->spectrum);
}

/* The largest product error among the set's colours: each reflectance with
 * each (itself too), each emission with each reflectance. */
static double worst_product(const rgb2spec_table *t, const colour_set *s)
{
    spectral_samples *tab = malloc((size_t)(s->count ? s->count : 1) * sizeof *tab);
    if (!tab)
        return 1.0; /* cannot tell: the accurate mode */
    for (int i = 0; i < s->count; ++i)
        spectral_samples_make(t, &s->v[i], &tab[i]);
    double worst = 0.0;
    for (int i = 0; i < s->count; ++i)
        for (int j = i; j < s->count; ++j) {
            if (tab[i].illuminant && tab[j].illuminant)
                continue;
            double e = spectral_product_error(t, &tab[i], &tab[j]);
            worst = e > worst ? e : worst;
        }
    free(tab);
    return worst;
}

color_choice color_choice_auto(const color_choice_scene *sc, hz_error *err)
{
    color_choice out = {false, NULL, 0.0};
    err->message[0] = '\0';
    for (size_t i = 0; i < sc->medium_count; ++i)
        if (medium_is_chromatic(&sc->media[i])) {
            out.spectral = true;
            out.why = "a coloured medium";
            return out;
        }
    bool nonlinear = material_is_spectrally_nonlinear(sc->default_material);
    for (size_t i = 0; i < sc->material_count && !nonlinear; ++i)
        nonlinear = material_is_spectrally_nonlinear(&sc->materials[i]);
    if (nonlinear) {
        out.spectral = true;
        out.why = "a coloured metal, coating, hair or measured material";
        return out;
    }
    colour_set *s = calloc(1, sizeof *s);
    if (!s) {
        out.spectral = true;
        out.why = "no memory to check its colours";
        return out;
    }
    add_material(s, sc->default_material);
    for (size_t i = 0; i < sc->material_count; ++i)
        add_material(s, &sc->materials[i]);
    bool coloured = false; /* a grey reflectance scales any spectrum exactly */
    for (int i = 0; i < s->count; ++i)
        coloured |= s->v[i].rgb.r != s->v[i].rgb.g || s->v[i].rgb.g != s->v[i].rgb.b;
    if (!coloured) {
        free(s);
        return out;
    }
    for (size_t i = 0; i < sc->light_count; ++i)
        add_light(s, &sc->lights[i]);
    const rgb2spec_table *tables;
    if (rgb2spec_tables_load(&tables, err) != HZ_OK) {
        free(s);
        return out;
    }
    out.worst_error = worst_product(&tables[COLOR_SPACE_SRGB], s);
    free(s);
    if (out.worst_error > COLOR_CHOICE_TOLERANCE) {
        out.spectral = true;
        out.why = "colours whose products RGB gets wrong";
    }
    return out;
}
