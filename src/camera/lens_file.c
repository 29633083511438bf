/* The lens description reader: stricter than pbrt-v4's ReadFloatFile (which
 * takes any whitespace-separated run of numbers whose count is a multiple of
 * four) in asking for four numbers on every row, so that a missing column is
 * reported on its own line rather than shifting every later element. */
#include "camera/lens_file.h"

#include <ctype.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"

typedef struct {
    const char *name;
    int line;
    const char *line_start;
} lens_cursor;

static hz_status fail_at(hz_error *err, const lens_cursor *c, const char *at, const char *fmt,
                         const char *what)
{
    file_loc loc = {c->name, c->line, (int)(at - c->line_start) + 1, NULL};
    return hz_fail_at(err, loc, fmt, what);
}

/* The four values of one row, each checked; `at` holds each one's place. */
static hz_status check_row(const lens_cursor *c, const lens_row *r, const char *const at[4],
                           hz_error *err)
{
    const double v[4] = {r->radius, r->thickness, r->eta, r->aperture};
    static const char *const names[4] = {"curvature radius", "thickness", "index of refraction",
                                         "aperture diameter"};
    for (int i = 0; i < 4; ++i)
        if (!isfinite(v[i]))
            return fail_at(err, c, at[i], "lens element %s is not finite", names[i]);
    if (r->thickness < 0.0)
        return fail_at(err, c, at[1], "lens element %s must be >= 0 (millimetres)", names[1]);
    if (r->eta < 0.0)
        return fail_at(err, c, at[2], "lens element %s must be >= 0 (0 means air)", names[2]);
    if (!(r->aperture > 0.0))
        return fail_at(err, c, at[3], "lens element %s must be > 0 (millimetres)", names[3]);
    return HZ_OK;
}

/* One line (up to its newline or end): nothing, a comment, or a row. */
static hz_status parse_line(lens_cursor *c, const char *p, const char *end, lens_table *out,
                            hz_error *err)
{
    double v[4];
    const char *at[4];
    int n = 0;
    while (p < end) {
        if (*p == '#')
            break;
        if (isspace((unsigned char)*p)) {
            ++p;
            continue;
        }
        const char *tok = p;
        while (p < end && !isspace((unsigned char)*p) && *p != '#')
            ++p;
        char buf[64];
        size_t len = (size_t)(p - tok);
        char *stop = buf;
        double x = 0.0;
        if (len < sizeof buf) {
            memcpy(buf, tok, len);
            buf[len] = '\0';
            x = strtod(buf, &stop);
        }
        if (len >= sizeof buf || stop != buf + len || len == 0) {
            char shown[40];
            snprintf(shown, sizeof shown, "%.*s", (int)(len < 32 ? len : 32), tok);
            return fail_at(err, c, tok, "expected a number in the lens file, got \"%s\"", shown);
        }
        if (n == 4)
            return fail_at(err, c, tok, "%s",
                           "a lens element row has four values (curvature radius, thickness, "
                           "index of refraction, aperture diameter); this is a fifth");
        at[n] = tok;
        v[n++] = x;
    }
    if (n == 0)
        return HZ_OK;
    if (n < 4)
        return fail_at(err, c, p, "%s",
                       "a lens element row has four values (curvature radius, thickness, "
                       "index of refraction, aperture diameter); this one ends early");
    if (out->count == LENS_FILE_MAX_ELEMENTS)
        return fail_at(err, c, at[0], "more than %s lens elements", "64");
    lens_row r = {v[0], v[1], v[2], v[3]};
    if (check_row(c, &r, at, err) != HZ_OK)
        return HZ_ERROR;
    out->rows[out->count++] = r;
    return HZ_OK;
}

hz_status lens_file_parse(const char *name, const char *text, lens_table *out, hz_error *err)
{
    out->count = 0;
    lens_cursor c = {name, 1, text};
    const char *p = text;
    for (;;) {
        const char *nl = strchr(p, '\n');
        const char *end = nl ? nl : p + strlen(p);
        c.line_start = p;
        if (parse_line(&c, p, end, out, err) != HZ_OK)
            return HZ_ERROR;
        if (!nl)
            break;
        p = nl + 1;
        c.line++;
    }
    if (out->count == 0) {
        file_loc loc = {name, 1, 1, NULL};
        return hz_fail_at(err, loc, "the lens file has no lens elements");
    }
    return HZ_OK;
}

hz_status lens_file_read(const char *path, lens_table *out, hz_error *err)
{
    /* Only a regular file: a FIFO or device is refused without waiting on it. */
    char *text = NULL;
    size_t n = 0;
    hz_error why;
    if (file_read_all(path, (size_t)1 << 24, &text, &n, &why) != HZ_OK)
        return hz_fail(err, "%s: cannot read the lens file: %s", path, why.message);
    if (memchr(text, '\0', n)) {
        free(text);
        return hz_fail(err, "%s: cannot read the lens file (a binary file)", path);
    }
    hz_status st = lens_file_parse(path, text, out, err);
    free(text);
    return st;
}
