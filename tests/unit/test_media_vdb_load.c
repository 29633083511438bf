/* media/vdb_load: the OpenVDB/NanoVDB bridge. Bad input gives one clear line of
 * error and never a crash; .nvdb and .vdb load the same grid; listing reports
 * what is in a file. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "media/grid.h"
#include "media/vdb_load.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

static void assert_contains(const char *msg, const char *needle)
{
    if (!strstr(msg, needle))
        fail_msg("error \"%s\" does not mention \"%s\"", msg, needle);
}

static void assert_one_line(const char *msg)
{
    if (msg[0] == '\0' || strchr(msg, '\n'))
        fail_msg("error \"%s\" is not one non-empty line", msg);
}

/* Loads and expects failure; returns the message (static storage). */
static const char *load_error(const char *path, const char *gridname)
{
    static char err[1024];
    vdb_buffer buf = {(void *)1, 1, NULL, 0};
    hz_status st = vdb_load_grid(path, gridname, &buf, err, sizeof err);
    if (st == HZ_OK)
        fail_msg("loading grid \"%s\" of %s should fail", gridname, path);
    assert_null(buf.data);
    assert_int_equal(buf.size, 0);
    assert_one_line(err);
    return err;
}

static void write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    if (n)
        assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

static void *read_file(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    void *data = malloc((size_t)size);
    assert_non_null(data);
    assert_int_equal(fread(data, 1, (size_t)size, f), (size_t)size);
    fclose(f);
    *n = (size_t)size;
    return data;
}

static void loads_box(void **state)
{
    (void)state;
    char err[256];
    vdb_buffer buf;
    assert_int_equal(vdb_load_grid(VOLUMES "box.vdb", "density", &buf, err, sizeof err), HZ_OK);
    assert_non_null(buf.data);
    assert_int_equal((uintptr_t)buf.data % 8, 0); /* PNanoVDB reads 64-bit words */
    assert_true(buf.size > 1000);
    vdb_buffer_free(&buf);
    assert_null(buf.data);
}

/* An uncompressed .nvdb grid that starts 8-byte aligned in its file is
 * mapped, one that does not is read: box.nvdb's grid starts at byte 200,
 * after its name record "density\0"; the same file with the name record one
 * NUL longer (the name is still "density") moves it to byte 201. Both load
 * the same bytes, and a mapped grid loads as a grid like any other. */
static void mapped_and_read_agree(void **state)
{
    (void)state;
    size_t n;
    unsigned char *orig = read_file(VOLUMES "box.nvdb", &n);
    enum { NAME_SIZE_AT = 16 + 136, NAME_AT = 16 + 176 };
    uint32_t name_size;
    memcpy(&name_size, orig + NAME_SIZE_AT, 4);
    assert_int_equal(name_size, 8);
    assert_memory_equal(orig + NAME_AT, "density", 8);
    unsigned char *shifted = malloc(n + 1);
    assert_non_null(shifted);
    memcpy(shifted, orig, NAME_AT + 8);
    shifted[NAME_AT + 8] = '\0';
    memcpy(shifted + NAME_AT + 9, orig + NAME_AT + 8, n - NAME_AT - 8);
    name_size = 9;
    memcpy(shifted + NAME_SIZE_AT, &name_size, 4);
    const char *path = HAZE_TMP "/media_shifted.nvdb";
    write_file(path, shifted, n + 1);

    char err[256];
    vdb_buffer mapped, read;
    assert_int_equal(vdb_load_grid(VOLUMES "box.nvdb", "density", &mapped, err, sizeof err), HZ_OK);
    if (vdb_load_grid(path, "density", &read, err, sizeof err) != HZ_OK)
        fail_msg("%s", err);
    assert_non_null(mapped.mapping);
    assert_null(read.mapping);
    assert_int_equal((uintptr_t)mapped.data % 8, 0);
    assert_int_equal(mapped.size, read.size);
    assert_memory_equal(mapped.data, read.data, read.size);
    assert_memory_equal(mapped.data, orig + NAME_AT + 8, mapped.size);

    hz_error herr = {0};
    grid *g = NULL;
    if (grid_create_from_buffer(&mapped, "density", &g, &herr) != HZ_OK)
        fail_msg("%s", herr.message);
    assert_null(mapped.data); /* the grid owns the mapping */
    assert_int_equal(grid_check_density(g, &herr), HZ_OK);
    grid_accessor a;
    grid_accessor_init(g, &a);
    assert_true(grid_density_index(g, &a, v3(31.5, 10, 10)) == 0.5);
    grid_destroy(g);
    vdb_buffer_free(&read);
    remove(path);
    free(shifted);
    free(orig);
}

static void missing_grid_lists_the_grids(void **state)
{
    (void)state;
    const char *e = load_error(VOLUMES "smoke.vdb", "temperature");
    assert_contains(e, "no grid named \"temperature\"");
    assert_contains(e, "\"density\", \"v\"");
    assert_contains(e, "smoke.vdb");
    e = load_error(VOLUMES "box.nvdb", "smoke");
    assert_contains(e, "no grid named \"smoke\"");
    assert_contains(e, "\"density\"");
}

static void wrong_type_names_the_type(void **state)
{
    (void)state;
    assert_contains(load_error(VOLUMES "smoke.vdb", "v"), "grid \"v\" is vec3s, expected float");
}

static void missing_file(void **state)
{
    (void)state;
    assert_contains(load_error(HAZE_TMP "/does-not-exist.vdb", "density"), "cannot open");
}

static void empty_file(void **state)
{
    (void)state;
    const char *path = HAZE_TMP "/media_empty.vdb";
    write_file(path, "", 0);
    assert_contains(load_error(path, "density"), "file is empty");
    remove(path);
}

static void non_vdb_file(void **state)
{
    (void)state;
    const char *path = HAZE_TMP "/media_text.vdb";
    const char text[] = "Film \"rgb\" \"string filename\" \"out.exr\"\n";
    write_file(path, text, sizeof text - 1);
    assert_contains(load_error(path, "density"), "not a VDB file");
    /* Shorter than any magic number. */
    write_file(path, "VD", 2);
    assert_contains(load_error(path, "density"), "not a VDB file");
    remove(path);
}

/* Every prefix length class of a real file: header, metadata, descriptors, data. */
static void truncated_files(void **state)
{
    (void)state;
    const char *sources[] = {VOLUMES "smoke.vdb", VOLUMES "box.vdb", VOLUMES "box.nvdb"};
    const char *path = HAZE_TMP "/media_truncated.vdb";
    for (size_t s = 0; s < sizeof sources / sizeof sources[0]; ++s) {
        size_t n;
        unsigned char *data = read_file(sources[s], &n);
        const size_t cuts[] = {4,    8,    12,    20,    40,      100,  300,
                               1000, 4000, n / 3, n / 2, n - 100, n - 1};
        for (size_t c = 0; c < sizeof cuts / sizeof cuts[0]; ++c) {
            write_file(path, data, cuts[c]);
            char err[1024] = "";
            vdb_buffer buf;
            hz_status st = vdb_load_grid(path, "density", &buf, err, sizeof err);
            if (st == HZ_OK) {
                vdb_buffer_free(&buf);
                fail_msg("%s cut to %zu bytes loaded", sources[s], cuts[c]);
            }
            assert_one_line(err);
        }
        free(data);
    }
    remove(path);
}

/* Grids that share a name: haze refuses to guess, in one plain line (no
 * OpenVDB log text, no escape sequence) naming them as OpenVDB does, and
 * reads the one a scene names that way. */
static void duplicate_grid_names(void **state)
{
    (void)state;
    const char *dup = HAZE_TEST_VOLUMES "/dup_names.vdb";
    const char *e = load_error(dup, "density");
    assert_contains(e, "dup_names.vdb: 2 grids are named \"density\"");
    assert_contains(e, "\"density[0]\", \"density[1]\"");
    assert_null(strchr(e, 0x1b));
    assert_null(strstr(e, "WARN"));
    for (int i = 0; i < 2; ++i) {
        hz_error err = {0};
        grid *g = NULL;
        if (grid_load(dup, i == 0 ? "density[0]" : "density[1]", &g, &err) != HZ_OK)
            fail_msg("%s", err.message);
        grid_accessor a;
        grid_accessor_init(g, &a);
        assert_true(grid_voxel(g, &a, 1, 0, 1) == (float)(i + 1));
        grid_destroy(g);
    }
    assert_contains(load_error(dup, "density[2]"), "no grid named \"density[2]\"");
}

static void nvdb_matches_vdb(void **state)
{
    (void)state;
    hz_error err = {0};
    grid *a = NULL, *b = NULL;
    if (grid_load(VOLUMES "box.vdb", "density", &a, &err) != HZ_OK ||
        grid_load(VOLUMES "box.nvdb", "density", &b, &err) != HZ_OK)
        fail_msg("%s", err.message);
    grid_accessor aa, ab;
    grid_accessor_init(a, &aa);
    grid_accessor_init(b, &ab);
    for (double x = -2; x <= 34; x += 0.75)
        for (double y = -2; y <= 34; y += 1.25)
            for (double z = -1.5; z <= 33; z += 2.5) {
                double da = grid_density_index(a, &aa, v3(x, y, z));
                double db = grid_density_index(b, &ab, v3(x, y, z));
                if (da != db)
                    fail_msg("density at (%g, %g, %g): vdb %g, nvdb %g", x, y, z, da, db);
            }
    assert_true(grid_density_index(b, &ab, v3(31.5, 10, 10)) == 0.5);
    vec3 p = v3(3.5, -2, 40);
    vec3 wa = grid_world_from_index(a, p), wb = grid_world_from_index(b, p);
    assert_true(wa.x == wb.x && wa.y == wb.y && wa.z == wb.z);
    assert_true(grid_max_value(b) == 1.0f);
    grid_destroy(a);
    grid_destroy(b);
}

typedef struct {
    int count;
    vdb_grid_info info[4];
    char names[4][32], types[4][32];
} listing;

static void collect(const vdb_grid_info *info, void *user)
{
    listing *l = user;
    if (l->count >= 4)
        return;
    l->info[l->count] = *info;
    snprintf(l->names[l->count], sizeof l->names[0], "%s", info->name);
    snprintf(l->types[l->count], sizeof l->types[0], "%s", info->type);
    l->count++;
}

static void lists_grids(void **state)
{
    (void)state;
    char err[1024];
    listing l = {0};
    assert_int_equal(vdb_list_grids(VOLUMES "smoke.vdb", collect, &l, err, sizeof err), HZ_OK);
    assert_int_equal(l.count, 2);
    assert_string_equal(l.names[0], "density");
    assert_string_equal(l.types[0], "float");
    assert_string_equal(l.names[1], "v");
    assert_string_equal(l.types[1], "vec3s");
    assert_true(l.info[0].has_range && l.info[0].min_value >= 0.01 && l.info[0].max_value <= 1.0);
    assert_true(l.info[1].has_range && l.info[1].min_value > 0.5);
    assert_int_equal(l.info[0].active_voxels, l.info[1].active_voxels);
    assert_true(fabs(l.info[0].voxel_size[0] - 1.0 / 48) < 1e-12);

    l = (listing){0};
    assert_int_equal(vdb_list_grids(VOLUMES "box.vdb", collect, &l, err, sizeof err), HZ_OK);
    assert_int_equal(l.count, 1);
    const vdb_grid_info *b = &l.info[0];
    assert_int_equal(b->active_voxels, 32768);
    for (int a = 0; a < 3; ++a) {
        assert_int_equal(b->index_min[a], 0);
        assert_int_equal(b->index_max[a], 31);
        assert_true(fabs(b->world_min[a] - -0.5 / 32) < 1e-12);
        assert_true(fabs(b->world_max[a] - 31.5 / 32) < 1e-12);
        assert_true(fabs(b->voxel_size[a] - 1.0 / 32) < 1e-15);
    }
    assert_true(b->has_range && b->min_value == 1.0 && b->max_value == 1.0);

    l = (listing){0};
    assert_int_equal(vdb_list_grids(VOLUMES "box.nvdb", collect, &l, err, sizeof err), HZ_OK);
    assert_int_equal(l.count, 1);
    assert_string_equal(l.names[0], "density");
    assert_string_equal(l.types[0], "float");
    assert_int_equal(l.info[0].active_voxels, 32768);
    assert_int_equal(l.info[0].index_max[2], 31);
    assert_true(fabs(l.info[0].world_min[1] - -0.5 / 32) < 1e-12);
    assert_true(fabs(l.info[0].world_max[1] - 31.5 / 32) < 1e-12);
    assert_true(l.info[0].has_range && l.info[0].max_value == 1.0);

    assert_int_equal(vdb_list_grids(HAZE_TMP "/nope.vdb", collect, &l, err, sizeof err), HZ_ERROR);
    assert_contains(err, "cannot open");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(loads_box),
        cmocka_unit_test(mapped_and_read_agree),
        cmocka_unit_test(missing_grid_lists_the_grids),
        cmocka_unit_test(wrong_type_names_the_type),
        cmocka_unit_test(missing_file),
        cmocka_unit_test(empty_file),
        cmocka_unit_test(non_vdb_file),
        cmocka_unit_test(truncated_files),
        cmocka_unit_test(nvdb_matches_vdb),
        cmocka_unit_test(duplicate_grid_names),
        cmocka_unit_test(lists_grids),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
