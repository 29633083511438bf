/* Status codes and error messages. Functions that can fail return hz_status and
 * fill an hz_error; scene errors carry the file:line:column they come from. */
#ifndef HAZE_CORE_ERROR_H
#define HAZE_CORE_ERROR_H

#include <stdarg.h>

typedef enum { HZ_OK = 0, HZ_ERROR = 1 } hz_status;

/* A place in a scene file. `file` points at a string owned by the scene
 * description (it outlives every file_loc that refers to it). */
typedef struct {
    const char *file;
    int line, column;
} file_loc;

typedef struct {
    char message[1024];
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
hz_status hz_vfail(hz_error *err, const char *fmt, va_list ap);

#endif
