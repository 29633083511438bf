#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

#include "film/exr.h"

static void tmp_path(char *buf, size_t n, const char *name)
{
    snprintf(buf, n, "%s/film_exr_%s", HAZE_TMP, name);
}

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return buf;
}

static void spit(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    fclose(f);
}

/* No "<base>.tmp-*" may be left in HAZE_TMP. */
static void assert_no_temp_files(const char *base)
{
    char prefix[300];
    snprintf(prefix, sizeof prefix, "%s.tmp-", strrchr(base, '/') + 1);
    DIR *d = opendir(HAZE_TMP);
    assert_non_null(d);
    struct dirent *e;
    while ((e = readdir(d)))
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0)
            fail_msg("temporary file left behind: %s", e->d_name);
    closedir(d);
}

static uint32_t lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s;
}

/* Image with channel names given in non-alphabetical order, a data window
 * offset from the display window and several ZIP chunks (16 lines each). */
static void make_image(exr_image *img, bool half)
{
    static const char *names[] = {"Z", "R", "Variance.R", "B", "A", "G"};
    assert_int_equal(exr_image_alloc(img, 13, 37, 6, NULL), HZ_OK);
    img->data_x0 = 5;
    img->data_y0 = 7;
    img->display_width = 40;
    img->display_height = 50;
    uint32_t s = 1234;
    for (int c = 0; c < 6; c++) {
        snprintf(img->channels[c].name, sizeof img->channels[c].name, "%s", names[c]);
        img->channels[c].half = half && c != 0; /* Z stays float, like the film */
        for (int i = 0; i < 13 * 37; i++) {
            if (img->channels[c].half) /* exactly representable halves, sign and subnormals included */
                img->channels[c].pixels[i] = exr_half_to_float((uint16_t)(lcg(&s) % 0x7c00u) |
                                                               (uint16_t)(i & 1 ? 0x8000u : 0));
            else
                img->channels[c].pixels[i] = (float)((int32_t)lcg(&s)) * 1e-6f;
        }
    }
    assert_int_equal(exr_image_add_attribute(img, "software", "haze test", NULL), HZ_OK);
    assert_int_equal(exr_image_add_attribute(img, "haze.scene", "scenes/fog.pbrt", NULL), HZ_OK);
}

static void assert_same_image(const exr_image *a, const exr_image *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->data_x0, b->data_x0);
    assert_int_equal(a->data_y0, b->data_y0);
    assert_int_equal(a->display_width, b->display_width);
    assert_int_equal(a->display_height, b->display_height);
    assert_int_equal(a->channel_count, b->channel_count);
    for (int c = 0; c < a->channel_count; c++) {
        const exr_channel *cb = exr_find_channel(b, a->channels[c].name);
        assert_non_null(cb);
        assert_int_equal(cb->half, a->channels[c].half);
        assert_memory_equal(cb->pixels, a->channels[c].pixels,
                            sizeof(float) * (size_t)a->width * (size_t)a->height);
    }
    /* The reader returns channels in the file's (alphabetical) order. */
    for (int c = 1; c < b->channel_count; c++)
        assert_true(strcmp(b->channels[c - 1].name, b->channels[c].name) < 0);
    for (int k = 0; k < a->attribute_count; k++) {
        bool found = false;
        for (int j = 0; j < b->attribute_count; j++)
            if (strcmp(a->attribute_names[k], b->attribute_names[j]) == 0) {
                assert_string_equal(a->attribute_values[k], b->attribute_values[j]);
                found = true;
            }
        assert_true(found);
    }
}

static void round_trip(bool half)
{
    char path[512];
    tmp_path(path, sizeof path, half ? "half.exr" : "float.exr");
    exr_image img, back;
    make_image(&img, half);
    hz_error err = {0};
    assert_int_equal(exr_write(path, &img, &err), HZ_OK);
    assert_no_temp_files(path);
    assert_int_equal(exr_read(path, &back, &err), HZ_OK);
    assert_same_image(&img, &back);
    exr_image_free(&img);
    exr_image_free(&back);
}

/* Writes img to `name` in HAZE_TMP and returns the file's bytes (path in `path`). */
static unsigned char *written(exr_image *img, const char *name, char *path, size_t path_size,
                              size_t *len)
{
    hz_error err = {0};
    tmp_path(path, path_size, name);
    if (exr_write(path, img, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_no_temp_files(path);
    unsigned char *bytes = slurp(path, len);
    assert_non_null(bytes);
    return bytes;
}

/* Chunks compressed by several threads: the same bytes as one thread's file
 * (written in order), and the same pixels back; more threads than chunks too. */
static void test_threads_same_file(void **state)
{
    (void)state;
    for (int half = 0; half < 2; half++) {
        char one[512], many[512];
        exr_image img, back;
        make_image(&img, half != 0);
        hz_error err = {0};
        img.threads = 1;
        size_t n1 = 0;
        unsigned char *b1 = written(&img, "threads1.exr", one, sizeof one, &n1);
        for (int threads = 2; threads <= 8; threads += 3) {
            img.threads = threads;
            size_t n2 = 0;
            unsigned char *b2 = written(&img, "threadsN.exr", many, sizeof many, &n2);
            assert_int_equal(n1, n2);
            assert_memory_equal(b1, b2, n1);
            free(b2);
            assert_int_equal(exr_read(many, &back, &err), HZ_OK);
            assert_same_image(&img, &back);
            exr_image_free(&back);
        }
        free(b1);
        exr_image_free(&img);
    }
}

/* exr_image.fill's source: the image whose lines it copies, and how often
 * each line was asked for. */
typedef struct {
    const exr_image *from;
    int asked[64];
} fill_source;

static void fill_from(void *ctx, int y0, int y1, float *const *pixels)
{
    fill_source *src = ctx;
    int w = src->from->width;
    for (int y = y0; y < y1; y++) {
        src->asked[y]++;
        for (int c = 0; c < src->from->channel_count; c++)
            memcpy(pixels[c] + (size_t)(y - y0) * (size_t)w,
                   src->from->channels[c].pixels + (size_t)y * (size_t)w, (size_t)w * sizeof(float));
    }
}

/* Lines made chunk by chunk (exr_image.fill) give the same file as the same
 * values in the channels, with one thread or several, float or half, a last
 * chunk shorter than the others (37 lines, 16 per chunk); each line is
 * asked for once. */
static void test_lines_filled_same_file(void **state)
{
    (void)state;
    for (int half = 0; half < 2; half++) {
        char one[512], filled[512];
        exr_image img, lines;
        make_image(&img, half != 0);
        hz_error err = {0};
        img.threads = 1;
        size_t n1 = 0;
        unsigned char *b1 = written(&img, "pixels.exr", one, sizeof one, &n1);
        assert_int_equal(exr_image_alloc_lines(&lines, img.width, img.height, img.channel_count,
                                               &err),
                         HZ_OK);
        lines.data_x0 = img.data_x0;
        lines.data_y0 = img.data_y0;
        lines.display_width = img.display_width;
        lines.display_height = img.display_height;
        for (int c = 0; c < img.channel_count; c++) {
            assert_null(lines.channels[c].pixels);
            memcpy(lines.channels[c].name, img.channels[c].name, sizeof img.channels[c].name);
            lines.channels[c].half = img.channels[c].half;
        }
        for (int a = 0; a < img.attribute_count; a++)
            assert_int_equal(exr_image_add_attribute(&lines, img.attribute_names[a],
                                                     img.attribute_values[a], &err),
                             HZ_OK);
        for (int threads = 1; threads <= 5; threads += 2) {
            fill_source src = {.from = &img};
            lines.fill = fill_from;
            lines.fill_ctx = &src;
            lines.threads = threads;
            size_t n2 = 0;
            unsigned char *b2 = written(&lines, "filled.exr", filled, sizeof filled, &n2);
            for (int y = 0; y < img.height; y++)
                assert_int_equal(src.asked[y], 1);
            assert_int_equal(n1, n2);
            assert_memory_equal(b1, b2, n1);
            free(b2);
        }
        free(b1);
        exr_image_free(&lines);
        exr_image_free(&img);
    }
}

/* The writer's own ZIP (ISA-L's igzip behind OpenEXR's byte split and
 * predictor) read back by OpenEXRCore's zlib decoder: a smooth image with a
 * black border compresses to a fraction of its bytes and comes back exactly;
 * noise that does not shrink is stored raw and comes back too. */
static void test_zip_chunks_read_back(void **state)
{
    (void)state;
    for (int noise = 0; noise < 2; noise++) {
        char path[512];
        tmp_path(path, sizeof path, noise ? "noise.exr" : "smooth.exr");
        exr_image img, back;
        int w = 301, h = 67; /* five chunks, the last one partial */
        assert_int_equal(exr_image_alloc(&img, w, h, 4, NULL), HZ_OK);
        uint32_t s = 99;
        for (int c = 0; c < 4; c++) {
            snprintf(img.channels[c].name, sizeof img.channels[c].name, "%c", "ABGR"[c]);
            img.channels[c].half = !noise && c == 1;
            for (int y = 0; y < h; y++)
                for (int x = 0; x < w; x++) {
                    float v = x < 40 || y < 5 ? 0.f : (float)(x / 4 + y / 4 + c) / 64.f; /* few mantissa bits */
                    if (noise) { /* random bits (NaNs too: the writer keeps them) */
                        uint32_t bits = lcg(&s) ^ (lcg(&s) >> 16);
                        memcpy(&v, &bits, sizeof v);
                    }
                    if (img.channels[c].half)
                        v = exr_half_to_float(exr_half_from_float(v));
                    img.channels[c].pixels[y * w + x] = v;
                }
        }
        hz_error err = {0};
        assert_int_equal(exr_write(path, &img, &err), HZ_OK);
        struct stat st;
        assert_int_equal(stat(path, &st), 0);
        size_t raw = (size_t)w * (size_t)h * (noise ? 4 * 4 : 3 * 4 + 2);
        if (noise)
            assert_true((size_t)st.st_size > raw); /* stored, plus header and offsets */
        else
            assert_true((size_t)st.st_size < raw / 4);
        assert_int_equal(exr_read(path, &back, &err), HZ_OK);
        assert_same_image(&img, &back);
        exr_image_free(&img);
        exr_image_free(&back);
    }
}

static void test_round_trip_float(void **state)
{
    (void)state;
    round_trip(false);
}

static void test_round_trip_half(void **state)
{
    (void)state;
    round_trip(true);
}

static void test_half_conversion(void **state)
{
    (void)state;
    /* Every half survives half -> float -> half (NaNs stay NaN). */
    for (uint32_t h = 0; h < 65536; h++) {
        float f = exr_half_to_float((uint16_t)h);
        uint16_t back = exr_half_from_float(f);
        if (((h >> 10) & 0x1f) == 0x1f && (h & 0x3ff))
            assert_true(isnan(f) && ((back >> 10) & 0x1f) == 0x1f && (back & 0x3ff));
        else
            assert_int_equal(back, h);
    }
    assert_true(exr_half_to_float(0x3c00) == 1.0f);
    assert_true(exr_half_to_float(0x7bff) == 65504.0f);
    assert_true(exr_half_to_float(0x0001) == 0x1p-24f);
    /* Round to nearest, ties to even. */
    assert_int_equal(exr_half_from_float(1.0f + 0x1p-11f), 0x3c00);          /* tie -> even */
    assert_int_equal(exr_half_from_float(1.0f + 3 * 0x1p-11f), 0x3c02);      /* tie -> even (up) */
    assert_int_equal(exr_half_from_float(1.0f + 0x1p-11f + 0x1p-20f), 0x3c01); /* above tie */
    assert_int_equal(exr_half_from_float(65519.0f), 0x7bff);
    assert_int_equal(exr_half_from_float(65520.0f), 0x7c00);
    assert_int_equal(exr_half_from_float(-1e9f), 0xfc00);
    assert_int_equal(exr_half_from_float(0x1p-25f), 0x0000);                  /* tie -> 0 */
    assert_int_equal(exr_half_from_float(0x1p-25f * 1.5f), 0x0001);
    assert_int_equal(exr_half_from_float(3 * 0x1p-25f), 0x0002);              /* tie -> even */
    assert_int_equal(exr_half_from_float(-0.0f), 0x8000);
    assert_int_equal(exr_half_from_float(INFINITY), 0x7c00);
}

static void test_bad_files(void **state)
{
    (void)state;
    char good[512], bad[512];
    tmp_path(good, sizeof good, "good.exr");
    tmp_path(bad, sizeof bad, "bad.exr");
    exr_image img, back;
    make_image(&img, false);
    hz_error err = {0};
    assert_int_equal(exr_write(good, &img, &err), HZ_OK);
    exr_image_free(&img);
    size_t len = 0;
    unsigned char *bytes = slurp(good, &len);
    assert_non_null(bytes);
    assert_true(len > 400);

    /* Truncations anywhere: inside the magic, the header, the offset table,
     * the pixel data. */
    size_t cuts[] = {0, 3, 20, 100, 300, len / 2, len - 50, len - 1};
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
        spit(bad, bytes, cuts[k]);
        err.message[0] = 0;
        assert_int_equal(exr_read(bad, &back, &err), HZ_ERROR);
        assert_true(strlen(err.message) > 0);
        assert_non_null(strstr(err.message, bad));
        assert_null(strchr(err.message, '\n'));
        assert_null(back.channels);
    }
    /* Garbage pixel data after an intact header. */
    unsigned char *junk = malloc(len);
    assert_non_null(junk);
    memcpy(junk, bytes, len);
    uint32_t s = 99;
    for (size_t i = len / 2; i < len; i++)
        junk[i] = (unsigned char)lcg(&s);
    spit(bad, junk, len);
    assert_int_equal(exr_read(bad, &back, &err), HZ_ERROR);
    /* Pure garbage. */
    for (size_t i = 0; i < len; i++)
        junk[i] = (unsigned char)(lcg(&s) >> 24);
    spit(bad, junk, len);
    assert_int_equal(exr_read(bad, &back, &err), HZ_ERROR);
    free(junk);
    free(bytes);
    /* Missing file. */
    assert_int_equal(exr_read(HAZE_TMP "/no/such/file.exr", &back, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "no/such/file.exr"));
}

static void test_write_missing_directory(void **state)
{
    (void)state;
    exr_image img;
    make_image(&img, false);
    hz_error err = {0};
    const char *path = HAZE_TMP "/film_exr_missing_dir/out.exr";
    assert_int_equal(exr_write(path, &img, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "film_exr_missing_dir"));
    struct stat st;
    assert_int_not_equal(stat(path, &st), 0);
    exr_image_free(&img);
}

static void test_failed_write_keeps_old_file(void **state)
{
    (void)state;
    char path[512];
    tmp_path(path, sizeof path, "atomic.exr");
    exr_image img;
    make_image(&img, false);
    hz_error err = {0};
    assert_int_equal(exr_write(path, &img, &err), HZ_OK);
    size_t len0 = 0, len1 = 0;
    unsigned char *before = slurp(path, &len0);
    assert_non_null(before);

    /* Fails after the temporary file exists: "compression" is a required
     * attribute whose type is not string. */
    assert_int_equal(exr_image_add_attribute(&img, "compression", "none", NULL), HZ_OK);
    img.channels[0].pixels[0] = 42.0f; /* would change the file */
    assert_int_equal(exr_write(path, &img, &err), HZ_ERROR);
    assert_true(strlen(err.message) > 0);
    unsigned char *after = slurp(path, &len1);
    assert_non_null(after);
    assert_int_equal(len0, len1);
    assert_memory_equal(before, after, len0);
    assert_no_temp_files(path);
    free(after);

    /* Fails before writing: invalid image. */
    exr_image empty = {0};
    assert_int_equal(exr_write(path, &empty, &err), HZ_ERROR);
    after = slurp(path, &len1);
    assert_int_equal(len0, len1);
    assert_memory_equal(before, after, len0);
    free(after);
    free(before);
    assert_no_temp_files(path);

    /* Fails at rename: the target is a directory. */
    char dir[512];
    tmp_path(dir, sizeof dir, "is_a_dir.exr");
    mkdir(dir, 0755);
    img.attribute_count = 2; /* drop the bad attribute */
    assert_int_equal(exr_write(dir, &img, &err), HZ_ERROR);
    assert_no_temp_files(dir);
    exr_image_free(&img);
}

static void test_invalid_images(void **state)
{
    (void)state;
    char path[512];
    tmp_path(path, sizeof path, "invalid.exr");
    exr_image img;
    assert_int_equal(exr_image_alloc(&img, 2, 2, 2, NULL), HZ_OK);
    hz_error err = {0};
    /* Unnamed channel. */
    assert_int_equal(exr_write(path, &img, &err), HZ_ERROR);
    snprintf(img.channels[0].name, 64, "R");
    snprintf(img.channels[1].name, 64, "R");
    assert_int_equal(exr_write(path, &img, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "twice"));
    exr_image_free(&img);
    assert_int_equal(exr_image_alloc(&img, 0, 2, 1, &err), HZ_ERROR);
}

/* Writes a 37x21 tiled (16x8 tiles) float "Y" channel with value x + 100 y. */
static int write_tiled(const char *path)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx;
    int part;
    if (exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init)) return 1;
    exr_add_part(ctx, NULL, EXR_STORAGE_TILED, &part);
    exr_initialize_required_attr_simple(ctx, part, 37, 21, EXR_COMPRESSION_ZIP);
    exr_set_tile_descriptor(ctx, part, 16, 8, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN);
    exr_add_channel(ctx, part, "Y", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (exr_write_header(ctx)) return 2;
    float buf[16 * 8];
    exr_encode_pipeline_t enc; int init_done = 0;
    for (int ty = 0; ty < 3; ty++) for (int tx = 0; tx < 3; tx++) {
        exr_chunk_info_t ci;
        if (exr_write_tile_chunk_info(ctx, part, tx, ty, 0, 0, &ci)) return 3;
        for (int y = 0; y < ci.height; y++) for (int x = 0; x < ci.width; x++)
            buf[y * ci.width + x] = (float)(tx * 16 + x + 100 * (ty * 8 + y));
        if (init_done ? exr_encoding_update(ctx, part, &ci, &enc) : exr_encoding_initialize(ctx, part, &ci, &enc)) return 4;
        enc.channels[0].encode_from_ptr = (const uint8_t *)buf;
        enc.channels[0].user_pixel_stride = 4; enc.channels[0].user_line_stride = 4 * ci.width;
        enc.channels[0].user_bytes_per_element = 4; enc.channels[0].user_data_type = EXR_PIXEL_FLOAT;
        if (!init_done) { exr_encoding_choose_default_routines(ctx, part, &enc); init_done = 1; }
        if (exr_encoding_run(ctx, part, &enc)) return 5;
    }
    exr_encoding_destroy(ctx, &enc);
    return exr_finish(&ctx) ? 6 : 0;
}

static void test_read_tiled(void **state)
{
    (void)state;
    char path[512];
    tmp_path(path, sizeof path, "tiled.exr");
    assert_int_equal(write_tiled(path), 0);
    exr_image img;
    hz_error err = {0};
    assert_int_equal(exr_read(path, &img, &err), HZ_OK);
    assert_int_equal(img.width, 37);
    assert_int_equal(img.height, 21);
    assert_string_equal(img.channels[0].name, "Y");
    for (int y = 0; y < 21; y++)
        for (int x = 0; x < 37; x++)
            assert_true(img.channels[0].pixels[y * 37 + x] == (float)(x + 100 * y));
    exr_image_free(&img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_conversion),
        cmocka_unit_test(test_round_trip_float),
        cmocka_unit_test(test_round_trip_half),
        cmocka_unit_test(test_threads_same_file),
        cmocka_unit_test(test_lines_filled_same_file),
        cmocka_unit_test(test_zip_chunks_read_back),
        cmocka_unit_test(test_bad_files),
        cmocka_unit_test(test_write_missing_directory),
        cmocka_unit_test(test_failed_write_keeps_old_file),
        cmocka_unit_test(test_invalid_images),
        cmocka_unit_test(test_read_tiled),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
