/* Scene parser driver: files, the token stream, Include/Import, and the public
 * entry points. What directives mean lives in parser_directives.c. */
/* realpath() is an XSI function: _POSIX_C_SOURCE alone does not declare it. */
#define _XOPEN_SOURCE 700

#include "scene/parser.h"

#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "core/path.h"
#include "scene/mem.h"

/* Deep enough for any real scene; bounds the files open at once. */
#define MAX_INCLUDE_DEPTH 64

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
    sd->strings = scene_grow(sd->strings, &sd->string_capacity, sd->string_count,
                             sizeof *sd->strings);
    sd->strings[sd->string_count++] = scene_xstrdup(s);
    return sd->strings[sd->string_count - 1];
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
        return hz_fail_at(err, t.loc, "out of memory");
    *out = parser_intern(ps, s);
    free(s);
    return HZ_OK;
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
 * for in-memory scenes whose name is not a file. */
static char *canonical(const char *path)
{
    char *r = realpath(path, NULL);
    return r ? r : scene_xstrdup(path);
}

/* Pushes a file onto the token stream; takes `canon` (and `text` unless it
 * is the caller's: the outermost file). */
static void push_file(parser *ps, const char *text, size_t len, const char *file, char *canon)
{
    assert(!ps->has_peek); /* the next token must come from the new file */
    ps->files = scene_grow(ps->files, &ps->file_cap, ps->file_depth, sizeof *ps->files);
    parser_file *f = &ps->files[ps->file_depth++];
    lexer_init(&f->lx, text, len, file);
    f->canon = canon;
}
hz_status parser_include(parser *ps, const token *directive, const char *path, hz_error *err)
{
    char name[48];
    directive_name(directive, name, sizeof name);
    char *full = path_relative_to(directive->loc.file, path);
    if (!full)
        return hz_fail_at(err, directive->loc, "%s: out of memory", name);
    char *canon = realpath(full, NULL);
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
    scene_desc_add_file(ps->sd, file);
    ps->texts = scene_grow(ps->texts, &ps->text_cap, ps->text_count, sizeof *ps->texts);
    ps->texts[ps->text_count++] = text;
    push_file(ps, text, len, file, canon);
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

static hz_status parse_root(const char *text, size_t len, const char *name, scene_desc *out,
                            hz_error *err)
{
    memset(out, 0, sizeof *out);
    parser ps;
    memset(&ps, 0, sizeof ps);
    ps.sd = out;
    scene_desc_init(out, name);
    const char *file = out->camera.entity.loc.file;
    ps.gs.ctm[0] = ps.gs.ctm[1] = transform_identity();
    ps.gs.active = 3;
    ps.gs.material = -1;
    ps.gs.inside = ps.gs.outside = parser_intern(&ps, "");
    for (int i = 0; i < ATTR_COUNT; ++i)
        params_init(&ps.gs.attrs[i], (file_loc){file, 1, 1});
    ps.current_object = -1;
    push_file(&ps, text, len, file, canonical(name));

    /* Every error of the file in one run: after a directive's error the
     * stream goes on at the next directive (up to HZ_ERRORS_MAX kept); a
     * lexer error ends it. */
    hz_errors errs = {0};
    file_loc end = {file, 1, 1};
    for (;;) {
        token t;
        if (parser_next(&ps, &t, err) != HZ_OK) {
            hz_errors_add(&errs, err);
            break;
        }
        if (t.kind == TOK_EOF) {
            end = t.loc;
            break;
        }
        if (t.kind == TOK_IDENT && parser_directive(&ps, &t, err) == HZ_OK)
            continue;
        if (t.kind != TOK_IDENT) {
            char got[48];
            token_describe(&t, got, sizeof got);
            hz_fail_at(err, t.loc, "expected a directive, found %s", got);
        }
        hz_errors_add(&errs, err);
        if (ps.lex_failed)
            break;
        if (skip_to_directive(&ps, err) != HZ_OK) {
            hz_errors_add(&errs, err); /* the lexer's, met while skipping */
            break;
        }
    }
    if (!ps.lex_failed && parser_finish(&ps, end, err) != HZ_OK)
        hz_errors_add(&errs, err);
    hz_status st = hz_errors_finish(&errs, out->files, out->file_count, err);
    parser_state_free(&ps);
    if (st != HZ_OK)
        scene_desc_free(out);
    return st;
}

hz_status scene_parse_string(const char *text, const char *name, scene_desc *out, hz_error *err)
{
    return parse_root(text, strlen(text), name ? name : "<string>", out, err);
}

hz_status scene_parse_file(const char *path, scene_desc *out, hz_error *err)
{
    char *text;
    size_t len;
    hz_error ferr;
    memset(out, 0, sizeof *out);
    if (file_read_all(path, FILE_LIMIT_SCENE, &text, &len, &ferr) != HZ_OK)
        return hz_fail(err, "%s: cannot read scene: %s", path, ferr.message);
    hz_status st = parse_root(text, len, path, out, err);
    free(text);
    return st;
}
