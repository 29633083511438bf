/* The fuzzers' input as a file: an anonymous in-memory file (memfd) holding
 * the bytes, read back through /proc/self/fd/N by loaders that take a path.
 * Nothing touches the disk and concurrent fuzzing processes cannot collide. */
#ifndef HAZE_FUZZ_MEMFD_H
#define HAZE_FUZZ_MEMFD_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

/* Returns the descriptor (close it when done) and fills path; aborts on
 * failure (a harness problem, not a finding). */
static inline int fuzz_memfd(const char *name, const uint8_t *data, size_t size, char *path,
                             size_t path_size)
{
    int fd = memfd_create(name, MFD_CLOEXEC);
    if (fd < 0) {
        perror("fuzz: memfd_create");
        abort();
    }
    for (size_t done = 0; done < size;) {
        ssize_t n = write(fd, data + done, size - done);
        if (n <= 0) {
            perror("fuzz: write");
            abort();
        }
        done += (size_t)n;
    }
    snprintf(path, path_size, "/proc/self/fd/%d", fd);
    return fd;
}

#endif
