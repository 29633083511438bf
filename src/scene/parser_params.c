/* Typed parameter lists: `"type name" value` or `"type name" [values]`, with
 * pbrt-v4's type names and aliases. Values are checked against the type here,
 * so factories only see well-formed lists; spectrum and blackbody values are
 * converted to rgb (rules in spectrum.h) and kept as given (params_spectrum). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "core/path.h"
#include "scene/mem.h"
#include "scene/named_spectra.h"
#include "scene/parser_params.h"
#include "scene/parser_state.h"
#include "scene/parser_tokens.h"
#include "scene/spectrum.h"

static const struct {
    const char *name;
    param_type type;
} type_names[] = {
    {"integer", PARAM_INTEGER}, {"float", PARAM_FLOAT},     {"bool", PARAM_BOOL},
    {"string", PARAM_STRING},   {"point2", PARAM_POINT2},   {"vector2", PARAM_VECTOR2},
    {"point3", PARAM_POINT3},   {"point", PARAM_POINT3},    {"vector3", PARAM_VECTOR3},
    {"vector", PARAM_VECTOR3},  {"normal", PARAM_NORMAL},   {"normal3", PARAM_NORMAL},
    {"rgb", PARAM_RGB},         {"color", PARAM_RGB},       {"spectrum", PARAM_SPECTRUM},
    {"blackbody", PARAM_BLACKBODY}, {"texture", PARAM_TEXTURE},
};

/* Splits "type name" into its two words. */
static hz_status split_decl(const char *decl, file_loc loc, char *type, char *name, size_t size,
                            hz_error *err)
{
    char words[3][128];
    int n = 0;
    const char *p = decl;
    while (*p) {
        while (*p == ' ' || *p == '\t')
            ++p;
        if (!*p)
            break;
        size_t len = strcspn(p, " \t");
        if (n == 3 || len >= sizeof words[0]) {
            n = 3;
            break;
        }
        memcpy(words[n], p, len);
        words[n][len] = '\0';
        ++n;
        p += len;
    }
    if (n != 2)
        return hz_fail_at(err, loc, "parameter declaration \"%.60s\" must be \"type name\"", decl);
    snprintf(type, size, "%s", words[0]);
    snprintf(name, size, "%s", words[1]);
    return HZ_OK;
}

static hz_status lookup_type(const char *type, file_loc loc, param_type *out, hz_error *err)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; ++i) {
        if (strcmp(type_names[i].name, type) == 0) {
            *out = type_names[i].type;
            return HZ_OK;
        }
    }
    return hz_fail_at(err, loc,
                      "unknown parameter type \"%.60s\"; expected integer, float, bool, string, "
                      "point2, vector2, point3, vector3, normal, rgb, spectrum, blackbody or "
                      "texture",
                      type);
}

static int is_value(const token *t)
{
    return t->kind == TOK_NUMBER || t->kind == TOK_STRING || token_is(t, "true") ||
           token_is(t, "false");
}

/* Collects the value tokens of one parameter (one bare value or a bracket). */
static hz_status read_values(parser *ps, const char *decl, file_loc decl_loc, token **vals,
                             size_t *count, hz_error *err)
{
    token t;
    size_t cap = 0;
    *vals = NULL;
    *count = 0;
    if (parser_next(ps, &t, err) != HZ_OK)
        return HZ_ERROR;
    char got[48];
    if (t.kind != TOK_LBRACKET) {
        if (!is_value(&t)) {
            token_describe(&t, got, sizeof got);
            return hz_fail_at(err, decl_loc, "parameter \"%.60s\" has no value (found %s)", decl,
                              got);
        }
        *vals = scene_malloc(sizeof **vals);
        if (!*vals)
            return parser_oom(ps, t.loc, err);
        (*vals)[0] = t;
        *count = 1;
        return HZ_OK;
    }
    file_loc open = t.loc;
    for (;;) {
        if (parser_next(ps, &t, err) != HZ_OK)
            return HZ_ERROR;
        if (t.kind == TOK_RBRACKET)
            return HZ_OK;
        if (!is_value(&t)) {
            token_describe(&t, got, sizeof got);
            return hz_fail_at(err, open, "'[' is not closed (found %s at line %d, column %d)", got,
                              t.loc.line, t.loc.column);
        }
        token *grown = scene_grow(*vals, &cap, *count, sizeof **vals);
        if (!grown)
            return parser_oom(ps, t.loc, err); /* the caller frees *vals */
        *vals = grown;
        (*vals)[(*count)++] = t;
    }
}

static const char *kind_name(const token *t)
{
    switch (t->kind) {
    case TOK_NUMBER: return "number";
    case TOK_STRING: return "string";
    default: return "bool";
    }
}

/* Fails unless every value is a number. */
static hz_status want_numbers(const param *p, const token *vals, size_t n, hz_error *err)
{
    for (size_t i = 0; i < n; ++i) {
        if (vals[i].kind != TOK_NUMBER) {
            char got[48];
            token_describe(&vals[i], got, sizeof got);
            return hz_fail_at(err, vals[i].loc, "parameter \"%s %s\" expects numbers, got %s %s",
                              param_type_name(p->type), p->name, kind_name(&vals[i]), got);
        }
    }
    return HZ_OK;
}

/* Spectrum and blackbody parameters become three rgb numbers. */
static hz_status set_rgb(parser *ps, param *p, rgb c, hz_error *err)
{
    p->nums = scene_array(3, sizeof *p->nums);
    if (!p->nums)
        return parser_oom(ps, p->loc, err);
    p->count = 3;
    p->nums[0] = c.r;
    p->nums[1] = c.g;
    p->nums[2] = c.b;
    return HZ_OK;
}

/* A sampled spectrum (increasing wavelengths) as the param's RGB, its
 * illuminant RGB and its value at 550 nm (linear between samples, the end
 * values beyond them). Takes `samples` (2 * pairs numbers: the lambdas, then
 * the values), freed with p. */
static hz_status set_sampled(parser *ps, param *p, double *samples, size_t pairs, hz_error *err)
{
    const double *lambda = samples, *value = samples + pairs;
    p->samples = samples;
    p->lambda = lambda;
    p->value = value;
    p->pairs = pairs;
    p->at_550 = value[pairs - 1];
    p->unit_values = true;
    for (size_t i = 0; i < pairs; ++i)
        p->unit_values &= value[i] >= 0.0 && value[i] <= 1.0;
    for (size_t i = 0; i < pairs; ++i)
        if (lambda[i] >= 550.0) {
            double t = i == 0 ? 1.0 : (550.0 - lambda[i - 1]) / (lambda[i] - lambda[i - 1]);
            p->at_550 = i == 0 ? value[0] : value[i - 1] + t * (value[i] - value[i - 1]);
            break;
        }
    p->illuminant = spectrum_sampled_to_illuminant(lambda, value, pairs);
    p->luminance = spectrum_sampled_luminance(lambda, value, pairs);
    return set_rgb(ps, p, spectrum_sampled_to_rgb(lambda, value, pairs), err);
}

/* pbrt-v4's spectrum file (.spd): "wavelength value" pairs, whitespace
 * separated, '#' comments; a name not found among the named spectra is read
 * as one, relative to the scene file. The file joins the scene's inputs. */
static hz_status read_spd(parser *ps, param *p, const char *name, file_loc loc, hz_error *err)
{
    char *full = path_of_scene_file(loc, name);
    if (!full)
        return parser_oom(ps, loc, err);
    char *text;
    size_t len;
    hz_error ferr;
    if (file_read_all(full, FILE_LIMIT_SCENE, &text, &len, &ferr) != HZ_OK) {
        hz_status st = hz_fail_at(err, loc,
                                  "parameter \"spectrum %s\": no named spectrum \"%.60s\" and "
                                  "no spectrum file \"%.200s\" (%s); haze knows pbrt-v4's "
                                  "metal-*-eta/-k, glass-* and stdillum-*",
                                  p->name, name, full, ferr.message);
        free(full);
        return st;
    }
    double *v = NULL;
    size_t n = 0, cap = 0;
    hz_status st = HZ_OK;
    for (char *c = text; st == HZ_OK && *c;) {
        if (*c == '#') {
            while (*c && *c != '\n')
                ++c;
            continue;
        }
        if (*c == ' ' || *c == '\t' || *c == '\n' || *c == '\r') {
            ++c;
            continue;
        }
        char *end;
        double x = strtod(c, &end);
        if (end == c || !isfinite(x)) {
            st = hz_fail_at(err, loc, "spectrum file \"%.200s\": not a number at byte %zu", full,
                            (size_t)(c - text));
            break;
        }
        double *grown = scene_grow(v, &cap, n, sizeof *v);
        if (!grown) {
            st = parser_oom(ps, loc, err);
            break;
        }
        v = grown;
        v[n++] = x;
        c = end;
    }
    size_t pairs = n / 2;
    if (st == HZ_OK && (n % 2 != 0 || pairs == 0))
        st = hz_fail_at(err, loc, "spectrum file \"%.200s\" needs (wavelength, value) pairs, got "
                        "%zu values", full, n);
    double *samples = NULL;
    if (st == HZ_OK) {
        samples = scene_array(pairs, 2 * sizeof *samples);
        if (!samples)
            st = parser_oom(ps, loc, err);
    }
    double *lambda = samples, *value = samples ? samples + pairs : NULL;
    for (size_t i = 0; st == HZ_OK && i < pairs; ++i) {
        lambda[i] = v[2 * i];
        value[i] = v[2 * i + 1];
        if (i > 0 && !(lambda[i] > lambda[i - 1]))
            st = hz_fail_at(err, loc, "spectrum file \"%.200s\": wavelengths must increase",
                            full);
    }
    if (st == HZ_OK)
        st = set_sampled(ps, p, samples, pairs, err); /* p owns samples now */
    else
        free(samples);
    if (st == HZ_OK) {
        const char *file = parser_intern(ps, full);
        if (!file || !scene_desc_add_file(ps->sd, file))
            st = parser_oom(ps, loc, err);
    }
    free(v);
    free(text);
    free(full);
    return st;
}

/* A constant spectrum kept as two equal samples just beyond 360..830 nm, the
 * range wavelengths are drawn from (spectrum_value.h). */
static hz_status keep_constant(parser *ps, param *p, double c, hz_error *err)
{
    p->samples = scene_array(4, sizeof *p->samples);
    if (!p->samples)
        return parser_oom(ps, p->loc, err);
    p->samples[0] = 359.0;
    p->samples[1] = 831.0;
    p->samples[2] = p->samples[3] = c;
    p->lambda = p->samples;
    p->value = p->samples + 2;
    p->pairs = 2;
    return HZ_OK;
}

static hz_status convert_spectrum(parser *ps, param *p, const token *vals, size_t n,
                                  hz_error *err)
{
    if (vals[0].kind == TOK_STRING) {
        /* pbrt-v4's named spectra, reduced to RGB (scene/named_spectra.h). */
        rgb named;
        if (n != 1)
            return hz_fail_at(err, vals[0].loc,
                              "parameter \"spectrum %s\" takes one spectrum name, got %zu values",
                              p->name, n);
        char *name = token_string_dup(&vals[0]);
        if (!name)
            return parser_oom(ps, vals[0].loc, err);
        if (!named_spectrum_rgb(name, &named)) {
            hz_status st = read_spd(ps, p, name, vals[0].loc, err);
            free(name);
            return st;
        }
        const named_spectrum_samples *table = named_spectrum_find(name);
        free(name);
        if (table) { /* every name has one (test_scene_spectrum_value) */
            p->lambda = table->lambda;
            p->value = table->value;
            p->pairs = table->n;
        }
        p->illuminant = named;
        p->at_550 = named.g; /* a glass: its index at 550 nm */
        return set_rgb(ps, p, named, err);
    }
    if (want_numbers(p, vals, n, err) != HZ_OK)
        return HZ_ERROR;
    rgb c;
    if (n == 1) {
        c = rgb_grey(vals[0].num);
        p->at_550 = vals[0].num;
        p->illuminant = vals[0].num > 0.0 ? spectrum_sampled_to_illuminant(NULL, NULL, 1)
                                          : rgb_grey(0.0);
        p->luminance = vals[0].num;
        if (keep_constant(ps, p, vals[0].num, err) != HZ_OK)
            return HZ_ERROR;
    } else {
        if (n % 2 != 0)
            return hz_fail_at(err, p->loc,
                              "parameter \"spectrum %s\" needs (wavelength, value) pairs, got %zu "
                              "values",
                              p->name, n);
        size_t pairs = n / 2;
        double *samples = scene_array(pairs, 2 * sizeof *samples);
        if (!samples)
            return parser_oom(ps, p->loc, err);
        double *lambda = samples, *value = samples + pairs;
        for (size_t i = 0; i < pairs; ++i) {
            lambda[i] = vals[2 * i].num;
            value[i] = vals[2 * i + 1].num;
            if (i > 0 && !(lambda[i] > lambda[i - 1])) {
                free(samples);
                return hz_fail_at(err, vals[2 * i].loc,
                                  "parameter \"spectrum %s\": wavelengths must increase", p->name);
            }
        }
        return set_sampled(ps, p, samples, pairs, err); /* p owns samples now */
    }
    return set_rgb(ps, p, c, err);
}

/* "string" and "texture" values; on error p may own strings (param_free). */
static hz_status convert_strings(parser *ps, param *p, const token *vals, size_t n,
                                 hz_error *err)
{
    p->strs = scene_array(n, sizeof *p->strs);
    if (!p->strs)
        return parser_oom(ps, p->loc, err);
    for (size_t i = 0; i < n; ++i)
        p->strs[i] = NULL;
    p->count = n;
    for (size_t i = 0; i < n; ++i) {
        if (vals[i].kind != TOK_STRING) {
            char got[48];
            token_describe(&vals[i], got, sizeof got);
            return hz_fail_at(err, vals[i].loc, "parameter \"%s %s\" expects strings, got %s",
                              param_type_name(p->type), p->name, got);
        }
        p->strs[i] = token_string_dup(&vals[i]);
        if (!p->strs[i])
            return parser_oom(ps, vals[i].loc, err);
    }
    return HZ_OK;
}

static hz_status convert_bools(parser *ps, param *p, const token *vals, size_t n, hz_error *err)
{
    p->bools = scene_array(n, sizeof *p->bools);
    if (!p->bools)
        return parser_oom(ps, p->loc, err);
    p->count = n;
    for (size_t i = 0; i < n; ++i) {
        /* pbrt-v4 takes true/false bare or quoted. */
        const token *v = &vals[i];
        bool bare = v->kind == TOK_IDENT;
        bool quoted_t = v->kind == TOK_STRING && v->len == 4 && !memcmp(v->text, "true", 4);
        bool quoted_f = v->kind == TOK_STRING && v->len == 5 && !memcmp(v->text, "false", 5);
        if (!bare && !quoted_t && !quoted_f) {
            char got[48];
            token_describe(v, got, sizeof got);
            return hz_fail_at(err, v->loc, "parameter \"bool %s\" expects true or false, got %s",
                              p->name, got);
        }
        p->bools[i] = quoted_t || token_is(v, "true");
    }
    return HZ_OK;
}

static hz_status convert_blackbody(parser *ps, param *p, const token *vals, size_t n,
                                   hz_error *err)
{
    if (want_numbers(p, vals, n, err) != HZ_OK)
        return HZ_ERROR;
    if (n != 1)
        return hz_fail_at(err, p->loc, "parameter \"blackbody %s\" takes 1 value (kelvin), got %zu",
                          p->name, n);
    if (!(vals[0].num > 0.0))
        return hz_fail_at(err, vals[0].loc, "parameter \"blackbody %s\": temperature must be > 0",
                          p->name);
    p->luminance = spectrum_blackbody_luminance(vals[0].num);
    p->kelvin = vals[0].num;
    return set_rgb(ps, p, spectrum_blackbody_to_rgb(vals[0].num), err);
}

/* Numeric values, `tuple` numbers each; "rgb" ones from the current color
 * space to sRGB. On error p may own its numbers (param_free). */
static hz_status convert_numbers(parser *ps, param *p, const token *vals, size_t n, size_t tuple,
                                 hz_error *err)
{
    if (want_numbers(p, vals, n, err) != HZ_OK)
        return HZ_ERROR;
    if (n % tuple != 0)
        return hz_fail_at(err, p->loc, "parameter \"%s %s\" needs a multiple of %zu values, got %zu",
                          param_type_name(p->type), p->name, tuple, n);
    for (size_t i = 0; p->type == PARAM_INTEGER && i < n; ++i)
        /* Range first: converting an out-of-range double to an integer is undefined. */
        if (!(vals[i].num >= -2147483648.0 && vals[i].num <= 2147483647.0) ||
            vals[i].num != (double)(long long)vals[i].num)
            return hz_fail_at(err, vals[i].loc, "parameter \"integer %s\" expects integers, got %.*s",
                              p->name, (int)(vals[i].len < 30 ? vals[i].len : 30), vals[i].text);
    p->nums = scene_array(n, sizeof *p->nums);
    if (!p->nums)
        return parser_oom(ps, p->loc, err);
    p->count = n;
    for (size_t i = 0; i < n; ++i)
        p->nums[i] = vals[i].num;
    if (p->type == PARAM_RGB && ps->gs.color_space != COLOR_SPACE_SRGB) {
        double m[9];
        color_space_convert_matrix(ps->gs.color_space, COLOR_SPACE_SRGB, m);
        for (size_t i = 0; i + 2 < n; i += 3) {
            double r = p->nums[i], g = p->nums[i + 1], b = p->nums[i + 2];
            for (int k = 0; k < 3; ++k)
                p->nums[i + k] = m[3 * k] * r + m[3 * k + 1] * g + m[3 * k + 2] * b;
        }
    }
    return HZ_OK;
}

/* The values as p's type; on error p may own arrays (param_free). */
static hz_status convert(parser *ps, param *p, const token *vals, size_t n, hz_error *err)
{
    if (n == 0)
        return hz_fail_at(err, p->loc, "parameter \"%s %s\" has no values",
                          param_type_name(p->type), p->name);
    switch (p->type) {
    case PARAM_STRING:
    case PARAM_TEXTURE:
        return convert_strings(ps, p, vals, n, err);
    case PARAM_BOOL:
        return convert_bools(ps, p, vals, n, err);
    case PARAM_SPECTRUM:
        return convert_spectrum(ps, p, vals, n, err);
    case PARAM_BLACKBODY:
        return convert_blackbody(ps, p, vals, n, err);
    case PARAM_POINT2:
    case PARAM_VECTOR2:
        return convert_numbers(ps, p, vals, n, 2, err);
    case PARAM_POINT3:
    case PARAM_VECTOR3:
    case PARAM_NORMAL:
        return convert_numbers(ps, p, vals, n, 3, err);
    case PARAM_RGB: /* one triple, or an array of them (rgbgrid) */
        return convert_numbers(ps, p, vals, n, 3, err);
    case PARAM_INTEGER:
    case PARAM_FLOAT:
        break;
    }
    return convert_numbers(ps, p, vals, n, 1, err);
}

/* The parameter of that name already given, or NULL. */
static const param *given_before(const param_list *pl, const char *name)
{
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, name) == 0)
            return &pl->items[i];
    return NULL;
}

/* A parameter given again with the same type as `first`: pbrt-v4 reads the
 * first and lets the others be (pbrt-v4-scenes' villa gives a roughness
 * twice). */
static hz_status add_shadowed(parser *ps, param_list *out, param p, int first_line,
                              hz_error *err)
{
    file_loc at = p.loc;
    if (parser_warn(ps, at, err, "parameter \"%s %s\" given again: the first (line %d) is used, "
                    "as in pbrt-v4", param_type_name(p.type), p.name, first_line) != HZ_OK) {
        param_free(&p);
        return HZ_ERROR;
    }
    if (!params_add_shadowed(out, p))
        return parser_oom(ps, at, err);
    return HZ_OK;
}

static hz_status parse_one(parser *ps, const token *decl_tok, param_list *out, hz_error *err)
{
    char *decl = token_string_dup(decl_tok);
    if (!decl)
        return parser_oom(ps, decl_tok->loc, err);
    char type[128], name[128];
    param p;
    memset(&p, 0, sizeof p);
    p.loc = decl_tok->loc;
    token *vals = NULL;
    size_t n = 0;
    hz_status st = split_decl(decl, p.loc, type, name, sizeof type, err);
    if (st == HZ_OK)
        st = lookup_type(type, p.loc, &p.type, err);
    if (st == HZ_OK)
        st = read_values(ps, decl, p.loc, &vals, &n, err);
    if (st == HZ_OK) {
        p.name = scene_strdup(name);
        if (!p.name)
            st = parser_oom(ps, p.loc, err);
        else
            st = convert(ps, &p, vals, n, err);
        /* Reserved first, params_add can only report a repeated name. */
        if (st == HZ_OK && !params_reserve(out))
            st = parser_oom(ps, p.loc, err);
        const param *first = st == HZ_OK ? given_before(out, p.name) : NULL;
        if (first && first->type == p.type)
            st = add_shadowed(ps, out, p, first->loc.line, err);
        else if (st == HZ_OK)
            st = params_add(out, p, err); /* frees p on failure */
        else
            param_free(&p);
    }
    free(vals);
    free(decl);
    return st;
}

hz_status parser_params(parser *ps, param_list *out, file_loc directive, hz_error *err)
{
    params_init(out, directive);
    for (;;) {
        token t;
        if (parser_peek(ps, &t, err) != HZ_OK)
            return HZ_ERROR;
        if (t.kind != TOK_STRING)
            return HZ_OK;
        parser_next(ps, &t, err);
        if (parse_one(ps, &t, out, err) != HZ_OK)
            return HZ_ERROR;
    }
}
