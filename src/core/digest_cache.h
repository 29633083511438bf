/* Digests of large files' bytes, kept between runs in the cache folder
 * (core/cache_dir.h) under the file's identity: a second render of the same
 * 1 GB volume does not read it through once more to fingerprint it.
 *
 * An entry is keyed by the file's device and inode and holds what fstat
 * says of it (size, modification and status-change times, to the
 * nanosecond) with the digest; it counts only while all of them still
 * match. Every write to a file moves its status-change time, so a changed
 * file misses. A file changed within DIGEST_CACHE_SETTLE_MS before its
 * digest was read is not kept: timestamps come from a coarse clock, and a
 * second write in the same tick would keep the same times (on a file
 * system that keeps whole seconds, DIGEST_CACHE_SETTLE_COARSE_MS). Entries are
 * written to a temporary file and renamed (a reader sees a whole entry or
 * none); one that does not parse is a miss. Each kind of digest (its
 * function and what it covers) has its own entries. */
#ifndef HAZE_CORE_DIGEST_CACHE_H
#define HAZE_CORE_DIGEST_CACHE_H

#include <stdbool.h>
#include <stdint.h>

#define DIGEST_CACHE_SETTLE_MS 100
/* ... or, for a file whose times have no nanoseconds (a file system that
 * keeps whole seconds), this. */
#define DIGEST_CACHE_SETTLE_COARSE_MS 2100

typedef struct {
    uint64_t dev, ino, size;
    int64_t mtime_s, mtime_ns, ctime_s, ctime_ns;
    int64_t read_s, read_ns; /* when the digest's reading began (CLOCK_REALTIME) */
} file_identity;

typedef struct {
    uint64_t v[2];
} file_digest;

/* The identity of the open file `fd`, and now as the start of its reading;
 * false when fstat fails. */
bool file_identity_of(int fd, file_identity *out);

/* The digest of `kind` (letters, digits, '-') kept for the file, if any. */
bool digest_cache_get(const char *kind, const file_identity *id, file_digest *out);
/* Keeps `d` for the file, when the cache folder exists or can be made and
 * the file had settled when its reading began; quietly nothing otherwise
 * (the next run reads the file again). */
void digest_cache_put(const char *kind, const file_identity *id, const file_digest *d);

#endif
