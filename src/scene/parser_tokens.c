/* The token stream of the scene parser (parser_tokens.h): the files being
 * read, Include/Import, and the arguments of directives. */
/* realpath() is an XSI function: _POSIX_C_SOURCE alone does not declare it. */
#define _XOPEN_SOURCE 700

#include "scene/parser_tokens.h"

#include <assert.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "core/path.h"
#include "scene/mem.h"

/* Deep enough for any real scene; bounds the files open at once. */
#define MAX_INCLUDE_DEPTH 64

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

bool parser_push_root(parser *ps, const char *text, size_t len, const char *file,
                      const char *name)
{
    char *canon = canonical(name);
    return canon && push_file(ps, text, len, file, canon);
}
