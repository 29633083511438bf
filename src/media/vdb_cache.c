#define _POSIX_C_SOURCE 200809L
#include "media/vdb_cache.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/cache_dir.h"
#include "core/digest_cache.h"
#include "media/vdb_module.h"

/* Bump when what an entry holds changes (the converter's output, its layout). */
#define VDB_CACHE_FORMAT 1
/* The digest cache's kind of the bytes_key of a .vdb file. */
#define VDB_CACHE_DIGEST "vdb-bytes-128"

/* Two 64-bit lanes over 8-byte words: x = (x ^ w) * p, rotated; the lanes use
 * different primes and rotations. Not cryptographic: the cache trusts its
 * own directory, and a collision needs two files of one size. */
typedef struct {
    uint64_t a, b;
} hash128;

static uint64_t rotl(uint64_t x, int r) { return x << r | x >> (64 - r); }

static void mix(hash128 *h, uint64_t w)
{
    h->a = rotl((h->a ^ w) * 0x9E3779B97F4A7C15ull, 31);
    h->b = rotl((h->b ^ w) * 0xC2B2AE3D27D4EB4Full, 27) + h->a;
}

static void mix_bytes(hash128 *h, const unsigned char *p, size_t n)
{
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        memcpy(&w, p + i, 8);
        mix(h, w);
    }
    uint64_t tail = 0;
    memcpy(&tail, p + i, n - i);
    mix(h, tail ^ ((uint64_t)(n - i) << 56));
}

static void mix_string(hash128 *h, const char *s)
{
    mix_bytes(h, (const unsigned char *)s, strlen(s));
    mix(h, strlen(s));
}

/* The hash of the file's bytes and size: from the digest cache when it
 * has the file as it is, else read through (and kept there). */
static bool bytes_key(const char *path, uint64_t file_size, hash128 *out)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return false;
    file_identity id;
    bool known = file_identity_of(fd, &id) && id.size == file_size;
    file_digest d;
    if (known && digest_cache_get(VDB_CACHE_DIGEST, &id, &d)) {
        close(fd);
        *out = (hash128){d.v[0], d.v[1]};
        return true;
    }
    hash128 h = {0x243F6A8885A308D3ull, 0x13198A2E03707344ull};
    enum { CHUNK = 1 << 20 };
    unsigned char *buf = malloc(CHUNK);
    uint64_t total = 0;
    bool ok = buf != NULL;
    while (ok) {
        ssize_t got = read(fd, buf, CHUNK);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0)
            ok = false;
        if (got <= 0)
            break;
        /* Whole words of each chunk (CHUNK is a multiple of 8), the last
         * chunk's tail too. */
        mix_bytes(&h, buf, (size_t)got);
        total += (uint64_t)got;
    }
    free(buf);
    close(fd);
    if (!ok || total != file_size)
        return false; /* the file changed under us: no cache this time */
    mix(&h, total);
    if (known)
        digest_cache_put(VDB_CACHE_DIGEST, &id, &(file_digest){{h.a, h.b}});
    *out = h;
    return true;
}

bool vdb_cache_open(vdb_cache *c, const char *path, uint64_t file_size)
{
    memset(c, 0, sizeof *c);
    hash128 h;
    if (!hz_cache_dir(c->dir, sizeof c->dir) || !bytes_key(path, file_size, &h))
        return false;
    mix(&h, VDB_CACHE_FORMAT);
    mix(&h, HAZE_OPENVDB_ABI);
    /* The converter that would run: its path, size and time, so a rebuilt or
     * another module ($HAZE_OPENVDB_MODULE) never sees the old entries. */
    char module[4096], why[256];
    struct stat ms;
    if (vdb_module_locate(module, sizeof module, why, sizeof why) != HZ_OK ||
        stat(module, &ms) != 0)
        return false;
    mix_string(&h, module);
    mix(&h, (uint64_t)ms.st_size);
    mix(&h, (uint64_t)ms.st_mtim.tv_sec);
    mix(&h, (uint64_t)ms.st_mtim.tv_nsec);
    c->key[0] = h.a;
    c->key[1] = h.b;
    return true;
}

bool vdb_cache_entry(const vdb_cache *c, const char *name, vdb_value_type type, bool absent,
                     char *out, size_t size)
{
    hash128 h = {c->key[0], c->key[1]};
    mix_string(&h, name);
    mix(&h, (uint64_t)type);
    int n = snprintf(out, size, "%s/%016llx%016llx.%s", c->dir, (unsigned long long)h.a,
                     (unsigned long long)h.b, absent ? "absent" : "nvdb");
    return n > 0 && (size_t)n < size;
}

bool vdb_cache_prepare(const vdb_cache *c) { return hz_cache_dir_prepare(c->dir); }
