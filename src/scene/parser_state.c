/* The parser's state: diagnostics, the graphics state stack, named
 * coordinate systems (parser_state.h). */
#include "scene/parser_state.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "scene/mem.h"

hz_status parser_oom(parser *ps, file_loc loc, hz_error *err)
{
    ps->out_of_memory = true;
    return hz_fail_at(err, loc, "out of memory");
}

const char *parser_intern(parser *ps, const char *s)
{
    scene_desc *sd = ps->sd;
    /* Strings are few per entity; reuse the most recent ones (types, media
     * names repeat in runs) without a hash table. */
    size_t look = sd->string_count < 8 ? sd->string_count : 8;
    for (size_t i = 0; i < look; ++i) {
        char *c = sd->strings[sd->string_count - 1 - i];
        if (strcmp(c, s) == 0)
            return c;
    }
    return scene_desc_own(sd, s);
}

hz_status parser_warn(parser *ps, file_loc at, hz_error *err, const char *fmt, ...)
{
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    hz_format_warning(line, sizeof line, at, fmt, ap);
    va_end(ap);
    scene_desc *sd = ps->sd;
    const char *kept = parser_intern(ps, line);
    const char **grown = kept ? realloc(sd->warnings, (sd->warning_count + 1) * sizeof *grown)
                              : NULL;
    if (!grown)
        return parser_oom(ps, at, err);
    sd->warnings = grown;
    sd->warnings[sd->warning_count++] = kept;
    return HZ_OK;
}

/* ---- graphics state ---------------------------------------------------- */

void gstate_free(gstate *g)
{
    if (g->has_area_light)
        params_free(&g->area_light.params);
    g->has_area_light = false;
    for (int i = 0; i < ATTR_COUNT; ++i)
        params_free(&g->attrs[i]);
}

/* A deep copy; false when out of memory (nothing then left to free). */
static bool gstate_copy(gstate *c, const gstate *g)
{
    *c = *g;
    /* Empty lists first: a failure midway then leaves only copies to free. */
    c->has_area_light = false;
    for (int i = 0; i < ATTR_COUNT; ++i)
        params_init(&c->attrs[i], g->attrs[i].loc);
    if (g->has_area_light) {
        if (!params_copy(&c->area_light.params, &g->area_light.params))
            return false;
        c->has_area_light = true;
    }
    for (int i = 0; i < ATTR_COUNT; ++i) {
        if (!params_copy(&c->attrs[i], &g->attrs[i])) {
            gstate_free(c);
            return false;
        }
    }
    return true;
}

void parser_state_free(parser *ps)
{
    gstate_free(&ps->gs);
    for (size_t i = 0; i < ps->depth; ++i)
        gstate_free(&ps->stack[i]);
    free(ps->stack);
    free(ps->coords);
    for (size_t i = 0; i < ps->file_depth; ++i)
        free(ps->files[i].canon);
    free(ps->files);
    for (size_t i = 0; i < ps->text_count; ++i)
        free(ps->texts[i]);
    free(ps->texts);
    memset(ps, 0, sizeof *ps);
}

hz_status parser_push_state(parser *ps, char kind, file_loc at, hz_error *err)
{
    gstate *grown = scene_grow(ps->stack, &ps->stack_cap, ps->depth, sizeof *ps->stack);
    if (!grown)
        return parser_oom(ps, at, err);
    ps->stack = grown;
    gstate c;
    if (!gstate_copy(&c, &ps->gs))
        return parser_oom(ps, at, err);
    c.kind = kind;
    c.pushed_at = at;
    ps->stack[ps->depth++] = c;
    return HZ_OK;
}

void parser_pop_state(parser *ps)
{
    gstate_free(&ps->gs);
    ps->gs = ps->stack[--ps->depth];
}

hz_status parser_need_world(parser *ps, const token *d, const char *name, hz_error *err)
{
    if (!ps->in_world)
        return hz_fail_at(err, d->loc, "%s is only allowed after WorldBegin", name);
    return HZ_OK;
}

hz_status parser_need_options(parser *ps, const token *d, const char *name, file_loc *seen,
                              hz_error *err)
{
    if (ps->in_world)
        return hz_fail_at(err, d->loc, "%s must come before WorldBegin", name);
    if (seen) {
        /* pbrt-v4 takes the last (sanmiguel-realistic-courtyard gives two
         * cameras); the caller replaces the first. */
        if (seen->line > 0 &&
            parser_warn(ps, d->loc, err, "%s given again: this one replaces the one at %s:%d:%d, "
                        "as in pbrt-v4", name, seen->file, seen->line, seen->column) != HZ_OK)
            return HZ_ERROR;
        *seen = d->loc;
    }
    return HZ_OK;
}

/* ---- named coordinate systems ----------------------------------------- */

named_coordsys *parser_find_coordsys(parser *ps, const char *name)
{
    for (size_t i = 0; i < ps->coord_count; ++i)
        if (strcmp(ps->coords[i].name, name) == 0)
            return &ps->coords[i];
    return NULL;
}

hz_status parser_set_coordsys(parser *ps, const char *name, const transform ctm[2], file_loc loc,
                              hz_error *err)
{
    named_coordsys *c = parser_find_coordsys(ps, name);
    if (!c) {
        const char *owned = parser_intern(ps, name);
        if (!owned)
            return parser_oom(ps, loc, err);
        named_coordsys *grown =
            scene_grow(ps->coords, &ps->coord_cap, ps->coord_count, sizeof *ps->coords);
        if (!grown)
            return parser_oom(ps, loc, err);
        ps->coords = grown;
        c = &ps->coords[ps->coord_count++];
        c->name = owned;
    }
    c->ctm[0] = ctm[0];
    c->ctm[1] = ctm[1];
    return HZ_OK;
}
