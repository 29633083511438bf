/* Text from files (grid names, channel names, scene strings) on its way to a
 * terminal: an escape sequence in a grid name must not reach the user's
 * terminal, and a message must stay one line. */
#ifndef HAZE_CORE_TEXT_H
#define HAZE_CORE_TEXT_H

#include <stddef.h>

/* Copies the first `n` bytes of `in` to `out` (always NUL-terminated within
 * out_size), with control bytes (0x00-0x1f, 0x7f), C1 controls and bytes
 * that are not part of valid UTF-8 written as \xNN. Valid UTF-8 passes
 * unchanged (a literal backslash too: the output is for people to read). */
void text_escape(const char *in, size_t n, char *out, size_t out_size);

/* The same in place on a NUL-terminated string of buffer size `size`
 * (truncated to fit). */
void text_escape_inplace(char *s, size_t size);

#endif
