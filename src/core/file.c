#define _POSIX_C_SOURCE 200809L
#include "core/file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <zlib.h>

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

const char *file_kind_name(mode_t mode)
{
    if (S_ISDIR(mode))
        return "a directory";
    if (S_ISCHR(mode) || S_ISBLK(mode))
        return "a device";
    if (S_ISFIFO(mode))
        return "a FIFO";
    if (S_ISSOCK(mode))
        return "a socket";
    return "not a regular file";
}

hz_status file_check_regular(const char *path, hz_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0 || S_ISREG(st.st_mode))
        return HZ_OK;
    return hz_fail(err, "%s: cannot read: is %s; haze reads only regular files", path,
                   file_kind_name(st.st_mode));
}

hz_status file_open_regular(const char *path, int *fd_out, off_t *size, hz_error *err)
{
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return hz_fail(err, "%s", strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int en = errno;
        close(fd);
        return hz_fail(err, "%s", strerror(en));
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return hz_fail(err, "is %s; haze reads only regular files", file_kind_name(st.st_mode));
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0)
        fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    *fd_out = fd;
    *size = st.st_size;
    return HZ_OK;
}

static hz_status too_big(size_t limit, bool gz, hz_error *err)
{
    return hz_fail(err, "larger than haze's limit of %zu MiB%s", limit >> 20,
                   gz ? " once decompressed" : "");
}

static hz_status read_plain(int fd, off_t size, size_t limit, char **data,
                            size_t *len, hz_error *err)
{
    if (size < 0 || (unsigned long long)size > limit)
        return too_big(limit, false, err);
    size_t cap = (size_t)size + 1, n = 0;
    char *buf = malloc(cap);
    if (!buf)
        return hz_fail(err, "out of memory for %zu bytes", cap);
    for (;;) {
        ssize_t got = read(fd, buf + n, cap - n);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0) {
            int en = errno;
            free(buf);
            return hz_fail(err, "%s", strerror(en));
        }
        if (got == 0)
            break;
        n += (size_t)got;
        if (n == cap) { /* the file grew while being read */
            free(buf);
            return hz_fail(err, "changed size while being read");
        }
    }
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return HZ_OK;
}

static hz_status read_gzip(int fd, size_t limit, char **data, size_t *len,
                           hz_error *err)
{
    gzFile gz = gzdopen(fd, "rb");
    if (!gz) {
        close(fd);
        return hz_fail(err, "cannot start gzip decompression");
    }
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap + 1);
    hz_status st = HZ_OK;
    while (buf) {
        if (n == cap) {
            if (cap > limit) {
                st = too_big(limit, true, err);
                break;
            }
            cap *= 2;
            char *grown = realloc(buf, cap + 1);
            if (!grown) {
                st = hz_fail(err, "out of memory decompressing");
                break;
            }
            buf = grown;
        }
        size_t want = cap - n < (1u << 30) ? cap - n : (1u << 30);
        int got = gzread(gz, buf + n, (unsigned)want);
        if (got < 0) {
            int zerr;
            const char *msg = gzerror(gz, &zerr);
            st = hz_fail(err, "corrupt gzip data (%s)", msg ? msg : "zlib error");
            break;
        }
        if (got == 0)
            break;
        n += (size_t)got;
    }
    if (!buf)
        st = hz_fail(err, "out of memory decompressing");
    if (st == HZ_OK && n > limit)
        st = too_big(limit, true, err);
    gzclose(gz); /* closes fd */
    if (st != HZ_OK) {
        free(buf);
        return st;
    }
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return HZ_OK;
}

hz_status file_read_all(const char *path, size_t limit, char **data, size_t *len, hz_error *err)
{
    int fd = -1;
    off_t size = 0;
    if (file_open_regular(path, &fd, &size, err) != HZ_OK)
        return HZ_ERROR;
    if (ends_with(path, ".gz"))
        return read_gzip(fd, limit, data, len, err);
    hz_status st = read_plain(fd, size, limit, data, len, err);
    close(fd);
    return st;
}

bool file_has_suffix(const char *path, const char *suffix)
{
    size_t n = strlen(path), m = strlen(suffix);
    return n >= m && strcasecmp(path + n - m, suffix) == 0;
}
