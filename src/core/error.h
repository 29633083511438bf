/* Status codes and error messages. Functions that can fail return hz_status and
 * fill an hz_error; scene errors carry the file:line:column they come from. */
#ifndef HAZE_CORE_ERROR_H
#define HAZE_CORE_ERROR_H

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

typedef enum { HZ_OK = 0, HZ_ERROR = 1 } hz_status;

/* A place in a scene file. `file` points at a string owned by the scene
 * description (it outlives every file_loc that refers to it). */
typedef struct {
    const char *file;
    int line, column;
    /* The top-level scene file, whose directory relative file names start
     * from (pbrt-v4's search directory, for the scene and every file it
     * includes); NULL: `file` itself. */
    const char *root;
} file_loc;

typedef struct {
    char message[4096];
    file_loc loc; /* where, for hz_fail_at (file NULL otherwise); loc.file
                   * lives as long as the scene description it came from */
} hz_error;

#if defined(__GNUC__)
#define HZ_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define HZ_PRINTF(a, b)
#endif

/* Fill `err` (may be NULL) and return HZ_ERROR, so callers can
 * `return hz_fail(err, "...")`. */
hz_status hz_fail(hz_error *err, const char *fmt, ...) HZ_PRINTF(2, 3);
/* Same, prefixed with "file:line:column: ". */
hz_status hz_fail_at(hz_error *err, file_loc loc, const char *fmt, ...) HZ_PRINTF(3, 4);
/* "FILE:LINE:COL: warning: MESSAGE" (FILE "<input>" when unnamed) into buf. */
void hz_format_warning(char *buf, size_t n, file_loc at, const char *fmt, va_list ap);
/* That line and a newline on `out`; nothing when `out` is NULL. */
void hz_warn_at(FILE *out, file_loc at, const char *fmt, ...) HZ_PRINTF(3, 4);
hz_status hz_vfail(hz_error *err, const char *fmt, va_list ap);

/* Writes the message to `f`, each of its lines (several errors come one
 * per line) prefixed "haze: ". */
void hz_error_print(FILE *f, const hz_error *err);

/* The errors of one run that are reported together (a scene's problems,
 * found by going on past each one): the first HZ_ERRORS_MAX are kept, the
 * rest counted. */
enum { HZ_ERRORS_MAX = 20 };
typedef struct {
    hz_error *items;
    size_t count, dropped;
} hz_errors;

/* Adds a copy of `e`. Out of memory counts it as dropped. */
void hz_errors_add(hz_errors *l, const hz_error *e);
/* HZ_OK when the list is empty. Otherwise fills `err` with the errors, one
 * per line, in file order (files in the order of `files`, then line and
 * column; errors with no place, or in no listed file, last, in the order
 * found), "... and N more" when some were dropped; `err->loc` is the first
 * error's place. Frees the list either way. */
hz_status hz_errors_finish(hz_errors *l, const char *const *files, size_t file_count,
                           hz_error *err);

#endif
