/* Reading a .vdb grid in a separate process (see vdb_isolated.h): the
 * renderer's side (posix_spawn, the pipe, the reply) and the reader's. */
#define _GNU_SOURCE /* memfd_create */
#include "media/vdb_isolated.h"

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
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "media/vdb_module.h"

extern char **environ;

/* What the reader sends first: its outcome and the length of what follows
 * (the grid's buffer, or the error message). */
typedef struct {
    uint64_t ok; /* 64 bits: no padding bytes go down the pipe */
    uint64_t length;
} reply_header;

static void close_all(const int *fds, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (fds[i] >= 0)
            close(fds[i]);
}

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

/* Reply statuses. REPLY_IN_FILE: the grid (length bytes) is in the
 * request's memory file, not in the pipe. */
enum { REPLY_OK = 0, REPLY_ERROR = 1, REPLY_ABSENT = 2, REPLY_IN_FILE = 3 };

int vdb_reader_run(const char *module, const char *path, uint64_t file_size,
                   const vdb_grid_request *req, size_t n, const int *memfds, int fd)
{
    char msg[1024] = "";
    const haze_openvdb_api *api = NULL;
    bool loaded = setenv("HAZE_OPENVDB_MODULE", module, 1) == 0 &&
                  vdb_module_get(&api, msg, sizeof msg) == HZ_OK;
    for (size_t i = 0; i < n; ++i) {
        vdb_buffer b = {NULL, 0, NULL, 0};
        hz_status st = loaded ? api->load_grid(path, file_size, req[i].name, req[i].type,
                                               memfds[i], &b, msg, sizeof msg)
                              : HZ_ERROR;
        uint64_t status = st == HZ_OK && b.mapping                            ? REPLY_IN_FILE
                          : st == HZ_OK                                        ? REPLY_OK
                          : req[i].optional && vdb_error_is_missing_grid(msg) ? REPLY_ABSENT
                                                                               : REPLY_ERROR;
        reply_header h = {status, status == REPLY_OK || status == REPLY_IN_FILE ? (uint64_t)b.size
                                  : status == REPLY_ERROR                       ? (uint64_t)strlen(msg)
                                                                                : 0};
        bool bytes = status == REPLY_OK || status == REPLY_ERROR;
        bool sent = write_all(fd, &h, sizeof h) &&
                    (!bytes || h.length == 0 ||
                     write_all(fd, status == REPLY_OK ? b.data : msg, h.length));
        vdb_buffer_free(&b);
        if (!sent)
            return 1;
        if (status == REPLY_ERROR)
            return 0;
    }
    return 0;
}

/* Starts the reader with its stdout on `fd_out`, its stderr on /dev/null
 * (what the libraries print is not haze's one line) and memory file i (when
 * memfds[i] >= 0) on descriptor VDB_READER_MEMFD + i. */
static int spawn_reader(const char *reader, char *const argv[], int fd_out, const int *memfds,
                        size_t n, pid_t *pid)
{
    posix_spawn_file_actions_t fa;
    int e = posix_spawn_file_actions_init(&fa);
    if (e != 0)
        return e;
    e = posix_spawn_file_actions_adddup2(&fa, fd_out, STDOUT_FILENO);
    if (e == 0)
        e = posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    for (size_t i = 0; i < n && e == 0; ++i)
        if (memfds[i] >= 0)
            e = posix_spawn_file_actions_adddup2(&fa, memfds[i], VDB_READER_MEMFD + (int)i);
    if (e == 0)
        e = posix_spawn(pid, reader, &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    return e;
}

/* Maps memory file `memfd`, which holds a grid of `length` bytes: false when
 * it does not. */
static bool map_memfd(int memfd, uint64_t length, vdb_buffer *out)
{
    struct stat st;
    if (memfd < 0) {
        errno = EBADF; /* a reply about a memory file haze did not pass */
        return false;
    }
    if (fstat(memfd, &st) != 0)
        return false;
    if (st.st_size <= 0 || (uint64_t)st.st_size < length || length == 0 ||
        (uint64_t)st.st_size > SIZE_MAX) {
        errno = EINVAL; /* the reader's reply does not fit the file: say so, not a stale errno */
        return false;
    }
    void *m = mmap(NULL, (size_t)st.st_size, PROT_READ | PROT_WRITE, MAP_SHARED, memfd, 0);
    if (m == MAP_FAILED)
        return false;
    *out = (vdb_buffer){m, (size_t)length, m, (size_t)st.st_size};
    return true;
}

/* Reads one reply into outs/present (or err); false when the pipe ended
 * early. *ok tells whether the request succeeded (a grid or an absence).
 * memfd: the request's memory file (-1: none). */
static bool read_reply(int fd, int memfd, const char *path, vdb_buffer *out, int *present,
                       bool *ok, bool *oom, char *err, size_t err_size)
{
    reply_header h;
    *ok = false;
    if (!read_all(fd, &h, sizeof h))
        return false;
    if (h.ok == REPLY_ABSENT) {
        *present = 0;
        *ok = true;
        return true;
    }
    if (h.ok == REPLY_IN_FILE) {
        if (!map_memfd(memfd, h.length, out)) {
            snprintf(err, err_size, "%s: cannot map the grid the OpenVDB reader made (%s)", path,
                     strerror(errno));
            return true;
        }
        *present = 1;
        *ok = true;
        return true;
    }
    if (h.ok == REPLY_OK) {
        /* NanoVDB wants 32-byte alignment; aligned_alloc wants a multiple. */
        size_t n = (size_t)h.length;
        void *data = n > 0 && n <= SIZE_MAX - 31 ? aligned_alloc(32, (n + 31) / 32 * 32) : NULL;
        if (!data) {
            *oom = true;
            snprintf(err, err_size, "%s: out of memory for a grid of %" PRIu64 " bytes", path,
                     h.length);
            return true;
        }
        if (!read_all(fd, data, n)) {
            free(data);
            return false;
        }
        *out = (vdb_buffer){data, n, NULL, 0};
        *present = 1;
        *ok = true;
        return true;
    }
    if (h.ok != REPLY_ERROR) {
        /* Not a reply: something else wrote into the pipe. */
        snprintf(err, err_size, "%s: the OpenVDB reader's reply is garbled", path);
        return true;
    }
    char msg[1024];
    size_t n = h.length < sizeof msg - 1 ? (size_t)h.length : sizeof msg - 1;
    if (!read_all(fd, msg, n))
        return false;
    msg[n] = '\0';
    snprintf(err, err_size, "%s", msg);
    return true;
}

hz_status vdb_module_load_grid_isolated(const char *path, uint64_t file_size,
                                        const vdb_grid_request *req, size_t n, vdb_buffer *outs,
                                        int *present, size_t *failed, char *err,
                                        size_t err_size)
{
    enum { MAX_REQUESTS = VDB_MAX_GRID_REQUESTS };
    *failed = 0;
    for (size_t i = 0; i < n; ++i) {
        outs[i] = (vdb_buffer){NULL, 0, NULL, 0};
        present[i] = 0;
    }
    char module[4096];
    if (n > MAX_REQUESTS) {
        snprintf(err, err_size, "%s: too many grids asked for at once", path);
        return HZ_ERROR;
    }
    if (vdb_module_locate(module, sizeof module, err, err_size) != HZ_OK)
        return HZ_ERROR;
    char reader[4096], size_arg[32], count_arg[16], type_arg[MAX_REQUESTS][8];
    vdb_reader_path(reader, sizeof reader);
    snprintf(size_arg, sizeof size_arg, "%" PRIu64, file_size);
    snprintf(count_arg, sizeof count_arg, "%zu", n);
    char *argv[5 + 2 * MAX_REQUESTS + 1]; /* reader module file size n (name type)... */
    size_t a = 0;
    argv[a++] = reader;
    argv[a++] = module;
    argv[a++] = (char *)path;
    argv[a++] = size_arg;
    argv[a++] = count_arg;
    /* Each grid is built in a memory file that both processes map: no copy
     * through the pipe, and no second copy of the grid in memory while the
     * reader still holds its own (the pipe carries it where memfd_create
     * fails). Above the descriptors the reader gets them on, so that moving
     * one there cannot overwrite another. */
    int memfds[MAX_REQUESTS];
    for (size_t i = 0; i < n; ++i) {
        int m = memfd_create("haze-vdb-grid", MFD_CLOEXEC);
        memfds[i] = m >= 0 ? fcntl(m, F_DUPFD_CLOEXEC, VDB_READER_MEMFD + MAX_REQUESTS) : -1;
        if (m >= 0)
            close(m);
    }
    for (size_t i = 0; i < n; ++i) {
        snprintf(type_arg[i], sizeof type_arg[i], "%d%d%d", (int)req[i].type,
                 req[i].optional != 0, memfds[i] >= 0);
        argv[a++] = (char *)req[i].name;
        argv[a++] = type_arg[i];
    }
    argv[a] = NULL;
    int fds[2];
    if (pipe(fds) != 0) {
        snprintf(err, err_size, "%s: cannot start the OpenVDB reader: %s", path, strerror(errno));
        close_all(memfds, n);
        return HZ_ERROR;
    }
    fcntl(fds[0], F_SETFD, FD_CLOEXEC);
    pid_t pid;
    int e = spawn_reader(reader, argv, fds[1], memfds, n, &pid);
    close(fds[1]);
    if (e != 0) {
        close(fds[0]);
        close_all(memfds, n);
        snprintf(err, err_size, "%s: cannot start the OpenVDB reader %s: %s", path, reader,
                 strerror(e));
        return HZ_ERROR;
    }
    bool complete = true, ok = true, oom = false;
    size_t i = 0;
    for (; i < n && ok && complete; ++i)
        complete =
            read_reply(fds[0], memfds[i], path, &outs[i], &present[i], &ok, &oom, err, err_size);
    close(fds[0]);
    close_all(memfds, n); /* the mappings keep what they map */
    if (oom)
        kill(pid, SIGKILL);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (complete && ok)
        return HZ_OK; /* every reply stands, whatever the reader did after them */
    *failed = i > 0 ? i - 1 : 0;
    for (size_t k = 0; k < n; ++k)
        vdb_buffer_free(&outs[k]);
    if (!complete) {
        if (WIFSIGNALED(status))
            snprintf(err, err_size,
                     "%s: OpenVDB failed reading grid \"%s\" (its reader was killed by signal "
                     "%d, %s; out of memory?)",
                     path, req[*failed].name, WTERMSIG(status), strsignal(WTERMSIG(status)));
        else
            snprintf(err, err_size,
                     "%s: OpenVDB failed reading grid \"%s\" (its reader, %s, exited with "
                     "status %d without a result)",
                     path, req[*failed].name, reader,
                     WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    }
    return HZ_ERROR;
}
