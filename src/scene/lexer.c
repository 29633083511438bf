#define _POSIX_C_SOURCE 200809L
#include "scene/lexer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

void lexer_init(lexer *lx, const char *src, size_t len, const char *file, const char *root)
{
    lx->src = src;
    lx->len = len;
    lx->pos = 0;
    /* A UTF-8 byte order mark (editors on Windows write one) is not text. */
    if (len >= 3 && memcmp(src, "\xEF\xBB\xBF", 3) == 0)
        lx->pos = 3;
    lx->line = 1;
    lx->column = 1;
    lx->file = file;
    lx->root = root;
}

static file_loc here(const lexer *lx)
{
    return (file_loc){lx->file, lx->line, lx->column, lx->root};
}

static void advance(lexer *lx)
{
    if (lx->src[lx->pos] == '\n') {
        ++lx->line;
        lx->column = 1;
    } else {
        ++lx->column;
    }
    ++lx->pos;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

static int is_digit(char c) { return c >= '0' && c <= '9'; }
static int is_alpha(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }

/* A bare word ends at whitespace, a quote, a bracket or a comment. */
static int ends_word(char c)
{
    return is_space(c) || c == '"' || c == '[' || c == ']' || c == '#';
}

static char printable(char c)
{
    return (c >= 0x20 && c < 0x7f) ? c : '?';
}

static hz_status lex_string(lexer *lx, token *tok, hz_error *err)
{
    advance(lx); /* opening quote */
    size_t start = lx->pos;
    for (;;) {
        if (lx->pos >= lx->len || lx->src[lx->pos] == '\n')
            return hz_fail_at(err, tok->loc, "unterminated string");
        char c = lx->src[lx->pos];
        if (c == '"')
            break;
        /* C strings end at a NUL: the name would be silently cut short. */
        if (c == '\0')
            return hz_fail_at(err, here(lx), "NUL byte inside a string");
        if (c == '\\') {
            file_loc at = here(lx);
            advance(lx);
            if (lx->pos >= lx->len || lx->src[lx->pos] == '\n')
                return hz_fail_at(err, tok->loc, "unterminated string");
            char e = lx->src[lx->pos];
            if (!strchr("ntrbf\\\"'", e))
                return hz_fail_at(err, at, "unknown escape sequence '\\%c' in string", printable(e));
        }
        advance(lx);
    }
    tok->kind = TOK_STRING;
    tok->text = lx->src + start;
    tok->len = lx->pos - start;
    advance(lx); /* closing quote */
    return HZ_OK;
}

/* pbrt-style number: [+-] digits [. digits] [e [+-] digits], at least one
 * mantissa digit. Stricter than strtod, which would accept "inf" or hex. */
static int valid_number(const char *s, size_t n)
{
    size_t i = 0, digits = 0;
    if (i < n && (s[i] == '+' || s[i] == '-'))
        ++i;
    while (i < n && is_digit(s[i]))
        ++i, ++digits;
    if (i < n && s[i] == '.') {
        ++i;
        while (i < n && is_digit(s[i]))
            ++i, ++digits;
    }
    if (digits == 0)
        return 0;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < n && (s[i] == '+' || s[i] == '-'))
            ++i;
        size_t exp_digits = 0;
        while (i < n && is_digit(s[i]))
            ++i, ++exp_digits;
        if (exp_digits == 0)
            return 0;
    }
    return i == n;
}

static hz_status lex_word(lexer *lx, token *tok, hz_error *err)
{
    size_t start = lx->pos;
    char first = lx->src[start];
    int numeric = is_digit(first) || first == '+' || first == '-' || first == '.';
    while (lx->pos < lx->len && !ends_word(lx->src[lx->pos])) {
        char c = lx->src[lx->pos];
        if (!numeric && !is_alpha(c) && !is_digit(c))
            return hz_fail_at(err, here(lx), "unexpected character '%c' (byte 0x%02x)",
                              printable(c), (unsigned)(unsigned char)c);
        advance(lx);
    }
    tok->text = lx->src + start;
    tok->len = lx->pos - start;
    if (!numeric) {
        tok->kind = TOK_IDENT;
        /* Bare words are never values; these look like ones. */
        static const char *const nonfinite[] = {"nan", "inf", "infinity"};
        for (size_t i = 0; i < sizeof nonfinite / sizeof nonfinite[0]; ++i)
            if (tok->len == strlen(nonfinite[i]) && strncasecmp(tok->text, nonfinite[i], tok->len) == 0)
                return hz_fail_at(err, tok->loc, "'%.*s' is not a number: scene values must be finite",
                                  (int)tok->len, tok->text);
        return HZ_OK;
    }
    tok->kind = TOK_NUMBER;
    char buf[64];
    char shown[48];
    token_describe(tok, shown, sizeof shown);
    if (tok->len >= sizeof buf || !valid_number(tok->text, tok->len))
        return hz_fail_at(err, tok->loc, "malformed number %s", shown);
    memcpy(buf, tok->text, tok->len);
    buf[tok->len] = '\0';
    double v = strtod(buf, NULL);
    if (!isfinite(v))
        return hz_fail_at(err, tok->loc, "number %s is out of range", shown);
    tok->num = v;
    return HZ_OK;
}

hz_status lexer_next(lexer *lx, token *tok, hz_error *err)
{
    for (;;) {
        while (lx->pos < lx->len && is_space(lx->src[lx->pos]))
            advance(lx);
        if (lx->pos < lx->len && lx->src[lx->pos] == '#') {
            while (lx->pos < lx->len && lx->src[lx->pos] != '\n')
                advance(lx);
            continue;
        }
        break;
    }
    tok->loc = here(lx);
    tok->text = lx->src + lx->pos;
    tok->len = 0;
    tok->num = 0.0;
    if (lx->pos >= lx->len) {
        tok->kind = TOK_EOF;
        return HZ_OK;
    }
    char c = lx->src[lx->pos];
    switch (c) {
    case '"':
        return lex_string(lx, tok, err);
    case '[':
    case ']':
        tok->kind = c == '[' ? TOK_LBRACKET : TOK_RBRACKET;
        tok->len = 1;
        advance(lx);
        return HZ_OK;
    default:
        return lex_word(lx, tok, err);
    }
}

char *token_string_dup(const token *tok)
{
    char *s = malloc(tok->len + 1);
    if (!s)
        return NULL;
    size_t o = 0;
    for (size_t i = 0; i < tok->len; ++i) {
        char c = tok->text[i];
        if (c == '\\' && i + 1 < tok->len) {
            char e = tok->text[++i];
            switch (e) {
            case 'n': c = '\n'; break;
            case 't': c = '\t'; break;
            case 'r': c = '\r'; break;
            case 'b': c = '\b'; break;
            case 'f': c = '\f'; break;
            default: c = e; break; /* \\ \" \' */
            }
        }
        s[o++] = c;
    }
    s[o] = '\0';
    return s;
}

int token_is(const token *tok, const char *word)
{
    size_t n = strlen(word);
    return tok->kind == TOK_IDENT && tok->len == n && memcmp(tok->text, word, n) == 0;
}

void token_describe(const token *tok, char *buf, size_t size)
{
    if (size == 0)
        return;
    if (tok->kind == TOK_EOF) {
        snprintf(buf, size, "end of file");
        return;
    }
    const char *open = tok->kind == TOK_STRING ? "\"" : "'";
    size_t limit = size > 12 ? size - 12 : 0;
    size_t n = tok->len < limit ? tok->len : limit;
    size_t o = 0;
    o += (size_t)snprintf(buf, size, "%s", open);
    for (size_t i = 0; i < n && o + 1 < size; ++i)
        buf[o++] = printable(tok->text[i]);
    buf[o < size ? o : size - 1] = '\0';
    snprintf(buf + strlen(buf), size - strlen(buf), "%s%s", n < tok->len ? "..." : "", open);
}
