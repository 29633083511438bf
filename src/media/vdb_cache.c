#define _POSIX_C_SOURCE 200809L
#include "media/vdb_cache.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "media/vdb_module.h"

/* Bump when what an entry holds changes (the converter's output, its layout). */
#define VDB_CACHE_FORMAT 1

static bool cache_dir(char *out, size_t size)
{
    const char *dir = getenv("HAZE_CACHE_DIR");
    int n;
    if (dir)
        n = snprintf(out, size, "%s", dir);
    else if ((dir = getenv("XDG_CACHE_HOME")) && dir[0] == '/')
        n = snprintf(out, size, "%s/haze", dir);
    else if ((dir = getenv("HOME")) && dir[0] == '/')
        n = snprintf(out, size, "%s/.cache/haze", dir);
    else
        return false;
    return n > 0 && (size_t)n < size;
}

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

bool vdb_cache_open(vdb_cache *c, const char *path, uint64_t file_size)
{
    memset(c, 0, sizeof *c);
    if (!cache_dir(c->dir, sizeof c->dir) || !c->dir[0])
        return false;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return false;
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

bool vdb_cache_prepare(const vdb_cache *c)
{
    char path[sizeof c->dir];
    memcpy(path, c->dir, sizeof path);
    for (char *p = path + 1;; ++p) {
        bool end = *p == '\0';
        if (*p == '/' || end) {
            *p = '\0';
            if (mkdir(path, 0700) != 0 && errno != EEXIST)
                return false;
            if (end)
                break;
            *p = '/';
        }
    }
    struct stat st;
    return stat(c->dir, &st) == 0 && S_ISDIR(st.st_mode);
}
