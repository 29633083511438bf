#include "scene/params.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/mem.h"
#include "scene/spectrum.h"

const char *param_type_name(param_type t)
{
    switch (t) {
    case PARAM_INTEGER: return "integer";
    case PARAM_FLOAT: return "float";
    case PARAM_BOOL: return "bool";
    case PARAM_STRING: return "string";
    case PARAM_POINT2: return "point2";
    case PARAM_VECTOR2: return "vector2";
    case PARAM_POINT3: return "point3";
    case PARAM_VECTOR3: return "vector3";
    case PARAM_NORMAL: return "normal";
    case PARAM_RGB: return "rgb";
    case PARAM_SPECTRUM: return "spectrum";
    case PARAM_BLACKBODY: return "blackbody";
    case PARAM_TEXTURE: return "texture";
    }
    return "?";
}

void params_init(param_list *pl, file_loc directive)
{
    memset(pl, 0, sizeof *pl);
    pl->loc = directive;
}

void param_free(param *p)
{
    if (p->strs)
        for (size_t i = 0; i < p->count; ++i)
            free(p->strs[i]);
    free(p->strs);
    free(p->nums);
    free(p->bools);
    free(p->name);
    free(p->samples);
    p->samples = NULL;
    p->lambda = p->value = NULL;
    p->strs = NULL;
    p->nums = NULL;
    p->bools = NULL;
    p->name = NULL;
}

void params_free(param_list *pl)
{
    for (size_t i = 0; i < pl->count; ++i)
        param_free(&pl->items[i]);
    free(pl->items);
    pl->items = NULL;
    pl->count = pl->capacity = 0;
    free(pl->error);
    pl->error = NULL;
}

/* A deep copy of `s` into *d; false when out of memory (*d then owns
 * nothing). */
static bool param_copy(param *d, const param *s)
{
    *d = *s;
    d->nums = NULL;
    d->strs = NULL;
    d->bools = NULL;
    d->samples = NULL;
    d->name = scene_strdup(s->name);
    bool ok = d->name != NULL;
    if (ok && s->samples) {
        d->samples = scene_array(2 * s->pairs, sizeof *d->samples);
        ok = d->samples != NULL;
        if (ok) {
            memcpy(d->samples, s->samples, 2 * s->pairs * sizeof *d->samples);
            d->lambda = d->samples;
            d->value = d->samples + s->pairs;
        }
    }
    if (ok && s->nums) {
        d->nums = scene_array(s->count, sizeof *d->nums);
        ok = d->nums != NULL;
        if (ok)
            memcpy(d->nums, s->nums, s->count * sizeof *d->nums);
    }
    if (ok && s->bools) {
        d->bools = scene_array(s->count, sizeof *d->bools);
        ok = d->bools != NULL;
        if (ok)
            memcpy(d->bools, s->bools, s->count * sizeof *d->bools);
    }
    if (ok && s->strs) {
        d->strs = scene_array(s->count, sizeof *d->strs);
        ok = d->strs != NULL;
        for (size_t i = 0; ok && i < s->count; ++i)
            d->strs[i] = NULL; /* param_free may see them before they are set */
        for (size_t i = 0; ok && i < s->count; ++i) {
            d->strs[i] = scene_strdup(s->strs[i]);
            ok = d->strs[i] != NULL;
        }
    }
    if (!ok)
        param_free(d);
    return ok;
}

bool params_copy(param_list *dst, const param_list *src)
{
    *dst = *src;
    dst->items = NULL;
    dst->count = dst->capacity = 0;
    dst->error = NULL;
    if (src->error) {
        dst->error = malloc(sizeof *dst->error);
        if (!dst->error)
            return false;
        *dst->error = *src->error;
    }
    if (!src->count)
        return true;
    dst->items = scene_array(src->count, sizeof *dst->items);
    if (!dst->items)
        return false;
    dst->capacity = src->count;
    for (size_t i = 0; i < src->count; ++i) {
        if (!param_copy(&dst->items[i], &src->items[i])) {
            params_free(dst);
            return false;
        }
        dst->count = i + 1;
    }
    return true;
}

static param *find(const param_list *pl, const char *name)
{
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, name) == 0)
            return &pl->items[i];
    return NULL;
}

bool params_reserve(param_list *pl)
{
    param *grown = scene_grow(pl->items, &pl->capacity, pl->count, sizeof *pl->items);
    if (grown)
        pl->items = grown;
    return grown != NULL;
}

bool params_add_shadowed(param_list *pl, param p)
{
    const param *old = find(pl, p.name);
    if (!old || old->type != p.type || !params_reserve(pl)) {
        param_free(&p);
        return false;
    }
    p.optional = true;
    pl->items[pl->count++] = p;
    return true;
}

hz_status params_add(param_list *pl, param p, hz_error *err)
{
    const param *old = find(pl, p.name);
    hz_status st = HZ_OK;
    if (old)
        st = hz_fail_at(err, p.loc, "parameter \"%s\" given twice (first at line %d)", p.name,
                        old->loc.line);
    else if (!params_reserve(pl))
        st = hz_fail_at(err, p.loc, "out of memory");
    if (st != HZ_OK) {
        param_free(&p);
        return st;
    }
    pl->items[pl->count++] = p;
    return HZ_OK;
}

hz_status params_add_defaults(param_list *pl, const param_list *defaults, hz_error *err)
{
    for (size_t i = 0; i < defaults->count; ++i) {
        if (find(pl, defaults->items[i].name))
            continue;
        param p;
        if (!params_reserve(pl) || !param_copy(&p, &defaults->items[i]))
            return hz_fail_at(err, pl->loc, "out of memory");
        p.used = false;
        p.optional = true;
        pl->items[pl->count++] = p;
    }
    return HZ_OK;
}

void params_remove(param_list *pl, const char *name)
{
    param *p = find(pl, name);
    if (!p)
        return;
    size_t i = (size_t)(p - pl->items);
    param_free(p);
    memmove(&pl->items[i], &pl->items[i + 1], (pl->count - i - 1) * sizeof *pl->items);
    --pl->count;
}

bool params_rename(param_list *pl, const char *from, const char *to)
{
    param *p = find(pl, from);
    if (!p || find(pl, to))
        return true;
    char *name = malloc(strlen(to) + 1);
    if (!name)
        return false;
    strcpy(name, to);
    free(p->name);
    p->name = name;
    return true;
}

/* The list's first problem (later ones are not kept). */
static void set_error(param_list *pl, file_loc loc, const char *msg)
{
    pl->failed = true;
    if (!pl->error)
        pl->error = malloc(sizeof *pl->error);
    if (pl->error)
        hz_fail_at(pl->error, loc, "%s", msg);
}

void params_failure(const param_list *pl, hz_error *err)
{
    if (pl->error)
        *err = *pl->error;
    else
        hz_fail_at(err, pl->loc, "out of memory");
}

static void record(param_list *pl, file_loc loc, const char *fmt, ...) HZ_PRINTF(3, 4);
static void record(param_list *pl, file_loc loc, const char *fmt, ...)
{
    if (pl->failed)
        return; /* the first problem is the one reported */
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    set_error(pl, loc, msg);
}

/* The parameter `name` if it has one of the accepted types; otherwise NULL,
 * recording a type error when the name exists with another type. */
static param *lookup(param_list *pl, const char *name, const param_type *types, size_t ntypes)
{
    param *p = find(pl, name);
    if (!p)
        return NULL;
    p->used = true;
    for (size_t i = 0; i < ntypes; ++i)
        if (p->type == types[i])
            return p;
    record(pl, p->loc, "parameter \"%s\" must be %s, not %s", name, param_type_name(types[0]),
           param_type_name(p->type));
    return NULL;
}

static param *lookup_one(param_list *pl, const char *name, param_type type, size_t want)
{
    param *p = lookup(pl, name, &type, 1);
    if (p && p->count != want) {
        record(pl, p->loc, "parameter \"%s %s\" takes %zu value%s, got %zu", param_type_name(type),
               name, want, want == 1 ? "" : "s", p->count);
        return NULL;
    }
    return p;
}

double params_float(param_list *pl, const char *name, double def)
{
    param *p = lookup_one(pl, name, PARAM_FLOAT, 1);
    return p ? p->nums[0] : def;
}

int params_int(param_list *pl, const char *name, int def)
{
    param *p = lookup_one(pl, name, PARAM_INTEGER, 1);
    if (!p)
        return def;
    if (p->nums[0] < INT_MIN || p->nums[0] > INT_MAX) {
        record(pl, p->loc, "parameter \"integer %s\" is out of range", name);
        return def;
    }
    return (int)p->nums[0];
}

bool params_bool(param_list *pl, const char *name, bool def)
{
    param *p = lookup_one(pl, name, PARAM_BOOL, 1);
    return p ? p->bools[0] : def;
}

const char *params_string(param_list *pl, const char *name, const char *def)
{
    param *p = lookup_one(pl, name, PARAM_STRING, 1);
    return p ? p->strs[0] : def;
}

static vec3 get3(param_list *pl, const char *name, param_type type, vec3 def)
{
    param *p = lookup_one(pl, name, type, 3);
    return p ? v3(p->nums[0], p->nums[1], p->nums[2]) : def;
}

vec3 params_point3(param_list *pl, const char *name, vec3 def)
{
    return get3(pl, name, PARAM_POINT3, def);
}

vec3 params_vector3(param_list *pl, const char *name, vec3 def)
{
    return get3(pl, name, PARAM_VECTOR3, def);
}

rgb params_rgb(param_list *pl, const char *name, rgb def)
{
    static const param_type types[] = {PARAM_RGB, PARAM_SPECTRUM, PARAM_BLACKBODY};
    param *p = lookup(pl, name, types, 3);
    if (!p)
        return def;
    if (p->count != 3) {
        record(pl, p->loc, "parameter \"%s %s\" takes 3 values, got %zu", param_type_name(p->type),
               name, p->count);
        return def;
    }
    return rgb_make(p->nums[0], p->nums[1], p->nums[2]);
}

/* Rounding (a ColorSpace's matrix, a spectrum's integrals) is far below
 * this; a value meant to be outside [0, 1] is far above it. */
#define REFLECTANCE_ROUNDING 1e-6

static double clamp_near_unit(double v, bool clamp_all)
{
    if (clamp_all || (v < 0.0 && v >= -REFLECTANCE_ROUNDING))
        v = fmax(v, 0.0);
    if (clamp_all || (v > 1.0 && v <= 1.0 + REFLECTANCE_ROUNDING))
        v = fmin(v, 1.0);
    return v;
}

rgb params_reflectance(param_list *pl, const char *name, rgb def)
{
    rgb c = params_rgb(pl, name, def);
    bool unit = false;
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, name) == 0) { /* the first is the one read */
            unit = pl->items[i].type == PARAM_SPECTRUM && pl->items[i].unit_values;
            break;
        }
    return rgb_make(clamp_near_unit(c.r, unit), clamp_near_unit(c.g, unit),
                    clamp_near_unit(c.b, unit));
}

rgb params_illuminant(param_list *pl, const char *name, rgb def)
{
    rgb c = params_rgb(pl, name, def);
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, name) == 0 && pl->items[i].type == PARAM_SPECTRUM)
            return pl->items[i].illuminant;
    return c;
}

/* The first parameter called `name` if params_rgb read it as a spectrum
 * or a blackbody (right type, three numbers), else NULL. */
static const param *native_spectrum(const param_list *pl, const char *name)
{
    const param *p = find(pl, name);
    if (!p || p->count != 3)
        return NULL;
    return p->type == PARAM_BLACKBODY || (p->type == PARAM_SPECTRUM && p->pairs > 0) ? p : NULL;
}

spectrum_value params_spectrum(param_list *pl, const char *name, spectrum_use use, rgb def)
{
    rgb c = use == SPECTRUM_USE_ALBEDO      ? params_reflectance(pl, name, def)
            : use == SPECTRUM_USE_UNBOUNDED ? params_rgb(pl, name, def)
                                            : params_illuminant(pl, name, def);
    spectrum_value s = spectrum_value_rgb(c, use);
    const param *p = native_spectrum(pl, name);
    if (!p)
        return s;
    if (p->type == PARAM_BLACKBODY) {
        s.kind = SPECTRUM_VALUE_BLACKBODY;
        s.kelvin = p->kelvin;
    } else {
        s.kind = SPECTRUM_VALUE_SAMPLED;
        s.lambda = p->lambda;
        s.value = p->value;
        s.n = p->pairs;
    }
    if (use != SPECTRUM_USE_ILLUMINANT)
        return s;
    /* What params_illuminant divides out (p->luminance): the same integral
     * of the same samples for sampled spectra, which also covers named
     * illuminants (their RGB is at luminance 1 already, and so are their
     * tables, to within the CIE tables' differences) and constants (whose
     * p->luminance is the value itself). */
    double luminance = p->type == PARAM_BLACKBODY
                           ? p->luminance
                           : spectrum_sampled_luminance(s.lambda, s.value, s.n);
    if (luminance > 0.0 && isfinite(1.0 / luminance))
        s.scale = 1.0 / luminance;
    return s;
}

double params_illuminant_luminance(const param_list *pl, const char *name)
{
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, name) == 0)
            return pl->items[i].luminance > 0.0 ? pl->items[i].luminance : 1.0;
    return 1.0;
}

static const double *get_array(param_list *pl, const char *name, param_type type, size_t tuple,
                               size_t *n)
{
    *n = 0;
    param *p = lookup(pl, name, &type, 1);
    if (!p)
        return NULL;
    if (p->count % tuple != 0) { /* the parser checks this; kept for hand-built lists */
        record(pl, p->loc, "parameter \"%s %s\" needs a multiple of %zu values, got %zu",
               param_type_name(type), name, tuple, p->count);
        return NULL;
    }
    *n = p->count / tuple;
    return p->nums;
}

const double *params_floats(param_list *pl, const char *name, size_t *n)
{
    return get_array(pl, name, PARAM_FLOAT, 1, n);
}

const double *params_ints(param_list *pl, const char *name, size_t *n)
{
    return get_array(pl, name, PARAM_INTEGER, 1, n);
}

double params_float_or_550(param_list *pl, const char *name, double def)
{
    const param_type types[2] = {PARAM_FLOAT, PARAM_SPECTRUM};
    param *p = lookup(pl, name, types, 2);
    if (!p)
        return def;
    if (p->type == PARAM_SPECTRUM)
        return p->at_550;
    if (p->count != 1) {
        record(pl, p->loc, "parameter \"%s\" takes 1 value, got %zu", name, p->count);
        return def;
    }
    return p->nums[0];
}

char *const *params_strings(param_list *pl, const char *name, size_t *n)
{
    const param_type t = PARAM_STRING;
    param *p = lookup(pl, name, &t, 1);
    *n = p ? p->count : 0;
    return p ? p->strs : NULL;
}

const double *params_rgbs(param_list *pl, const char *name, size_t *n)
{
    return get_array(pl, name, PARAM_RGB, 3, n);
}

const double *params_point3s(param_list *pl, const char *name, size_t *n)
{
    return get_array(pl, name, PARAM_POINT3, 3, n);
}

const double *params_normals(param_list *pl, const char *name, size_t *n)
{
    return get_array(pl, name, PARAM_NORMAL, 3, n);
}

const double *params_point2s(param_list *pl, const char *name, size_t *n)
{
    return get_array(pl, name, PARAM_POINT2, 2, n);
}

const char *params_peek_string(const param_list *pl, const char *name, const char *def)
{
    const param *p = find(pl, name);
    return p && p->type == PARAM_STRING && p->count > 0 ? p->strs[0] : def;
}

const char *params_texture(param_list *pl, const char *name)
{
    param *p = find(pl, name);
    if (!p || p->type != PARAM_TEXTURE || p->count != 1)
        return NULL;
    p->used = true;
    return p->strs[0];
}

bool params_has(const param_list *pl, const char *name)
{
    return find(pl, name) != NULL;
}

bool params_is_spectrum(const param_list *pl, const char *name)
{
    const param *p = find(pl, name);
    return p && p->type == PARAM_SPECTRUM;
}

file_loc params_loc(const param_list *pl, const char *name)
{
    const param *p = find(pl, name);
    return p ? p->loc : pl->loc;
}

void params_reject(param_list *pl, const char *name, const char *fmt, ...)
{
    param *p = find(pl, name);
    if (p)
        p->used = true;
    if (pl->failed)
        return;
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    set_error(pl, p ? p->loc : pl->loc, msg);
}

hz_status params_finish(const param_list *pl, const char *what, hz_error *err)
{
    if (pl->failed) {
        if (err)
            params_failure(pl, err);
        return HZ_ERROR;
    }
    for (size_t i = 0; i < pl->count; ++i) {
        const param *p = &pl->items[i];
        if (!p->used && !p->optional)
            return hz_fail_at(err, p->loc, "unused parameter \"%s %s\" for %s",
                              param_type_name(p->type), p->name, what);
    }
    return HZ_OK;
}
