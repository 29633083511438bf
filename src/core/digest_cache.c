#define _POSIX_C_SOURCE 200809L
#include "core/digest_cache.h"

#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/cache_dir.h"

/* Bump when an entry's text changes. */
#define DIGEST_CACHE_FORMAT 1

bool file_identity_of(int fd, file_identity *out)
{
    struct stat st;
    struct timespec now;
    if (fstat(fd, &st) != 0 || clock_gettime(CLOCK_REALTIME, &now) != 0)
        return false;
    *out = (file_identity){(uint64_t)st.st_dev,       (uint64_t)st.st_ino,
                           (uint64_t)st.st_size,      (int64_t)st.st_mtim.tv_sec,
                           (int64_t)st.st_mtim.tv_nsec, (int64_t)st.st_ctim.tv_sec,
                           (int64_t)st.st_ctim.tv_nsec, (int64_t)now.tv_sec,
                           (int64_t)now.tv_nsec};
    return true;
}

static bool kind_ok(const char *kind)
{
    size_t n = strlen(kind);
    if (n == 0 || n > 32)
        return false;
    for (size_t i = 0; i < n; ++i) {
        char c = kind[i];
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-'))
            return false;
    }
    return true;
}

/* The entry's path in out[size] (and the folder in dir[dsize] when dir). */
static bool entry_path(const char *kind, const file_identity *id, char *out, size_t size,
                       char *dir, size_t dsize)
{
    char d[4096];
    if (!kind_ok(kind) || !hz_cache_dir(d, sizeof d))
        return false;
    if (dir && snprintf(dir, dsize, "%s", d) >= (int)dsize)
        return false;
    int n = snprintf(out, size, "%s/digest-%s-%" PRIx64 "-%" PRIx64, d, kind, id->dev, id->ino);
    return n > 0 && (size_t)n < size;
}

/* What an entry says of its file, after the format's number. */
static int identity_text(const file_identity *id, char *out, size_t size)
{
    return snprintf(out, size, "%" PRIu64 " %" PRId64 ".%09" PRId64 " %" PRId64 ".%09" PRId64,
                    id->size, id->mtime_s, id->mtime_ns, id->ctime_s, id->ctime_ns);
}

bool digest_cache_get(const char *kind, const file_identity *id, file_digest *out)
{
    char path[4352];
    if (!entry_path(kind, id, path, sizeof path, NULL, 0))
        return false;
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    char line[256] = "", want[160];
    bool got = fgets(line, sizeof line, f) != NULL;
    fclose(f);
    int n = snprintf(want, sizeof want, "haze-digest %d ", DIGEST_CACHE_FORMAT);
    n += identity_text(id, want + n, sizeof want - (size_t)n);
    if (!got || n <= 0 || (size_t)n >= sizeof want || strncmp(line, want, (size_t)n) != 0)
        return false;
    uint64_t a, b;
    char end;
    if (sscanf(line + n, " %16" SCNx64 " %16" SCNx64 "%c", &a, &b, &end) != 3 || end != '\n')
        return false;
    out->v[0] = a;
    out->v[1] = b;
    return true;
}

void digest_cache_put(const char *kind, const file_identity *id, const file_digest *d)
{
    /* Settled: its last change at least DIGEST_CACHE_SETTLE_MS before the
     * reading began (so a write in the clock tick of that change had
     * happened before it too). */
    int64_t since_ms = (id->read_s - id->ctime_s) * 1000 + (id->read_ns - id->ctime_ns) / 1000000;
    int64_t since_m_ms =
        (id->read_s - id->mtime_s) * 1000 + (id->read_ns - id->mtime_ns) / 1000000;
    /* Times without nanoseconds come from a file system that keeps whole
     * seconds (FAT keeps two): wait that long. */
    int64_t settle = id->ctime_ns == 0 && id->mtime_ns == 0 ? DIGEST_CACHE_SETTLE_COARSE_MS
                                                              : DIGEST_CACHE_SETTLE_MS;
    if (since_ms < settle || since_m_ms < settle)
        return;
    char path[4352], dir[4096], tmp[4400];
    if (!entry_path(kind, id, path, sizeof path, dir, sizeof dir) || !hz_cache_dir_prepare(dir))
        return;
    int n = snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
    if (n <= 0 || (size_t)n >= sizeof tmp)
        return;
    FILE *f = fopen(tmp, "w");
    if (!f)
        return;
    char ident[160];
    identity_text(id, ident, sizeof ident);
    bool ok = fprintf(f, "haze-digest %d %s %016" PRIx64 " %016" PRIx64 "\n", DIGEST_CACHE_FORMAT,
                      ident, d->v[0], d->v[1]) > 0;
    ok = fclose(f) == 0 && ok;
    if (!ok || rename(tmp, path) != 0)
        unlink(tmp);
}
