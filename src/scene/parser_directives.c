/* What each pbrt-v4 directive does to the graphics state and the scene_desc.
 * Semantics follow pbrt-v4's BasicSceneBuilder (src/pbrt/scene.cpp); where
 * pbrt-v4 only warns (unknown CoordSysTransform name, area lights in object
 * instances) haze refuses, because a silently different scene is worse. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/parser_directives.h"
#include "scene/parser_entities.h"
#include "scene/parser_state.h"
#include "scene/parser_tokens.h"

#define SUPPORTED                                                                                \
    "LookAt Translate Rotate Scale Transform ConcatTransform Identity CoordinateSystem "          \
    "CoordSysTransform TransformTimes ActiveTransform AttributeBegin AttributeEnd Attribute "     \
    "Camera Film Sampler PixelFilter Integrator Accelerator WorldBegin MakeNamedMedium "          \
    "MediumInterface "                                                                            \
    "LightSource AreaLightSource Shape Material MakeNamedMaterial NamedMaterial "                 \
    "Texture ReverseOrientation Include Import ObjectBegin ObjectEnd ObjectInstance Option "     \
    "ColorSpace"

typedef hz_status (*directive_fn)(parser *ps, const token *d, hz_error *err);

/* ---- transforms -------------------------------------------------------- */

static void ctm_post(parser *ps, transform t)
{
    for (int i = 0; i < 2; ++i)
        if (ps->gs.active & (1u << i))
            ps->gs.ctm[i] = transform_compose(ps->gs.ctm[i], t);
}

static void ctm_set(parser *ps, transform t)
{
    for (int i = 0; i < 2; ++i)
        if (ps->gs.active & (1u << i))
            ps->gs.ctm[i] = t;
}

static hz_status d_translate(parser *ps, const token *d, hz_error *err)
{
    double v[3];
    if (parser_numbers(ps, d, v, 3, false, err) != HZ_OK)
        return HZ_ERROR;
    ctm_post(ps, transform_translate(v3(v[0], v[1], v[2])));
    return HZ_OK;
}

static hz_status d_scale(parser *ps, const token *d, hz_error *err)
{
    double v[3];
    if (parser_numbers(ps, d, v, 3, false, err) != HZ_OK)
        return HZ_ERROR;
    if (v[0] == 0.0 || v[1] == 0.0 || v[2] == 0.0)
        return hz_fail_at(err, d->loc, "Scale by zero makes the transform singular");
    ctm_post(ps, transform_scale(v3(v[0], v[1], v[2])));
    return HZ_OK;
}

static hz_status d_rotate(parser *ps, const token *d, hz_error *err)
{
    double v[4];
    if (parser_numbers(ps, d, v, 4, false, err) != HZ_OK)
        return HZ_ERROR;
    if (v3_length(v3(v[1], v[2], v[3])) == 0.0)
        return hz_fail_at(err, d->loc, "Rotate axis is zero");
    ctm_post(ps, transform_rotate(v[0], v3(v[1], v[2], v[3])));
    return HZ_OK;
}

static hz_status d_look_at(parser *ps, const token *d, hz_error *err)
{
    double v[9];
    transform t;
    if (parser_numbers(ps, d, v, 9, false, err) != HZ_OK)
        return HZ_ERROR;
    if (!transform_look_at(v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]), v3(v[6], v[7], v[8]), &t))
        return hz_fail_at(err, d->loc,
                          "LookAt is degenerate (eye equals target, or up is parallel to the "
                          "view direction)");
    ctm_post(ps, t);
    return HZ_OK;
}

/* pbrt-v4 reads the 16 numbers row by row and transposes: files are column-major. */
static hz_status read_matrix(parser *ps, const token *d, transform *t, hz_error *err)
{
    double v[16];
    if (parser_numbers(ps, d, v, 16, true, err) != HZ_OK)
        return HZ_ERROR;
    mat4 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            m.m[r][c] = v[c * 4 + r];
    if (!transform_from_matrix(m, t))
        return hz_fail_at(err, d->loc, "%.*s matrix is singular", (int)d->len, d->text);
    return HZ_OK;
}

static hz_status d_transform(parser *ps, const token *d, hz_error *err)
{
    transform t;
    if (read_matrix(ps, d, &t, err) != HZ_OK)
        return HZ_ERROR;
    ctm_set(ps, t);
    return HZ_OK;
}

static hz_status d_concat(parser *ps, const token *d, hz_error *err)
{
    transform t;
    if (read_matrix(ps, d, &t, err) != HZ_OK)
        return HZ_ERROR;
    ctm_post(ps, t);
    return HZ_OK;
}

static hz_status d_identity(parser *ps, const token *d, hz_error *err)
{
    (void)d;
    (void)err;
    ctm_set(ps, transform_identity());
    return HZ_OK;
}

static hz_status d_coordsys(parser *ps, const token *d, hz_error *err)
{
    const char *name;
    if (parser_string_arg(ps, d, &name, err) != HZ_OK)
        return HZ_ERROR;
    return parser_set_coordsys(ps, name, ps->gs.ctm, d->loc, err);
}

static hz_status d_coordsys_transform(parser *ps, const token *d, hz_error *err)
{
    const char *name;
    if (parser_string_arg(ps, d, &name, err) != HZ_OK)
        return HZ_ERROR;
    named_coordsys *c = parser_find_coordsys(ps, name);
    if (!c)
        return hz_fail_at(err, d->loc, "CoordSysTransform: no coordinate system named \"%s\"", name);
    ps->gs.ctm[0] = c->ctm[0];
    ps->gs.ctm[1] = c->ctm[1];
    return HZ_OK;
}

static hz_status d_transform_times(parser *ps, const token *d, hz_error *err)
{
    double v[2];
    if (parser_need_options(ps, d, "TransformTimes", NULL, err) != HZ_OK || parser_numbers(ps, d, v, 2, false, err) != HZ_OK)
        return HZ_ERROR;
    if (!isfinite(v[0]) || !isfinite(v[1]) || v[1] < v[0])
        return hz_fail_at(err, d->loc,
                          "TransformTimes %g %g: the times must be finite and the end time not "
                          "before the start time",
                          v[0], v[1]);
    ps->sd->transform_start_time = v[0];
    ps->sd->transform_end_time = v[1];
    return HZ_OK;
}

static hz_status d_active_transform(parser *ps, const token *d, hz_error *err)
{
    token t;
    if (parser_next(ps, &t, err) != HZ_OK)
        return HZ_ERROR;
    if (token_is(&t, "All"))
        ps->gs.active = 3;
    else if (token_is(&t, "StartTime"))
        ps->gs.active = 1;
    else if (token_is(&t, "EndTime"))
        ps->gs.active = 2;
    else {
        char got[48];
        token_describe(&t, got, sizeof got);
        return hz_fail_at(err, t.loc, "ActiveTransform expects All, StartTime or EndTime, found %s",
                          got);
    }
    (void)d;
    return HZ_OK;
}

/* ---- blocks ------------------------------------------------------------ */

static hz_status d_attribute_begin(parser *ps, const token *d, hz_error *err)
{
    if (parser_need_world(ps, d, "AttributeBegin", err) != HZ_OK)
        return HZ_ERROR;
    return parser_push_state(ps, 'a', d->loc, err);
}

static hz_status d_attribute_end(parser *ps, const token *d, hz_error *err)
{
    if (parser_need_world(ps, d, "AttributeEnd", err) != HZ_OK)
        return HZ_ERROR;
    if (ps->depth == 0)
        return hz_fail_at(err, d->loc, "AttributeEnd without a matching AttributeBegin");
    const gstate *top = &ps->stack[ps->depth - 1];
    if (top->kind != 'a')
        return hz_fail_at(err, d->loc, "AttributeEnd inside the ObjectBegin at %s:%d:%d",
                          top->pushed_at.file, top->pushed_at.line, top->pushed_at.column);
    parser_pop_state(ps);
    return HZ_OK;
}

/* pbrt-v3's TransformBegin/End: pbrt-v4 reads them as AttributeBegin/End
 * (saving the whole graphics state, not only the transform) and warns once. */
static hz_status d_transform_begin(parser *ps, const token *d, hz_error *err)
{
    if (parser_need_world(ps, d, "TransformBegin", err) != HZ_OK)
        return HZ_ERROR;
    if (!ps->warned_transform_begin) {
        ps->warned_transform_begin = true;
        if (parser_warn(ps, d->loc, err,
                        "TransformBegin/End are pbrt-v3's: read as AttributeBegin/End, as "
                        "pbrt-v4 does") != HZ_OK)
            return HZ_ERROR;
    }
    return parser_push_state(ps, 'a', d->loc, err);
}

static hz_status d_world_begin(parser *ps, const token *d, hz_error *err)
{
    if (parser_need_options(ps, d, "WorldBegin", NULL, err) != HZ_OK)
        return HZ_ERROR;
    ps->in_world = true;
    ps->gs.ctm[0] = ps->gs.ctm[1] = transform_identity();
    ps->gs.active = 3;
    return parser_set_coordsys(ps, "world", ps->gs.ctm, d->loc, err);
}

static hz_status d_world_end(parser *ps, const token *d, hz_error *err)
{
    (void)ps;
    return hz_fail_at(err, d->loc, "WorldEnd does not exist in pbrt-v4 scenes; remove it");
}

static hz_status d_include(parser *ps, const token *d, hz_error *err)
{
    const char *path;
    if (parser_string_arg(ps, d, &path, err) != HZ_OK)
        return HZ_ERROR;
    return parser_include(ps, d, path, err);
}

hz_status parser_finish(parser *ps, file_loc end, hz_error *err)
{
    if (ps->depth > 0) {
        const gstate *top = &ps->stack[ps->depth - 1];
        return hz_fail_at(err, top->pushed_at, "%s is never closed",
                          top->kind == 'a' ? "AttributeBegin" : "ObjectBegin");
    }
    if (!ps->in_world)
        return hz_fail_at(err, end, "end of input before WorldBegin");
    return HZ_OK;
}

static const struct {
    const char *name;
    directive_fn fn;
} table[] = {
    {"LookAt", d_look_at},
    {"Translate", d_translate},
    {"Rotate", d_rotate},
    {"Scale", d_scale},
    {"Transform", d_transform},
    {"ConcatTransform", d_concat},
    {"Identity", d_identity},
    {"CoordinateSystem", d_coordsys},
    {"CoordSysTransform", d_coordsys_transform},
    {"TransformTimes", d_transform_times},
    {"ActiveTransform", d_active_transform},
    {"AttributeBegin", d_attribute_begin},
    {"AttributeEnd", d_attribute_end},
    {"TransformBegin", d_transform_begin},
    {"TransformEnd", d_attribute_end},
    {"WorldBegin", d_world_begin},
    {"WorldEnd", d_world_end},
    {"Include", d_include},
    {"Import", d_include},
};

hz_status parser_directive(parser *ps, const token *tok, hz_error *err)
{
    for (size_t i = 0; i < sizeof table / sizeof table[0]; ++i)
        if (token_is(tok, table[i].name))
            return table[i].fn(ps, tok, err);
    bool handled = false;
    hz_status st = parser_entity_directive(ps, tok, &handled, err);
    if (handled)
        return st;
    char got[48];
    token_describe(tok, got, sizeof got);
    return hz_fail_at(err, tok->loc, "unknown directive %s; supported: " SUPPORTED, got);
}
