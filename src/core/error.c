#include "core/error.h"

#include "core/text.h"

#include <stdio.h>
#include <string.h>

hz_status hz_vfail(hz_error *err, const char *fmt, va_list ap)
{
    if (err) {
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
