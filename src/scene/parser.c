/* The scene parser's driver: the public entry points (scene_desc.h), the
 * loop over directives and going on after an error. The token stream lives
 * in parser_tokens.c, what directives mean in parser_directives.c and
 * parser_entities.c. */
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "scene/parser_directives.h"
#include "scene/parser_entities.h"
#include "scene/parser_state.h"
#include "scene/parser_tokens.h"

/* After an error: consumes the rest of the failed directive, up to the next
 * word that starts with a capital letter (a directive; bare true/false are
 * values) or the end. */
static hz_status skip_to_directive(parser *ps, hz_error *err)
{
    for (;;) {
        token t;
        if (parser_peek(ps, &t, err) != HZ_OK)
            return HZ_ERROR;
        if (t.kind == TOK_EOF || (t.kind == TOK_IDENT && t.len > 0 && t.text[0] >= 'A' &&
                                  t.text[0] <= 'Z'))
            return HZ_OK;
        ps->has_peek = false;
    }
}

/* The parser at the start of `text`, with pbrt-v4's initial graphics state;
 * false when out of memory (ps and out can still be freed). */
static bool parser_start(parser *ps, const char *text, size_t len, const char *name,
                         scene_desc *out)
{
    memset(ps, 0, sizeof *ps);
    ps->sd = out;
    ps->gs.ctm[0] = ps->gs.ctm[1] = transform_identity();
    ps->gs.active = 3;
    ps->gs.material = -1;
    ps->current_object = -1;
    if (!scene_desc_init(out, name))
        return false;
    const char *file = out->files[0];
    for (int i = 0; i < ATTR_COUNT; ++i)
        params_init(&ps->gs.attrs[i], (file_loc){file, 1, 1, NULL});
    ps->gs.inside = ps->gs.outside = parser_intern(ps, "");
    if (!ps->gs.inside)
        return false;
    return parser_push_root(ps, text, len, file, name);
}

/* Every error of the file in one run: after a directive's error the stream
 * goes on at the next directive (up to HZ_ERRORS_MAX kept); a lexer error or
 * running out of memory ends it. *end is set where the input ended. */
static void parse_directives(parser *ps, hz_errors *errs, file_loc *end, hz_error *err)
{
    for (;;) {
        token t;
        if (parser_next(ps, &t, err) != HZ_OK) {
            hz_errors_add(errs, err);
            return;
        }
        if (t.kind == TOK_EOF) {
            *end = t.loc;
            return;
        }
        ps->defining.name = NULL;
        if (t.kind == TOK_IDENT && parser_directive(ps, &t, err) == HZ_OK)
            continue;
        if (ps->defining.name && !ps->out_of_memory)
            parser_define_stand_in(ps);
        if (t.kind != TOK_IDENT) {
            char got[48];
            token_describe(&t, got, sizeof got);
            hz_fail_at(err, t.loc, "expected a directive, found %s", got);
        }
        hz_errors_add(errs, err);
        if (ps->lex_failed || ps->out_of_memory)
            return;
        if (skip_to_directive(ps, err) != HZ_OK) {
            hz_errors_add(errs, err); /* the lexer's, met while skipping */
            return;
        }
    }
}

/* Parses into `out`, collecting every error with a place in `errs`. HZ_ERROR
 * (err filled, out freed) only when the parse could not begin or memory ran
 * out: then what parsed is not worth building. */
static hz_status parse_root(const char *text, size_t len, const char *name, scene_desc *out,
                            hz_errors *errs, hz_error *err)
{
    parser ps;
    if (!parser_start(&ps, text, len, name, out)) {
        /* The caller's name: the scene's own copy of it may be what failed. */
        hz_status st = parser_oom(&ps, (file_loc){name, 1, 1, NULL}, err);
        parser_state_free(&ps);
        scene_desc_free(out);
        return st;
    }
    file_loc end = {out->files[0], 1, 1, NULL};
    parse_directives(&ps, errs, &end, err);
    if (!ps.lex_failed && !ps.out_of_memory && parser_finish(&ps, end, err) != HZ_OK)
        hz_errors_add(errs, err);
    if (!ps.lex_failed && !ps.out_of_memory)
        parser_report_pending_materials(&ps, errs);
    bool oom = ps.out_of_memory;
    parser_state_free(&ps);
    if (!oom)
        return HZ_OK;
    if (errs->count == 0 && errs->dropped > 0)
        /* Not even the list of errors could be allocated: *err still holds
         * the last error (out of memory ends the parse), better than "... and
         * 1 more error". */
        hz_errors_finish(errs, NULL, 0, NULL);
    else
        hz_errors_finish(errs, out->files, out->file_count, err);
    scene_desc_free(out);
    return HZ_ERROR;
}

/* After parse_root: the errors reported in `err`, and `out` emptied, when
 * there were any. */
static hz_status report_alone(scene_desc *out, hz_errors *errs, hz_error *err)
{
    if (hz_errors_finish(errs, out->files, out->file_count, err) == HZ_OK)
        return HZ_OK;
    scene_desc_free(out);
    return HZ_ERROR;
}

hz_status scene_parse_string(const char *text, const char *name, scene_desc *out, hz_error *err)
{
    hz_errors errs = {0};
    if (parse_root(text, strlen(text), name ? name : "<string>", out, &errs, err) != HZ_OK)
        return HZ_ERROR;
    return report_alone(out, &errs, err);
}

hz_status scene_parse_string_all(const char *text, const char *name, scene_desc *out,
                                 hz_errors *errs, hz_error *err)
{
    return parse_root(text, strlen(text), name ? name : "<string>", out, errs, err);
}

hz_status scene_parse_file_all(const char *path, scene_desc *out, hz_errors *errs, hz_error *err)
{
    char *text;
    size_t len;
    hz_error ferr;
    memset(out, 0, sizeof *out);
    if (file_read_all(path, FILE_LIMIT_SCENE, &text, &len, &ferr) != HZ_OK)
        return hz_fail(err, "%s: cannot read scene: %s", path, ferr.message);
    hz_status st = parse_root(text, len, path, out, errs, err);
    free(text);
    return st;
}

hz_status scene_parse_file(const char *path, scene_desc *out, hz_error *err)
{
    hz_errors errs = {0};
    if (scene_parse_file_all(path, out, &errs, err) != HZ_OK)
        return HZ_ERROR;
    return report_alone(out, &errs, err);
}
