/* Reading a .vdb grid in a child process (see vdb_module.h). */
#define _POSIX_C_SOURCE 200809L
#include "media/vdb_module.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdint.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

/* What the child sends first: its outcome and the length of what follows
 * (the grid's buffer, or the error message). */
typedef struct {
    uint64_t ok; /* 64 bits: no padding bytes go down the pipe */
    uint64_t length;
} reply_header;

static bool write_all(int fd, const void *data, size_t n)
{
    const char *p = data;
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return false;
        p += w;
        n -= (size_t)w;
    }
    return true;
}

/* Reads exactly n bytes; false on end of file or error. */
static bool read_all(int fd, void *data, size_t n)
{
    char *p = data;
    while (n > 0) {
        ssize_t r = read(fd, p, n);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return false;
        p += r;
        n -= (size_t)r;
    }
    return true;
}

static void child(const haze_openvdb_api *api, int fd, const char *path, uint64_t file_size,
                  const char *gridname, vdb_value_type type)
{
    /* What the libraries print (Blosc: "Error allocating memory!") is not
     * haze's one line: the outcome goes back through the pipe. */
    int null = open("/dev/null", O_WRONLY);
    if (null >= 0) {
        dup2(null, STDOUT_FILENO);
        dup2(null, STDERR_FILENO);
        close(null);
    }
    vdb_buffer b = {NULL, 0};
    char msg[1024] = "";
    hz_status st = api->load_grid(path, file_size, gridname, type, &b, msg, sizeof msg);
    reply_header h = {st == HZ_OK, st == HZ_OK ? (uint64_t)b.size : (uint64_t)strlen(msg)};
    bool sent = write_all(fd, &h, sizeof h) && write_all(fd, st == HZ_OK ? b.data : msg, h.length);
    _exit(sent ? 0 : 1);
}

hz_status vdb_module_load_grid_isolated(const haze_openvdb_api *api, const char *path,
                                        uint64_t file_size, const char *gridname,
                                        vdb_value_type type, vdb_buffer *out, char *err,
                                        size_t err_size)
{
    *out = (vdb_buffer){NULL, 0};
    int fds[2];
    if (pipe(fds) != 0) {
        snprintf(err, err_size, "%s: cannot start the OpenVDB reader: %s", path, strerror(errno));
        return HZ_ERROR;
    }
    fflush(NULL); /* nothing buffered is written twice */
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(err, err_size, "%s: cannot start the OpenVDB reader: %s", path, strerror(errno));
        close(fds[0]);
        close(fds[1]);
        return HZ_ERROR;
    }
    if (pid == 0) {
        close(fds[0]);
        child(api, fds[1], path, file_size, gridname, type);
    }
    close(fds[1]);
    reply_header h;
    bool got = read_all(fds[0], &h, sizeof h);
    void *data = NULL;
    if (got && h.ok) {
        /* NanoVDB wants 32-byte alignment; aligned_alloc wants a multiple. */
        size_t n = (size_t)h.length;
        data = n > 0 && n <= SIZE_MAX - 31 ? aligned_alloc(32, (n + 31) / 32 * 32) : NULL;
        got = data && read_all(fds[0], data, n);
        if (!data && n > 0) {
            snprintf(err, err_size, "%s: out of memory for a grid of %zu bytes", path, n);
            close(fds[0]);
            kill(pid, SIGKILL);
            waitpid(pid, NULL, 0);
            return HZ_ERROR;
        }
    } else if (got) {
        char msg[1024];
        size_t n = h.length < sizeof msg - 1 ? (size_t)h.length : sizeof msg - 1;
        got = read_all(fds[0], msg, n);
        msg[got ? n : 0] = '\0';
        snprintf(err, err_size, "%s", msg);
    }
    close(fds[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    /* A complete reply stands, whatever the child did after sending it (a
     * leak checker, say, may change its exit status). */
    if (!got) {
        free(data);
        if (WIFSIGNALED(status))
            snprintf(err, err_size,
                     "%s: OpenVDB failed reading grid \"%s\" (its reader was killed by signal "
                     "%d, %s; out of memory?)",
                     path, gridname, WTERMSIG(status), strsignal(WTERMSIG(status)));
        else
            snprintf(err, err_size, "%s: OpenVDB failed reading grid \"%s\" (its reader exited "
                                    "without a result)",
                     path, gridname);
        return HZ_ERROR;
    }
    if (!h.ok)
        return HZ_ERROR;
    out->data = data;
    out->size = (size_t)h.length;
    return HZ_OK;
}
