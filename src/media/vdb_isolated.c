/* Reading a .vdb grid in a separate process (see vdb_module.h): the
 * renderer's side (posix_spawn, the pipe, the reply) and the reader's. */
#define _POSIX_C_SOURCE 200809L
#include "media/vdb_module.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <signal.h>
#include <spawn.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

/* What the reader sends first: its outcome and the length of what follows
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

int vdb_reader_run(const char *module, const char *path, uint64_t file_size,
                   const char *gridname, vdb_value_type type, int fd)
{
    char msg[1024] = "";
    vdb_buffer b = {NULL, 0};
    const haze_openvdb_api *api = NULL;
    hz_status st = HZ_ERROR;
    if (setenv("HAZE_OPENVDB_MODULE", module, 1) == 0 &&
        vdb_module_get(&api, msg, sizeof msg) == HZ_OK)
        st = api->load_grid(path, file_size, gridname, type, &b, msg, sizeof msg);
    else if (!msg[0])
        snprintf(msg, sizeof msg, "%s: cannot load the OpenVDB module %s", path, module);
    reply_header h = {st == HZ_OK, st == HZ_OK ? (uint64_t)b.size : (uint64_t)strlen(msg)};
    bool sent = write_all(fd, &h, sizeof h) && write_all(fd, st == HZ_OK ? b.data : msg, h.length);
    vdb_buffer_free(&b);
    return sent ? 0 : 1;
}

/* Starts the reader with its stdout on `fd_out` and its stderr on /dev/null
 * (what the libraries print is not haze's one line). */
static int spawn_reader(const char *reader, char *const argv[], int fd_out, pid_t *pid)
{
    posix_spawn_file_actions_t fa;
    int e = posix_spawn_file_actions_init(&fa);
    if (e != 0)
        return e;
    e = posix_spawn_file_actions_adddup2(&fa, fd_out, STDOUT_FILENO);
    if (e == 0)
        e = posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    if (e == 0)
        e = posix_spawn(pid, reader, &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    return e;
}

hz_status vdb_module_load_grid_isolated(const char *path, uint64_t file_size,
                                        const char *gridname, vdb_value_type type,
                                        vdb_buffer *out, char *err, size_t err_size)
{
    *out = (vdb_buffer){NULL, 0};
    const char *module = vdb_module_path();
    if (!module) {
        const haze_openvdb_api *api;
        return vdb_module_get(&api, err, err_size);
    }
    char reader[4096], size_arg[32], type_arg[8];
    vdb_reader_path(reader, sizeof reader);
    snprintf(size_arg, sizeof size_arg, "%" PRIu64, file_size);
    snprintf(type_arg, sizeof type_arg, "%d", (int)type);
    char *argv[] = {reader, (char *)module, (char *)path, size_arg, (char *)gridname, type_arg,
                    NULL};
    int fds[2];
    if (pipe(fds) != 0) {
        snprintf(err, err_size, "%s: cannot start the OpenVDB reader: %s", path, strerror(errno));
        return HZ_ERROR;
    }
    fcntl(fds[0], F_SETFD, FD_CLOEXEC);
    pid_t pid;
    int e = spawn_reader(reader, argv, fds[1], &pid);
    close(fds[1]);
    if (e != 0) {
        close(fds[0]);
        snprintf(err, err_size, "%s: cannot start the OpenVDB reader %s: %s", path, reader,
                 strerror(e));
        return HZ_ERROR;
    }
    reply_header h;
    bool got = read_all(fds[0], &h, sizeof h);
    void *data = NULL;
    bool oom = false;
    if (got && h.ok) {
        /* NanoVDB wants 32-byte alignment; aligned_alloc wants a multiple. */
        size_t n = (size_t)h.length;
        data = n > 0 && n <= SIZE_MAX - 31 ? aligned_alloc(32, (n + 31) / 32 * 32) : NULL;
        oom = !data;
        got = data && read_all(fds[0], data, n);
    } else if (got) {
        char msg[1024];
        size_t n = h.length < sizeof msg - 1 ? (size_t)h.length : sizeof msg - 1;
        got = read_all(fds[0], msg, n);
        msg[got ? n : 0] = '\0';
        snprintf(err, err_size, "%s", msg);
    }
    close(fds[0]);
    if (oom)
        kill(pid, SIGKILL);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (oom) {
        snprintf(err, err_size, "%s: out of memory for a grid of %" PRIu64 " bytes", path,
                 h.length);
        return HZ_ERROR;
    }
    /* A complete reply stands, whatever the reader did after sending it. */
    if (!got) {
        free(data);
        if (WIFSIGNALED(status))
            snprintf(err, err_size,
                     "%s: OpenVDB failed reading grid \"%s\" (its reader was killed by signal "
                     "%d, %s; out of memory?)",
                     path, gridname, WTERMSIG(status), strsignal(WTERMSIG(status)));
        else
            snprintf(err, err_size,
                     "%s: OpenVDB failed reading grid \"%s\" (its reader, %s, exited with "
                     "status %d without a result)",
                     path, gridname, reader, WIFEXITED(status) ? WEXITSTATUS(status) : -1);
        return HZ_ERROR;
    }
    if (!h.ok)
        return HZ_ERROR;
    out->data = data;
    out->size = (size_t)h.length;
    return HZ_OK;
}
