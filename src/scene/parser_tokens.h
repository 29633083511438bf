/* The scene parser's token stream (parser_tokens.c): one stream over the
 * scene's files, as pbrt-v4 reads them (parser_state.h's `files`), and the
 * arguments directives read from it. */
#ifndef HAZE_SCENE_PARSER_TOKENS_H
#define HAZE_SCENE_PARSER_TOKENS_H

#include <stdbool.h>
#include <stddef.h>

#include "scene/parser_state.h"

/* Starts the stream at the outermost file: `text` (the caller's, kept to the
 * end of the parse) read as `file`, its cycle detection by `name`'s canonical
 * path. False when out of memory. */
bool parser_push_root(parser *ps, const char *text, size_t len, const char *file,
                      const char *name);
hz_status parser_next(parser *ps, token *tok, hz_error *err);
hz_status parser_peek(parser *ps, token *tok, hz_error *err);
/* Next token must be a string: returns it decoded and interned. */
hz_status parser_string_arg(parser *ps, const token *directive, const char **out, hz_error *err);
/* Next n tokens must be numbers (optionally all inside one pair of brackets
 * when `brackets_ok`). */
hz_status parser_numbers(parser *ps, const token *directive, double *out, int n, bool brackets_ok,
                         hz_error *err);
hz_status parser_include(parser *ps, const token *directive, const char *path, hz_error *err);

#endif
