#include "core/text.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* Length of the valid UTF-8 sequence starting at s (at most n bytes), or 0. */
static size_t utf8_length(const unsigned char *s, size_t n)
{
    unsigned char c = s[0];
    size_t len;
    uint32_t cp, min;
    if (c >= 0xc2 && c <= 0xdf) {
        len = 2, cp = c & 0x1f, min = 0x80;
    } else if (c >= 0xe0 && c <= 0xef) {
        len = 3, cp = c & 0x0f, min = 0x800;
    } else if (c >= 0xf0 && c <= 0xf4) {
        len = 4, cp = c & 0x07, min = 0x10000;
    } else {
        return 0;
    }
    if (len > n)
        return 0;
    for (size_t i = 1; i < len; ++i) {
        if ((s[i] & 0xc0) != 0x80)
            return 0;
        cp = (cp << 6) | (s[i] & 0x3f);
    }
    if (cp < min || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff))
        return 0;
    /* C1 controls (U+0080..U+009F) act on terminals too. */
    if (cp < 0xa0)
        return 0;
    return len;
}

void text_escape(const char *in, size_t n, char *out, size_t out_size)
{
    if (out_size == 0)
        return;
    const unsigned char *s = (const unsigned char *)in;
    size_t o = 0;
    for (size_t i = 0; i < n;) {
        unsigned char c = s[i];
        char piece[8];
        size_t len;
        if (c >= 0x20 && c < 0x7f) {
            piece[0] = (char)c;
            len = 1;
            i += 1;
        } else if (c >= 0x80 && (len = utf8_length(s + i, n - i)) > 0) {
            memcpy(piece, s + i, len);
            i += len;
        } else {
            snprintf(piece, sizeof piece, "\\x%02x", c);
            len = 4;
            i += 1;
        }
        if (o + len >= out_size)
            break;
        memcpy(out + o, piece, len);
        o += len;
    }
    out[o] = '\0';
}

void text_escape_inplace(char *s, size_t size)
{
    size_t n = strlen(s);
    for (size_t i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)s[i];
        if (c < 0x20 || c >= 0x7f) {
            char copy[4096];
            size_t m = n < sizeof copy ? n : sizeof copy - 1;
            memcpy(copy, s, m);
            text_escape(copy, m, s, size);
            return;
        }
    }
}
