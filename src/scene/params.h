/* Typed parameter lists of pbrt-v4 scene directives ("float fov" 45).
 *
 * Factories read what they accept with the getters (which mark a parameter used
 * and return the default when it is absent), then call params_finish(): it
 * reports the first problem met by a getter (wrong type, wrong count, bad value)
 * or the first parameter nobody read, always with its file:line:column.
 * This is how misspelled or misplaced parameters become errors, as in pbrt-v4. */
#ifndef HAZE_SCENE_PARAMS_H
#define HAZE_SCENE_PARAMS_H

#include <stdbool.h>
#include <stddef.h>

#include "core/error.h"
#include "core/vec.h"
#include "scene/spectrum_value.h"

typedef enum {
    PARAM_INTEGER,
    PARAM_FLOAT,
    PARAM_BOOL,
    PARAM_STRING,
    PARAM_POINT2,
    PARAM_VECTOR2,
    PARAM_POINT3,
    PARAM_VECTOR3,
    PARAM_NORMAL,
    PARAM_RGB,
    PARAM_SPECTRUM, /* converted to rgb at parse time (see docs/scene-format.md), and kept */
    PARAM_BLACKBODY, /* converted to rgb at parse time, and kept */
    PARAM_TEXTURE    /* the name of a Texture, in strs[0] */
} param_type;

const char *param_type_name(param_type t);

typedef struct {
    param_type type;
    char *name;
    file_loc loc;   /* where the parameter's declaration string starts */
    size_t count;   /* number of scalar values: numbers, strings or bools */
    double *nums;   /* integer, float, point*, vector*, normal, rgb (spectrum/blackbody become 3 rgb numbers) */
    char **strs;    /* string */
    bool *bools;    /* bool */
    bool used;
    bool optional;  /* a default from Attribute: never reported as unused (pbrt-v4's mayBeUnused) */
    rgb illuminant; /* spectrum: the RGB of the spectrum as a light's (params_illuminant) */
    /* spectrum, blackbody: the luminance params_illuminant divides out
     * (spectrum_*_luminance); 0: none (rgb, named illuminants) */
    double luminance;
    double at_550;  /* spectrum: its value at 550 nm (an index that does not disperse) */
    bool unit_values; /* spectrum: every value within [0, 1] (see params_reflectance) */
    /* The spectrum as given, for spectral rendering (params_spectrum). */
    double kelvin;  /* blackbody: its temperature */
    /* spectrum: `pairs` (lambda nm, value) samples, in `samples` (owned:
     * the lambdas, then the values) for inline, constant and .spd spectra,
     * in a static table for named ones (samples NULL). */
    const double *lambda, *value;
    size_t pairs;
    double *samples;
} param;

typedef struct {
    param *items;
    size_t count, capacity;
    file_loc loc;       /* the directive these parameters belong to */
    bool failed;        /* a getter met a problem; `error` holds it */
    hz_error *error;    /* malloc'ed on the first problem (NULL: out of memory then),
                         * so that a list costs no 4 KiB message buffer per shape */
} param_list;

void params_init(param_list *pl, file_loc directive);
void params_free(param_list *pl);
/* Deep copy (used when entities outlive the parser's graphics state). False
 * when out of memory; *dst is then an empty list. */
bool params_copy(param_list *dst, const param_list *src);
/* Takes ownership of p's arrays (freed here on error too). Returns HZ_ERROR if
 * the name is repeated, naming the place of the repetition, or when out of
 * memory ("out of memory" at p's place; not after params_reserve). */
hz_status params_add(param_list *pl, param p, hz_error *err);
/* Adds p after a parameter of the same name and type (reserved first): the
 * first one is the one read, as pbrt-v4; this one is never reported unused.
 * False (p freed) when there is no such first one. */
bool params_add_shadowed(param_list *pl, param p);
/* Room for one more parameter, so that the next params_add can fail only on a
 * repeated name (callers that must tell the two apart). False when out of
 * memory, pl unchanged. */
bool params_reserve(param_list *pl);
/* Adds a deep copy of every parameter of `defaults` whose name pl lacks, marked
 * optional (Attribute "shape" etc. semantics). Only fails when out of memory
 * ("out of memory" at pl's directive; the copies made so far stay in pl). */
hz_status params_add_defaults(param_list *pl, const param_list *defaults, hz_error *err);
/* Removes parameter `name` (if present) and frees it. */
void params_remove(param_list *pl, const char *name);
/* Gives parameter `from` (if present, and no `to` is) the name `to`: for
 * other spellings of a name that published scenes use. False only when out
 * of memory (pl unchanged). */
bool params_rename(param_list *pl, const char *from, const char *to);
void param_free(param *p);

/* Getters: the default when absent; on a type or count mismatch they record an
 * error in pl (reported by params_finish) and return the default. Types are
 * strict as in pbrt-v4 (params_float does not read an "integer" parameter);
 * asking for a name that exists with another type records
 * "parameter "fov" must be float, not integer". Single-value getters want
 * exactly one value (three for point3/vector3/rgb). */
double params_float(param_list *pl, const char *name, double def);
int params_int(param_list *pl, const char *name, int def);
bool params_bool(param_list *pl, const char *name, bool def);
const char *params_string(param_list *pl, const char *name, const char *def);
vec3 params_point3(param_list *pl, const char *name, vec3 def);
vec3 params_vector3(param_list *pl, const char *name, vec3 def);
/* Accepts rgb, spectrum and blackbody parameters. */
rgb params_rgb(param_list *pl, const char *name, rgb def);
/* A reflectance: params_rgb, with what only rounding or a spectrum's
 * reduction to RGB put outside [0, 1] clamped into it, silently: components
 * within 1e-6 of it, and every component of a sampled spectrum whose values
 * all lie in [0, 1] (pbrt-v4 clamps such a spectrum per wavelength, where it
 * is within bounds; its RGB can step out through the XYZ-to-sRGB matrix:
 * [400 1 700 1] gives G = 1.0012). Anything else is returned as given, for
 * the caller to refuse. */
rgb params_reflectance(param_list *pl, const char *name, rgb def);
/* A light's (or an emitting medium's) radiance, normalised as pbrt-v4
 * normalises illuminant spectra: rgb values as given; blackbody and spectrum
 * values scaled to luminance 1 (pbrt-v4 divides them by their photometric
 * integral), a spectrum keeping its own chromaticity (no division by the RGB
 * of a constant spectrum, which reflectances get): "spectrum I" [360 5 830 5]
 * is as bright as "rgb I" [1 1 1], slightly pink (equal-energy white). */
rgb params_illuminant(param_list *pl, const char *name, rgb def);
/* The parameter `name` as a spectrum_value for `use` (rgb, spectrum and
 * blackbody parameters; the same type/count errors as params_rgb); `def` (an
 * RGB) when absent. Its `rgb` equals what params_reflectance (ALBEDO),
 * params_rgb (UNBOUNDED) or params_illuminant (ILLUMINANT) returns for the
 * same parameter, and it marks the parameter used as they do. Arrays are
 * borrowed from the scene_desc (they live as long as it) or from static
 * tables. */
spectrum_value params_spectrum(param_list *pl, const char *name, spectrum_use use, rgb def);
/* What params_illuminant divided the spectrum by (1 when nothing: rgb values,
 * named illuminants, no such parameter). */
double params_illuminant_luminance(const param_list *pl, const char *name);
/* Arrays: NULL and *n = 0 when absent. For point3/normal/vector3/point2 *n counts
 * tuples, not scalars. */
const double *params_floats(param_list *pl, const char *name, size_t *n);
const double *params_ints(param_list *pl, const char *name, size_t *n);
const double *params_point3s(param_list *pl, const char *name, size_t *n);
const double *params_normals(param_list *pl, const char *name, size_t *n);
const double *params_point2s(param_list *pl, const char *name, size_t *n);
/* A float parameter's value, or a spectrum's at 550 nm (pbrt-v4 takes an
 * index as either); `def` when absent. */
double params_float_or_550(param_list *pl, const char *name, double def);
/* String arrays ("string materials" ["a" "b"]): NULL and *n = 0 when absent. */
char *const *params_strings(param_list *pl, const char *name, size_t *n);
/* "rgb" arrays (3 values each; *n counts triples), as pbrt-v4's GetRGBArray. */
const double *params_rgbs(param_list *pl, const char *name, size_t *n);
/* The first value of string parameter `name`, or `def`; does not mark it
 * used (for readers outside the factory: haze info, the list of input files). */
const char *params_peek_string(const param_list *pl, const char *name, const char *def);
/* True when a parameter of this name is present (does not mark it used). */
bool params_has(const param_list *pl, const char *name);
/* Whether `name` is given as a "spectrum" (not a float, rgb or blackbody). */
bool params_is_spectrum(const param_list *pl, const char *name);
/* The texture a "texture NAME" parameter names (marked used), or NULL when
 * `name` is absent or of another type (left for the typed getters). */
const char *params_texture(param_list *pl, const char *name);
/* The location of a parameter (its directive's location when absent), for
 * factories that reject a value: hz_fail_at(err, params_loc(pl, "fov"), ...). */
file_loc params_loc(const param_list *pl, const char *name);
/* Records an error about parameter `name` (e.g. a value out of range). */
void params_reject(param_list *pl, const char *name, const char *fmt, ...) HZ_PRINTF(3, 4);

/* Reports the first recorded problem, else the first unused parameter:
 * "file:line:col: unused parameter "float fvo" for Camera "perspective"". */
hz_status params_finish(const param_list *pl, const char *what, hz_error *err);
/* The problem a getter recorded (pl->failed) into *err. */
void params_failure(const param_list *pl, hz_error *err);

#endif
