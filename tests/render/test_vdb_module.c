#define _POSIX_C_SOURCE 200809L
/* The OpenVDB module (media/vdb_module.h): reading a .nvdb file never maps
 * libopenvdb, reading a .vdb file loads the module (and OpenVDB) on first use;
 * the .vdb and .nvdb of one grid give byte-identical NanoVDB buffers; a missing
 * or wrong module is one clear line and exit 1, and .nvdb files still work
 * without it. The tests run in order: the first must run before anything
 * loads the module in this process. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "cli_util.h"

#include <stdbool.h>
#include <sys/resource.h>

#include "media/vdb_load.h"
#include "media/vdb_isolated.h"
#include "media/vdb_module.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

/* Whether a mapping of this process names a file containing `needle`. */
static bool mapped(const char *needle)
{
    FILE *f = fopen("/proc/self/maps", "r");
    assert_non_null(f);
    char line[4096];
    bool found = false;
    while (!found && fgets(line, sizeof line, f))
        found = strstr(line, needle) != NULL;
    fclose(f);
    return found;
}

static vdb_buffer load(const char *path)
{
    char err[1024] = "";
    vdb_buffer buf = {NULL, 0, NULL, 0};
    if (vdb_load_grid(path, "density", &buf, err, sizeof err) != HZ_OK)
        fail_msg("%s", err);
    return buf;
}

static void nvdb_does_not_map_openvdb(void **state)
{
    (void)state;
    assert_false(mapped("libopenvdb"));
    vdb_buffer nvdb = load(VOLUMES "box.nvdb");
    assert_true(nvdb.size > 32 && memcmp(nvdb.data, "NanoVDB0", 8) == 0); /* a NanoVDB grid */
    assert_false(mapped("libopenvdb"));
    assert_false(mapped("libhaze_openvdb"));
    /* A .vdb file is read by the reader process: OpenVDB is never mapped
     * into the renderer. */
    vdb_buffer vdb = load(VOLUMES "box.vdb");
    assert_true(vdb.size > 32 && memcmp(vdb.data, "NanoVDB0", 8) == 0);
    assert_false(mapped("libhaze_openvdb"));
    assert_false(mapped("libopenvdb"));
    vdb_buffer_free(&nvdb);
    vdb_buffer_free(&vdb);
}

/* Loads `path`'s density through the reader, never from the conversion
 * cache (HAZE_CACHE_DIR empty turns it off). */
static hz_status load_converting(const char *path, vdb_buffer *out, char *err, size_t err_size)
{
    const char *was = getenv("HAZE_CACHE_DIR");
    char keep[4096] = "";
    if (was)
        snprintf(keep, sizeof keep, "%s", was);
    assert_int_equal(setenv("HAZE_CACHE_DIR", "", 1), 0);
    hz_status st = vdb_load_grid(path, "density", out, err, err_size);
    if (was)
        assert_int_equal(setenv("HAZE_CACHE_DIR", keep, 1), 0);
    else
        assert_int_equal(unsetenv("HAZE_CACHE_DIR"), 0);
    return st;
}

static void vdb_and_nvdb_buffers_identical(void **state)
{
    (void)state;
    char err[1024] = "";
    vdb_buffer a = {NULL, 0, NULL, 0};
    if (load_converting(VOLUMES "box.vdb", &a, err, sizeof err) != HZ_OK)
        fail_msg("%s", err);
    vdb_buffer b = load(VOLUMES "box.nvdb");
    assert_int_equal(a.size, b.size);
    assert_int_equal(memcmp(a.data, b.data, a.size), 0);
    /* The reader built the grid in a memory file that this process maps. */
    assert_non_null(a.mapping);
    vdb_buffer_free(&a);
    vdb_buffer_free(&b);
}

/* Where no memory file can be handed to the reader (here: descriptors
 * limited below the ones it would get them on), the grid comes through the
 * pipe, a malloc'd copy, the same bytes. */
static void vdb_through_the_pipe(void **state)
{
    (void)state;
    struct rlimit old;
    assert_int_equal(getrlimit(RLIMIT_NOFILE, &old), 0);
    struct rlimit low = {VDB_READER_MEMFD + 4, old.rlim_max};
    assert_int_equal(setrlimit(RLIMIT_NOFILE, &low), 0);
    char err[1024] = "";
    vdb_buffer a = {NULL, 0, NULL, 0};
    hz_status st = load_converting(VOLUMES "box.vdb", &a, err, sizeof err);
    assert_int_equal(setrlimit(RLIMIT_NOFILE, &old), 0);
    if (st != HZ_OK)
        fail_msg("%s", err);
    vdb_buffer b = load(VOLUMES "box.nvdb");
    assert_null(a.mapping);
    assert_int_equal(a.size, b.size);
    assert_int_equal(memcmp(a.data, b.data, a.size), 0);
    vdb_buffer_free(&a);
    vdb_buffer_free(&b);
}

/* Runs haze with HAZE_OPENVDB_MODULE set to `module` (this process's own module
 * is loaded already, so the variable only reaches the child). */
static int run_with_module(const char *module, const char *args, char *out, size_t out_size)
{
    assert_int_equal(setenv("HAZE_OPENVDB_MODULE", module, 1), 0);
    int status = run_haze(args, out, out_size);
    assert_int_equal(unsetenv("HAZE_OPENVDB_MODULE"), 0);
    return status;
}

static void assert_one_line_with(const char *out, const char *needle)
{
    const char *nl = strchr(out, '\n');
    if (!nl || nl[1] != '\0')
        fail_msg("not one line: \"%s\"", out);
    if (!strstr(out, needle))
        fail_msg("\"%s\" does not mention \"%s\"", out, needle);
}

static void missing_module_is_one_line(void **state)
{
    (void)state;
    const char *missing = HAZE_TMP "/no-such-dir/libhaze_openvdb.so";
    char out[8192];
    assert_int_equal(run_with_module(missing, "info '" VOLUMES "box.vdb'", out, sizeof out), 1);
    assert_one_line_with(out, "cannot load the OpenVDB module");
    assert_one_line_with(out, missing);
    assert_one_line_with(out, "box.vdb");

    /* A render fails before it starts and writes no image. */
    const char *exr = HAZE_TMP "/vdb_module_missing.exr";
    remove(exr);
    char args[2048];
    snprintf(args, sizeof args, "render '%s/smoke.pbrt' --spp 1 --quiet -o '%s'", HAZE_SCENES,
             exr);
    assert_int_equal(run_with_module(missing, args, out, sizeof out), 1);
    assert_one_line_with(out, "cannot load the OpenVDB module");
    FILE *f = fopen(exr, "rb");
    assert_null(f);

    /* .nvdb files do not need the module. */
    assert_int_equal(run_with_module(missing, "info '" VOLUMES "box.nvdb'", out, sizeof out), 0);
    assert_non_null(strstr(out, "active voxels   32768"));
}

static void wrong_abi_is_refused(void **state)
{
    (void)state;
    char out[8192];
    assert_int_equal(run_with_module(BAD_MODULE, "info '" VOLUMES "box.vdb'", out, sizeof out), 1);
    char want[64];
    snprintf(want, sizeof want, "module ABI version %d", HAZE_OPENVDB_ABI + 1);
    assert_one_line_with(out, want);
    assert_one_line_with(out, BAD_MODULE);
}

/* OpenVDB dying inside its reader (out of memory: Blosc writes through a
 * failed allocation) costs the reader process, not the renderer: one line
 * naming the file and the signal, exit 1, no image, nothing the library
 * printed. */
static void crashing_reader_is_one_line(void **state)
{
    (void)state;
    const char *exr = HAZE_TMP "/vdb_module_crash.exr";
    remove(exr);
    char args[2048], out[8192];
    snprintf(args, sizeof args, "render '%s/smoke.pbrt' --spp 1 --quiet -o '%s'", HAZE_SCENES,
             exr);
    assert_int_equal(run_with_module(CRASHING_MODULE, args, out, sizeof out), 1);
    assert_one_line_with(out, "smoke.vdb: OpenVDB failed reading grid \"density\"");
    /* Killed by SIGSEGV; a sanitizer build's reader catches the signal and
     * exits instead. */
    if (!strstr(out, "killed by signal 11") && !strstr(out, "exited with status"))
        fail_msg("the reader's death is not reported: %s", out);
    assert_null(strstr(out, "Error allocating memory"));
    FILE *f = fopen(exr, "rb");
    assert_null(f);
}

/* What the libraries print to stdout in the reader (OpenVDB's coloured
 * log4cplus warnings) stays out of its replies: haze's error is the
 * module's own line, with no escape sequence and no log text. */
static void chatty_reader_is_one_line(void **state)
{
    (void)state;
    const char *exr = HAZE_TMP "/vdb_module_chatty.exr";
    char args[2048], out[8192];
    snprintf(args, sizeof args, "render '%s/smoke.pbrt' --spp 1 --quiet -o '%s'", HAZE_SCENES,
             exr);
    assert_int_equal(run_with_module(CHATTY_MODULE, args, out, sizeof out), 1);
    assert_one_line_with(out, "smoke.vdb: the chatty module reads no grid");
    assert_null(strchr(out, 0x1b));
    assert_null(strstr(out, "\\x1b"));
    assert_null(strstr(out, "WARN"));
}

static void module_next_to_haze_loads(void **state)
{
    (void)state;
    char out[8192];
    assert_int_equal(run_haze("info '" VOLUMES "smoke.vdb'", out, sizeof out), 0);
    assert_non_null(strstr(out, "grid \"v\""));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(nvdb_does_not_map_openvdb),
        cmocka_unit_test(vdb_and_nvdb_buffers_identical),
        cmocka_unit_test(vdb_through_the_pipe),
        cmocka_unit_test(missing_module_is_one_line),
        cmocka_unit_test(wrong_abi_is_refused),
        cmocka_unit_test(crashing_reader_is_one_line),
        cmocka_unit_test(chatty_reader_is_one_line),
        cmocka_unit_test(module_next_to_haze_loads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
