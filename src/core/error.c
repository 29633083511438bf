#include "core/error.h"

#include "core/text.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

hz_status hz_vfail(hz_error *err, const char *fmt, va_list ap)
{
    if (err) {
        err->loc = (file_loc){0};
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        text_escape_inplace(err->message, sizeof err->message);
    }
    return HZ_ERROR;
}

hz_status hz_fail(hz_error *err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    hz_vfail(err, fmt, ap);
    va_end(ap);
    return HZ_ERROR;
}

hz_status hz_fail_at(hz_error *err, file_loc loc, const char *fmt, ...)
{
    if (!err)
        return HZ_ERROR;
    err->loc = loc;
    int n = snprintf(err->message, sizeof err->message, "%s:%d:%d: ",
                     loc.file ? loc.file : "<input>", loc.line, loc.column);
    if (n < 0 || (size_t)n >= sizeof err->message)
        return HZ_ERROR;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message + n, sizeof err->message - (size_t)n, fmt, ap);
    va_end(ap);
    text_escape_inplace(err->message, sizeof err->message);
    return HZ_ERROR;
}

void hz_format_warning(char *buf, size_t n, file_loc at, const char *fmt, va_list ap)
{
    int k = snprintf(buf, n, "%s:%d:%d: warning: ", at.file ? at.file : "<input>", at.line,
                     at.column);
    if (k >= 0 && (size_t)k < n)
        vsnprintf(buf + k, n - (size_t)k, fmt, ap);
}

void hz_warn_at(FILE *out, file_loc at, const char *fmt, ...)
{
    if (!out)
        return;
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    hz_format_warning(line, sizeof line, at, fmt, ap);
    va_end(ap);
    fprintf(out, "%s\n", line);
}

void hz_errors_add(hz_errors *l, const hz_error *e)
{
    if (l->count == HZ_ERRORS_MAX) {
        l->dropped++;
        return;
    }
    if (!l->items) {
        l->items = malloc(HZ_ERRORS_MAX * sizeof *l->items);
        if (!l->items) {
            l->dropped++;
            return;
        }
    }
    l->items[l->count++] = *e;
}

typedef struct {
    size_t file, order;
    int line, column;
} error_key;

static int key_cmp(const void *pa, const void *pb)
{
    const error_key *a = pa, *b = pb;
    if (a->file != b->file)
        return a->file < b->file ? -1 : 1;
    if (a->line != b->line)
        return a->line < b->line ? -1 : 1;
    if (a->column != b->column)
        return a->column < b->column ? -1 : 1;
    return a->order < b->order ? -1 : a->order > b->order;
}

hz_status hz_errors_finish(hz_errors *l, const char *const *files, size_t file_count,
                           hz_error *err)
{
    if (l->count == 0 && l->dropped == 0) {
        free(l->items);
        *l = (hz_errors){0};
        return HZ_OK;
    }
    error_key keys[HZ_ERRORS_MAX];
    for (size_t i = 0; i < l->count; ++i) {
        const file_loc *loc = &l->items[i].loc;
        size_t f = file_count;
        for (size_t k = 0; loc->file && k < file_count && f == file_count; ++k)
            if (files[k] && strcmp(files[k], loc->file) == 0)
                f = k;
        keys[i] = (error_key){f, i, loc->line, loc->column};
    }
    qsort(keys, l->count, sizeof *keys, key_cmp);
    if (err) {
        err->message[0] = '\0';
        err->loc = l->count ? l->items[keys[0].order].loc : (file_loc){0};
        /* Whole lines only, with room kept for the count of the rest. */
        enum { TAIL = 48 };
        size_t used = 0, cap = sizeof err->message, dropped = l->dropped;
        for (size_t i = 0; i < l->count; ++i) {
            const char *m = l->items[keys[i].order].message;
            if (used && used + strlen(m) + 1 + TAIL >= cap) {
                dropped += l->count - i;
                break;
            }
            used += (size_t)snprintf(err->message + used, cap - used, "%s%s", used ? "\n" : "",
                                     m);
        }
        if (dropped)
            snprintf(err->message + used, cap - used, "%s... and %zu more error%s",
                     used ? "\n" : "", dropped, dropped == 1 ? "" : "s");
    }
    free(l->items);
    *l = (hz_errors){0};
    return HZ_ERROR;
}

void hz_error_print(FILE *f, const hz_error *err)
{
    const char *p = err->message;
    do {
        const char *nl = strchr(p, '\n');
        int n = nl ? (int)(nl - p) : (int)strlen(p);
        fprintf(f, "haze: %.*s\n", n, p);
        p = nl ? nl + 1 : NULL;
    } while (p);
}
