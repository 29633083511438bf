/* haze_vdb_reader MODULE FILE FILE_SIZE N (GRID TYPE)...: reads N grids of an
 * OpenVDB file with haze's OpenVDB module and writes them, as NanoVDB buffers,
 * to stdout; TYPE is two or three digits, the value type, whether the grid is
 * optional and whether a memory file for it waits on descriptor
 * VDB_READER_MEMFD + its index (the grid is then built there; see
 * src/media/vdb_isolated.h, vdb_module_load_grid_isolated). Run by haze, not
 * by users. */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "media/vdb_isolated.h"

/* The replies get stdout's pipe on a descriptor of their own, and stdout
 * goes to /dev/null: the libraries print there (OpenVDB's log4cplus
 * warnings, with their colour codes), which must not land among the replies'
 * bytes. Returns the replies' descriptor, -1 on failure. */
static int take_stdout(void)
{
    int replies = dup(STDOUT_FILENO);
    int null = open("/dev/null", O_WRONLY | O_CLOEXEC);
    bool ok = replies >= 0 && null >= 0 && dup2(null, STDOUT_FILENO) >= 0;
    if (null >= 0)
        close(null);
    if (!ok && replies >= 0)
        close(replies);
    return ok ? replies : -1;
}

int main(int argc, char **argv)
{
    enum { MAX_REQUESTS = VDB_MAX_GRID_REQUESTS };
    int n = argc > 4 ? atoi(argv[4]) : -1;
    if (n < 1 || n > MAX_REQUESTS || argc != 5 + 2 * n) {
        fprintf(stderr, "usage: %s MODULE FILE FILE_SIZE N (GRID TYPE)... (run by haze)\n",
                argv[0]);
        return 2;
    }
    vdb_grid_request req[MAX_REQUESTS];
    int memfds[MAX_REQUESTS];
    for (int i = 0; i < n; ++i) {
        const char *t = argv[6 + 2 * i];
        req[i].name = argv[5 + 2 * i];
        req[i].type = t[0] == '1' ? VDB_VEC3 : VDB_FLOAT;
        req[i].optional = t[0] && t[1] == '1';
        memfds[i] = t[0] && t[1] && t[2] == '1' ? VDB_READER_MEMFD + i : -1;
    }
    int replies = take_stdout();
    if (replies < 0) {
        perror("haze_vdb_reader: stdout");
        return 1;
    }
    return vdb_reader_run(argv[1], argv[2], strtoull(argv[3], NULL, 10), req, (size_t)n, memfds,
                          replies);
}
