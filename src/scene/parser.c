/* Scene parser driver: files, the token stream, Include/Import, and the public
 * entry points. What directives mean lives in parser_directives.c. */
/* realpath() is an XSI function: _POSIX_C_SOURCE alone does not declare it. */
#define _XOPEN_SOURCE 700

#include "scene/parser.h"

#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "core/path.h"
#include "scene/mem.h"

/* Deep enough for any real scene; bounds the files open at once. */
#define MAX_INCLUDE_DEPTH 64

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

/* The next token of the stream: the end of an included file continues its
 * includer; only the outermost file's end is TOK_EOF. */
static hz_status lex(parser *ps, token *tok, hz_error *err)
{
    for (;;) {
        parser_file *f = &ps->files[ps->file_depth - 1];
        if (lexer_next(&f->lx, tok, err) != HZ_OK) {
            ps->lex_failed = true;
            return HZ_ERROR;
        }
        if (tok->kind != TOK_EOF || ps->file_depth == 1)
            return HZ_OK;
        free(f->canon);
        ps->file_depth--;
    }
}

hz_status parser_next(parser *ps, token *tok, hz_error *err)
{
    if (ps->has_peek) {
        *tok = ps->peek;
        ps->has_peek = false;
        return HZ_OK;
    }
    return lex(ps, tok, err);
}

hz_status parser_peek(parser *ps, token *tok, hz_error *err)
{
    if (!ps->has_peek) {
        if (lex(ps, &ps->peek, err) != HZ_OK)
            return HZ_ERROR;
        ps->has_peek = true;
    }
    *tok = ps->peek;
    return HZ_OK;
}

static const char *directive_name(const token *d, char *buf, size_t n)
{
    snprintf(buf, n, "%.*s", (int)(d->len < 40 ? d->len : 40), d->text);
    return buf;
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

hz_status parser_string_arg(parser *ps, const token *directive, const char **out, hz_error *err)
{
    token t;
    if (parser_next(ps, &t, err) != HZ_OK)
        return HZ_ERROR;
    if (t.kind != TOK_STRING) {
        char name[48], got[48];
        token_describe(&t, got, sizeof got);
        return hz_fail_at(err, t.loc, "%s expects a quoted string, found %s",
                          directive_name(directive, name, sizeof name), got);
    }
    char *s = token_string_dup(&t);
    if (!s)
        return parser_oom(ps, t.loc, err);
    *out = parser_intern(ps, s);
    free(s);
    return *out ? HZ_OK : parser_oom(ps, t.loc, err);
}

hz_status parser_numbers(parser *ps, const token *directive, double *out, int n, bool brackets_ok,
                         hz_error *err)
{
    token t;
    char name[48], got[48];
    directive_name(directive, name, sizeof name);
    if (parser_peek(ps, &t, err) != HZ_OK)
        return HZ_ERROR;
    bool bracketed = brackets_ok && t.kind == TOK_LBRACKET;
    file_loc open = t.loc;
    if (bracketed)
        parser_next(ps, &t, err);
    for (int i = 0; i < n; ++i) {
        if (parser_next(ps, &t, err) != HZ_OK)
            return HZ_ERROR;
        if (t.kind != TOK_NUMBER) {
            token_describe(&t, got, sizeof got);
            return hz_fail_at(err, t.loc, "%s expects %d numbers, found %s after %d", name, n, got,
                              i);
        }
        out[i] = t.num;
    }
    if (bracketed) {
        if (parser_next(ps, &t, err) != HZ_OK)
            return HZ_ERROR;
        if (t.kind != TOK_RBRACKET) {
            token_describe(&t, got, sizeof got);
            return hz_fail_at(err, open, "%s: '[' is not closed after %d numbers (found %s)", name,
                              n, got);
        }
    }
    return HZ_OK;
}

/* The canonical name used for cycle detection; falls back to the name itself
 * for in-memory scenes whose name is not a file. NULL when out of memory. */
static char *canonical(const char *path)
{
    char *r = realpath(path, NULL);
    return r ? r : scene_strdup(path);
}

/* Pushes a file onto the token stream; takes `canon` (freed here when out of
 * memory, the only failure). The text stays the caller's. */
static bool push_file(parser *ps, const char *text, size_t len, const char *file, char *canon)
{
    assert(!ps->has_peek); /* the next token must come from the new file */
    parser_file *grown = scene_grow(ps->files, &ps->file_cap, ps->file_depth, sizeof *ps->files);
    if (!grown) {
        free(canon);
        return false;
    }
    ps->files = grown;
    parser_file *f = &ps->files[ps->file_depth++];
    lexer_init(&f->lx, text, len, file, ps->sd->file_count ? ps->sd->files[0] : file);
    f->canon = canon;
    return true;
}

/* Keeps an included file's text to the end of the parse (tokens point into
 * it); frees it when out of memory, the only failure. */
static bool keep_text(parser *ps, char *text)
{
    char **grown = scene_grow(ps->texts, &ps->text_cap, ps->text_count, sizeof *ps->texts);
    if (!grown) {
        free(text);
        return false;
    }
    ps->texts = grown;
    ps->texts[ps->text_count++] = text;
    return true;
}

hz_status parser_include(parser *ps, const token *directive, const char *path, hz_error *err)
{
    char name[48];
    directive_name(directive, name, sizeof name);
    char *full = path_of_scene_file(directive->loc, path);
    if (!full)
        return parser_oom(ps, directive->loc, err);
    char *canon = realpath(full, NULL);
    if (!canon && errno == ENOMEM) {
        free(full);
        return parser_oom(ps, directive->loc, err);
    }
    if (!canon) {
        hz_status st = hz_fail_at(err, directive->loc, "%s: cannot open \"%s\": %s", name, full,
                                  strerror(errno));
        free(full);
        return st;
    }
    for (size_t i = 0; i < ps->file_depth; ++i) {
        if (strcmp(ps->files[i].canon, canon) != 0)
            continue;
        char chain[700] = "";
        for (size_t j = i; j < ps->file_depth; ++j) {
            const char *c = ps->files[j].canon, *base = strrchr(c, '/');
            size_t used = strlen(chain);
            snprintf(chain + used, sizeof chain - used, "%s -> ", base ? base + 1 : c);
        }
        const char *base = strrchr(canon, '/');
        size_t used = strlen(chain);
        snprintf(chain + used, sizeof chain - used, "%s", base ? base + 1 : canon);
        hz_status st = hz_fail_at(err, directive->loc, "%s cycle: %s", name, chain);
        free(full);
        free(canon);
        return st;
    }
    if (ps->file_depth >= MAX_INCLUDE_DEPTH) {
        free(full);
        free(canon);
        return hz_fail_at(err, directive->loc, "%s: files nested more than %d deep", name,
                          MAX_INCLUDE_DEPTH);
    }
    char *text;
    size_t len;
    hz_error ferr;
    if (file_read_all(full, FILE_LIMIT_SCENE, &text, &len, &ferr) != HZ_OK) {
        hz_status st = hz_fail_at(err, directive->loc, "%s: cannot read \"%s\": %s", name, full,
                                  ferr.message);
        free(full);
        free(canon);
        return st;
    }
    const char *file = parser_intern(ps, full);
    free(full);
    if (!file || !scene_desc_add_file(ps->sd, file)) {
        free(text);
        free(canon);
        return parser_oom(ps, directive->loc, err);
    }
    if (!keep_text(ps, text)) {
        free(canon);
        return parser_oom(ps, directive->loc, err);
    }
    if (!push_file(ps, text, len, file, canon))
        return parser_oom(ps, directive->loc, err);
    return HZ_OK;
}

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
    char *canon = canonical(name);
    return canon && push_file(ps, text, len, file, canon);
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
