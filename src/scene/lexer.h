/* Tokenizer for pbrt-v4 scene files. Tokens point into the source text (which
 * must outlive them) and carry their file:line:column (1-based; columns count
 * bytes). Numbers are validated here so the parser never sees "1.2.3" or inf. */
#ifndef HAZE_SCENE_LEXER_H
#define HAZE_SCENE_LEXER_H

#include <stddef.h>

#include "core/error.h"

typedef enum {
    TOK_EOF,
    TOK_STRING,   /* "..." ; text/len exclude the quotes, escapes not yet decoded */
    TOK_NUMBER,   /* num holds the value */
    TOK_IDENT,    /* directive names, true, false */
    TOK_LBRACKET,
    TOK_RBRACKET
} token_kind;

typedef struct {
    token_kind kind;
    const char *text;
    size_t len;
    double num;
    file_loc loc;
} token;

typedef struct {
    const char *src;
    size_t len, pos;
    int line, column;
    const char *file; /* stored in every token's loc */
    const char *root; /* the top-level scene file, the same */
} lexer;

/* `root` (may be NULL) goes into every token's loc.root. */
void lexer_init(lexer *lx, const char *src, size_t len, const char *file, const char *root);
/* The next token, TOK_EOF at the end. Errors (unterminated string, bad escape,
 * malformed or out-of-range number, stray byte) name the token's start. */
hz_status lexer_next(lexer *lx, token *tok, hz_error *err);
/* Decoded, NUL-terminated copy of a TOK_STRING's contents (malloc'd; NULL only
 * when out of memory). The lexer has already validated the escapes. */
char *token_string_dup(const token *tok);
/* True when tok is an identifier equal to `word`. */
int token_is(const token *tok, const char *word);
/* Writes a printable, truncated rendering of the token for messages. */
void token_describe(const token *tok, char *buf, size_t size);

#endif
