/* The parameters every medium kind reads the same way (pbrt-v4's
 * coefficients, scale, g, Le and Lescale, the temperature mapping), in the
 * order the kinds read them: a kind's create calls medium_params_read, reads
 * its own, then medium_params_finish. Private to src/media. */
#ifndef HAZE_MEDIA_MEDIUM_PARAMS_H
#define HAZE_MEDIA_MEDIUM_PARAMS_H

#include <stdbool.h>

#include "media/medium.h"
#include "scene/params.h"

/* How a kind reads the common parameters. */
typedef enum {
    MEDIUM_LE_NONE,    /* not read: no constant emission */
    MEDIUM_LE_READ,    /* "Le", default 0 */
    MEDIUM_LE_TINT,    /* "Le", default 1: the colour of an emission grid */
} medium_le_rule;

typedef struct {
    bool grid;         /* "preset" is refused (pbrt-v4 reads it for homogeneous only) */
    bool coefficients; /* "sigma_a", "sigma_s" are read (rgbgrid: its arrays instead) */
    medium_le_rule Le;
    bool Le_scale;     /* "Lescale" is read (otherwise 1) */
} medium_param_rules;

typedef struct {
    rgb sigma_a, sigma_s; /* before scale */
    double scale, g;
    rgb Le;
    double Le_scale;
    /* The same as given (spectral rendering), their rgb the values above */
    spectrum_value sigma_a_spec, sigma_s_spec, Le_spec;
} medium_common_params;

/* Reads the coefficients, scale, g, Le and Lescale; problems are recorded
 * in pl. */
void medium_params_read(param_list *pl, const medium_param_rules *rules, medium_common_params *c);
/* Checks Le and Lescale (after a kind's own Le-like parameters). */
void medium_params_check_emission(param_list *pl, const medium_common_params *c);
/* The scaled coefficients checked, every parameter used, and the common
 * fields of out set (name, sigma_a, sigma_s, g). */
hz_status medium_params_finish(medium_entity *e, const medium_common_params *c, medium *out,
                               hz_error *err);

/* What MakeNamedMedium says about a grid's emission. */
typedef struct {
    const char *name;     /* temperaturename */
    bool named;           /* given explicitly: the grid must exist */
    double offset, scale; /* temperatureoffset (or temperaturecutoff), temperaturescale */
    double Le_scale;      /* Lescale */
} temperature_params;

/* The temperature mapping of a nanovdb or uniformgrid medium (problems are
 * recorded in pl). */
void medium_params_temperature(param_list *pl, temperature_params *tp);

bool medium_rgb_is_finite(rgb c);
bool medium_transform_is_finite(const transform *t);
/* The entity's name for messages ("" when unnamed). */
const char *medium_entity_name(const medium_entity *e);

#endif
