/* Helpers for tests that run the haze executable. */
#ifndef HAZE_TESTS_CLI_UTIL_H
#define HAZE_TESTS_CLI_UTIL_H


#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "film/exr.h"

/* 1 in a build with AddressSanitizer (gcc or clang): tests of timing or
 * resource limits adapt to it. */
#if defined(__SANITIZE_ADDRESS__)
#define UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UNDER_ASAN 1
#endif
#endif
#ifndef UNDER_ASAN
#define UNDER_ASAN 0
#endif

/* Runs the shell command `cmd`, captures what it prints into out (if not
 * NULL) and returns the exit status (-1 if it did not exit normally). */
static inline int run_captured(const char *cmd, char *out, size_t out_size)
{
    FILE *p = popen(cmd, "r");
    if (!p)
        return -1;
    size_t n = 0;
    char buf[4096];
    size_t got;
    while ((got = fread(buf, 1, sizeof buf, p)) > 0) {
        if (out && n + 1 < out_size) {
            size_t take = got < out_size - n - 1 ? got : out_size - n - 1;
            memcpy(out + n, buf, take);
            n += take;
        }
    }
    if (out && out_size)
        out[n] = '\0';
    int status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* Runs `haze ARGS` (a shell fragment), captures stdout+stderr into out (if not
 * NULL) and returns the exit status (-1 if it did not exit normally). */
static inline int run_haze(const char *args, char *out, size_t out_size)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "'%s' %s 2>&1", HAZE_BIN, args);
    return run_captured(cmd, out, out_size);
}

/* run_haze for a command that might hang (reading a FIFO): killed after
 * `seconds`, when the status is timeout(1)'s 124 (or 137). */
static inline int run_haze_within(int seconds, const char *args, char *out, size_t out_size)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "timeout -k 2 %d '%s' %s 2>&1", seconds, HAZE_BIN, args);
    return run_captured(cmd, out, out_size);
}

static inline void write_text_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f)
        abort();
    fputs(text, f);
    fclose(f);
}

/* Reads a whole file; returns malloc'd bytes (caller frees) or NULL. */
static inline unsigned char *read_whole_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc(n > 0 ? (size_t)n : 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return buf;
}

/* Whether two files hold the same bytes (false if either cannot be read). */
static inline bool files_equal(const char *a, const char *b)
{
    size_t na = 0, nb = 0;
    unsigned char *x = read_whole_file(a, &na), *y = read_whole_file(b, &nb);
    bool same = x && y && na == nb && memcmp(x, y, na) == 0;
    free(x);
    free(y);
    return same;
}

/* Number of files in `dir` whose name contains ".tmp-" (leftovers of atomic
 * writes); -1 when `dir` cannot be read. */
static inline int count_temporaries_in(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;)
        n += strstr(e->d_name, ".tmp-") != NULL;
    closedir(d);
    return n;
}

/* The pixels of an EXR (every channel's floats, in order) as one buffer, or
 * NULL when it cannot be read: for comparing renders of different scene
 * files, whose headers differ by their "haze:render" fingerprint. */
static inline unsigned char *read_exr_pixels(const char *path, size_t *size)
{
    exr_image img;
    hz_error err;
    if (exr_read(path, &img, &err) != HZ_OK)
        return NULL;
    size_t per = (size_t)img.width * (size_t)img.height * sizeof(float);
    unsigned char *out = malloc(per * (size_t)(img.channel_count ? img.channel_count : 1));
    for (int c = 0; out && c < img.channel_count; ++c)
        memcpy(out + per * (size_t)c, img.channels[c].pixels, per);
    *size = per * (size_t)img.channel_count;
    exr_image_free(&img);
    return out;
}

/* Same channels and pixels, bit for bit (headers aside). */
static inline bool exr_pixels_equal(const char *a, const char *b)
{
    size_t na = 0, nb = 0;
    unsigned char *pa = read_exr_pixels(a, &na), *pb = read_exr_pixels(b, &nb);
    bool same = pa && pb && na == nb && memcmp(pa, pb, na) == 0;
    free(pa);
    free(pb);
    return same;
}

/* The value of header attribute `name`, or NULL. */
static inline const char *exr_attribute(const exr_image *img, const char *name)
{
    for (int a = 0; a < img->attribute_count; a++)
        if (strcmp(img->attribute_names[a], name) == 0)
            return img->attribute_values[a];
    return NULL;
}

/* Whether EXRs a and b have the same value of attribute `name` (both
 * present). */
static inline bool exr_attributes_equal(const char *a, const char *b, const char *name)
{
    exr_image ia, ib;
    hz_error err;
    if (exr_read(a, &ia, &err) != HZ_OK)
        return false;
    if (exr_read(b, &ib, &err) != HZ_OK) {
        exr_image_free(&ia);
        return false;
    }
    const char *va = exr_attribute(&ia, name), *vb = exr_attribute(&ib, name);
    bool same = va && vb && strcmp(va, vb) == 0;
    exr_image_free(&ia);
    exr_image_free(&ib);
    return same;
}

#endif
