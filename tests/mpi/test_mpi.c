/* One image across MPI ranks (docs/mpi.md), against the haze executable under
 * mpirun on this machine: 2 and 4 (oversubscribed) ranks give the
 * single-process EXR byte for byte, for a grid medium with Z, variance and
 * sample-count AOVs; a rank that fails to load its scene, parsed a different
 * one, or is killed mid-render fails the run, naming the rank and its host,
 * and an existing output file is left untouched. Built only with HAZE_MPI. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <signal.h>
#include <stdbool.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli_util.h"
#include "core/clock.h"


static char dir[1024], scene[1200], reference[1200], host[256];

static double now(void) { return hz_clock_seconds(); }

static void nap(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

/* Runs a shell command, stdout+stderr into `out`; returns the exit status. */
static int run_shell(const char *cmd, char *out, size_t n)
{
    char full[8192];
    snprintf(full, sizeof full, "%s 2>&1", cmd);
    FILE *p = popen(full, "r");
    assert_non_null(p);
    size_t len = 0, got;
    char buf[4096];
    while ((got = fread(buf, 1, sizeof buf, p)) > 0)
        if (len + 1 < n) {
            size_t take = got < n - len - 1 ? got : n - len - 1;
            memcpy(out + len, buf, take);
            len += take;
        }
    out[len] = '\0';
    int status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static int count_temporaries(void)
{
    int n = count_temporaries_in(dir);
    assert_true(n >= 0);
    return n;
}

/* The regression smoke scene (a VDB grid medium over a floor), 40x50, with
 * every AOV, at `spp` (the option --spp overrides it). */
static void write_scene(const char *path)
{
    char text[4096];
    snprintf(text, sizeof text,
             "LookAt 0.6 1.2 -3.4   -0.05 0.85 0.1   0 1 0\n"
             "Camera \"perspective\" \"float fov\" 36\n"
             "Film \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 50\n"
             "    \"bool writedepth\" true \"bool writevariance\" true\n"
             "    \"bool writesamplecount\" true\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 8\n"
             "PixelFilter \"gaussian\"\n"
             "WorldBegin\n"
             "LightSource \"distant\" \"point3 from\" [1.8 2.8 2.4] \"point3 to\" [0 0 0]\n"
             "    \"rgb L\" [12 11 9.5]\n"
             "LightSource \"infinite\" \"rgb L\" [0.04 0.05 0.07]\n"
             "MakeNamedMedium \"smoke\" \"string type\" \"nanovdb\"\n"
             "    \"string filename\" \"%s/../volumes/smoke.vdb\" \"string gridname\" \"density\"\n"
             "    \"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [8 8 8] \"float g\" 0.5\n"
             "Material \"diffuse\" \"rgb reflectance\" [0.14 0.14 0.14]\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "    \"point3 P\" [-20 0 -20  20 0 -20  20 0 20  -20 0 20]\n"
             "AttributeBegin\n"
             "  Material \"interface\"\n"
             "  MediumInterface \"smoke\" \"\"\n"
             "  Shape \"trianglemesh\"\n"
             "    \"integer indices\" [0 6 2  0 4 6  1 3 7  1 7 5  0 1 5  0 5 4\n"
             "                       2 7 3  2 6 7  0 3 1  0 2 3  4 5 7  4 7 6]\n"
             "    \"point3 P\" [-0.42 -0.05 -0.42   0.32 -0.05 -0.42  -0.42 2.02 -0.42\n"
             "                 0.32 2.02 -0.42  -0.42 -0.05  0.36   0.32 -0.05  0.36\n"
             "                -0.42 2.02  0.36   0.32 2.02  0.36]\n"
             "AttributeEnd\n",
             HAZE_SCENES);
    write_text_file(path, text);
}

static int setup(void **state)
{
    (void)state;
    /* CI runs as root; OpenMPI refuses that unless told. */
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    /* OpenMPI leaks at MPI_Finalize from plugins it has dlclose'd by then:
     * their frames cannot be symbolised, so no LSan suppression matches them.
     * Under ASan the ranks run without leak checking (memory errors are still
     * fatal); haze's own allocations are leak-checked by the other tests. */
    if (UNDER_ASAN)
        setenv("ASAN_OPTIONS", "detect_leaks=0", 1);
    if (gethostname(host, sizeof host - 1) != 0)
        return -1;
    snprintf(dir, sizeof dir, "%s/mpi-%ld", HAZE_TMP, (long)getpid());
    mkdir(dir, 0755);
    snprintf(scene, sizeof scene, "%s/smoke.pbrt", dir);
    snprintf(reference, sizeof reference, "%s/single.exr", dir);
    write_scene(scene);
    /* The single-process reference, seed 5. */
    char cmd[4096], out[8192];
    snprintf(cmd, sizeof cmd, "'%s' render '%s' -o '%s' --seed 5 --threads 2 --quiet", HAZE_BIN,
             scene, reference);
    if (run_shell(cmd, out, sizeof out) != 0) {
        fprintf(stderr, "reference render failed: %s\n", out);
        return -1;
    }
    return 0;
}

/* mpirun ARGS haze render SCENE -o OUT --seed 5 EXTRA */
static int mpi_render(const char *mpirun_args, const char *out_name, const char *extra, char *text,
                      size_t n)
{
    char cmd[8192], out[1200];
    snprintf(out, sizeof out, "%s/%s", dir, out_name);
    snprintf(cmd, sizeof cmd, "'%s' %s --bind-to none '%s' render '%s' -o '%s' --seed 5 %s",
             HAZE_MPIEXEC, mpirun_args, HAZE_BIN, scene, out, extra);
    return run_shell(cmd, text, n);
}

static void expect_identical(const char *mpirun_args, const char *out_name, const char *extra)
{
    char text[16384], out[1200];
    int rc = mpi_render(mpirun_args, out_name, extra, text, sizeof text);
    if (rc != 0)
        fail_msg("mpirun %s exited %d: %s", mpirun_args, rc, text);
    snprintf(out, sizeof out, "%s/%s", dir, out_name);
    if (!files_equal(out, reference))
        fail_msg("%s differs from the single-process render", out);
}

static void test_two_ranks_bit_identical(void **state)
{
    (void)state;
    expect_identical("-np 2", "np2.exr", "--threads 1 --quiet");
    /* Several threads per rank: tiles split across ranks and threads. */
    expect_identical("-np 2", "np2t2.exr", "--threads 2 --quiet");
}

/* Spectral rendering: the wavelengths are the sampler's, so ranks give the
 * single-process image too. */
static void test_spectral_ranks_bit_identical(void **state)
{
    (void)state;
    char cmd[4096], out[8192], single[1200], text[16384], ranks[1200];
    snprintf(single, sizeof single, "%s/spectral-single.exr", dir);
    snprintf(cmd, sizeof cmd,
             "'%s' render '%s' -o '%s' --seed 5 --threads 2 --quiet --color spectral", HAZE_BIN,
             scene, single);
    if (run_shell(cmd, out, sizeof out) != 0)
        fail_msg("spectral reference render failed: %s", out);
    int rc = mpi_render("-np 2", "spectral-np2.exr", "--threads 1 --quiet --color spectral", text,
                        sizeof text);
    if (rc != 0)
        fail_msg("mpirun -np 2 exited %d: %s", rc, text);
    snprintf(ranks, sizeof ranks, "%s/spectral-np2.exr", dir);
    assert_true(files_equal(ranks, single));
    assert_false(files_equal(ranks, reference)); /* and it is not the RGB image */
}

static void test_four_ranks_bit_identical(void **state)
{
    (void)state;
    expect_identical("-np 4 --oversubscribe", "np4.exr", "--threads 1 --quiet");
}

/* --time-limit across ranks: with time to spare, every pass (8 spp: 1, 1, 2,
 * 4) gives the single-process pixels, every AOV; with none, the first pass
 * (the 1-sample render, since a Sobol' pixel's first samples do not depend
 * on the count). */
static void test_time_limit_passes(void **state)
{
    (void)state;
    char text[16384], out[1200], one[1200], cmd[4096];
    assert_int_equal(mpi_render("-np 2", "tl.exr", "--threads 1 --time-limit 1e6", text,
                                sizeof text), 0);
    if (!strstr(text, "8 spp in 4 passes"))
        fail_msg("summary: %s", text);
    snprintf(out, sizeof out, "%s/tl.exr", dir);
    assert_true(exr_pixels_equal(out, reference));

    snprintf(one, sizeof one, "%s/one.exr", dir);
    snprintf(cmd, sizeof cmd, "'%s' render '%s' -o '%s' --seed 5 --spp 1 --quiet", HAZE_BIN,
             scene, one);
    assert_int_equal(run_shell(cmd, text, sizeof text), 0);
    assert_int_equal(mpi_render("-np 2", "tl1.exr", "--threads 1 --time-limit 0.001", text,
                                sizeof text), 0);
    if (!strstr(text, "1 spp in 1 pass,"))
        fail_msg("summary: %s", text);
    snprintf(out, sizeof out, "%s/tl1.exr", dir);
    assert_true(exr_pixels_equal(out, one));
}

/* --target-error across ranks: the single-process pixels (the decisions of a
 * tile depend on its own pixels; the image's estimate is summed in tile order). */
static void test_target_error_ranks(void **state)
{
    (void)state;
    char text[16384], out[1200], single[1200], cmd[4096];
    snprintf(single, sizeof single, "%s/te1.exr", dir);
    snprintf(cmd, sizeof cmd,
             "'%s' render '%s' -o '%s' --seed 5 --target-error 3e-3 --spp 64 --quiet", HAZE_BIN,
             scene, single);
    assert_int_equal(run_shell(cmd, text, sizeof text), 0);
    assert_int_equal(mpi_render("-np 2", "te2.exr", "--threads 1 --target-error 3e-3 --spp 64",
                                text, sizeof text), 0);
    if (!strstr(text, "spp at most ("))
        fail_msg("summary: %s", text);
    snprintf(out, sizeof out, "%s/te2.exr", dir);
    assert_true(exr_pixels_equal(out, single));
    assert_true(exr_attributes_equal(out, single, "haze:estimated_error"));
}

/* The summary on rank 0 counts every rank's rays and says how many ranks. */
static void test_summary_names_ranks(void **state)
{
    (void)state;
    char text[16384];
    assert_int_equal(mpi_render("-np 2", "np2s.exr", "--threads 1", text, sizeof text), 0);
    if (!strstr(text, "2 threads on 2 ranks") || !strstr(text, "40x50") ||
        !strstr(text, "16000 camera"))
        fail_msg("summary: %s", text);
    assert_non_null(strstr(text, "2 ranks: tiles "));
    /* One summary: ranks other than 0 print nothing. */
    assert_null(strstr(strstr(text, "40x50") + 1, "40x50"));
}

/* Copies the reference to `name` (an existing good output) and returns its path. */
static void existing_output(const char *name, char *path, size_t n)
{
    snprintf(path, n, "%s/%s", dir, name);
    size_t size = 0;
    unsigned char *bytes = read_whole_file(reference, &size);
    assert_non_null(bytes);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, size, f), size);
    fclose(f);
    free(bytes);
}

static void expect_untouched(const char *path)
{
    assert_true(files_equal(path, reference));
    assert_int_equal(count_temporaries(), 0);
}

/* MPMD: rank 1 renders a scene whose volume is missing. */
static void test_failing_rank_named(void **state)
{
    (void)state;
    char out[1200], cmd[8192], text[16384], want[512];
    existing_output("kept.exr", out, sizeof out);
    snprintf(cmd, sizeof cmd,
             "'%s' -np 1 '%s' render '%s' -o '%s' --quiet : -np 1 '%s' render "
             "'%s/bad-input/vdb-missing.pbrt' -o '%s' --quiet",
             HAZE_MPIEXEC, HAZE_BIN, scene, out, HAZE_BIN, HAZE_TESTS, out);
    assert_int_not_equal(run_shell(cmd, text, sizeof text), 0);
    snprintf(want, sizeof want, "haze: rank 1 on host %s: ", host);
    if (!strstr(text, want) || !strstr(text, "no-such.vdb"))
        fail_msg("expected \"%s...no-such.vdb...\" in: %s", want, text);
    assert_null(strstr(text, "rank 0 on host"));
    expect_untouched(out);
}

/* Launched by mpirun without a loadable MPI module: every rank refuses
 * with the paths it tried, rather than rendering the whole image each; the
 * output is left alone. */
static void test_missing_module_refused(void **state)
{
    (void)state;
    char out[1200], cmd[8192], text[16384];
    existing_output("nomodule.exr", out, sizeof out);
    snprintf(cmd, sizeof cmd,
             "'%s' -np 2 --oversubscribe -x HAZE_MPI_MODULE='%s/no-such-libhaze_mpi.so' '%s' "
             "render '%s' -o '%s' --quiet",
             HAZE_MPIEXEC, dir, HAZE_BIN, scene, out);
    assert_int_not_equal(run_shell(cmd, text, sizeof text), 0);
    if (!strstr(text, "cannot load the MPI module") || !strstr(text, "no-such-libhaze_mpi.so"))
        fail_msg("expected \"cannot load the MPI module (tried ...no-such-libhaze_mpi.so\" in: %s",
                 text);
    expect_untouched(out);
}

/* MPMD: rank 1 was given another spp, so its tiles would not fit the image. */
static void test_mismatched_rank_refused(void **state)
{
    (void)state;
    char out[1200], cmd[8192], text[16384], want[512];
    existing_output("kept2.exr", out, sizeof out);
    snprintf(cmd, sizeof cmd,
             "'%s' -np 1 '%s' render '%s' -o '%s' --quiet : -np 1 '%s' render '%s' -o '%s' "
             "--quiet --spp 4",
             HAZE_MPIEXEC, HAZE_BIN, scene, out, HAZE_BIN, scene, out);
    assert_int_not_equal(run_shell(cmd, text, sizeof text), 0);
    snprintf(want, sizeof want, "haze: rank 1 on host %s: parsed a different scene", host);
    if (!strstr(text, want))
        fail_msg("expected \"%s\" in: %s", want, text);
    expect_untouched(out);
}

/* CPU seconds (user + system) used so far by `pid`; -1 when it is gone. */
static double cpu_seconds(pid_t pid)
{
    char path[64], buf[2048];
    snprintf(path, sizeof path, "/proc/%ld/stat", (long)pid);
    FILE *f = fopen(path, "r");
    if (!f)
        return -1.0;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    const char *p = strrchr(buf, ')'); /* fields after the command name */
    unsigned long utime = 0, stime = 0;
    if (!p || sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu", &utime,
                     &stime) != 2)
        return -1.0;
    return (double)(utime + stime) / (double)sysconf(_SC_CLK_TCK);
}

/* Rank 1 is killed by SIGKILL while rendering (after it has used 0.5 s of
 * CPU: far more than building this scene takes). */
static void test_killed_rank_fails_run(void **state)
{
    (void)state;
    char out[1200], pidfile[1200], cmd[8192], text[16384];
    existing_output("kept3.exr", out, sizeof out);
    snprintf(pidfile, sizeof pidfile, "%s/rank1.pid", dir);
    unlink(pidfile);
    snprintf(cmd, sizeof cmd,
             "'%s' -np 1 --bind-to none '%s' render '%s' -o '%s' --quiet --spp 4096 : -np 1 "
             "--bind-to none sh -c 'echo $$ > \"%s\"; exec \"$0\" \"$@\"' '%s' render '%s' "
             "-o '%s' --quiet --spp 4096",
             HAZE_MPIEXEC, HAZE_BIN, scene, out, pidfile, HAZE_BIN, scene, out);
    char full[8300];
    snprintf(full, sizeof full, "%s 2>&1", cmd);
    FILE *p = popen(full, "r");
    assert_non_null(p);
    pid_t rank1 = 0;
    double t0 = now();
    while (now() - t0 < 60.0) {
        FILE *f = fopen(pidfile, "r");
        long v = 0;
        if (f) {
            if (fscanf(f, "%ld", &v) != 1)
                v = 0;
            fclose(f);
        }
        if (v > 0 && cpu_seconds((pid_t)v) >= 0.5) {
            rank1 = (pid_t)v;
            break;
        }
        nap(0.02);
    }
    if (rank1 > 0)
        kill(rank1, SIGKILL);
    size_t len = 0, got;
    char buf[4096];
    while ((got = fread(buf, 1, sizeof buf, p)) > 0)
        if (len + 1 < sizeof text) {
            size_t take = got < sizeof text - len - 1 ? got : sizeof text - len - 1;
            memcpy(text + len, buf, take);
            len += take;
        }
    text[len] = '\0';
    int status = pclose(p);
    if (rank1 <= 0)
        fail_msg("rank 1 never started rendering: %s", text);
    assert_true(!WIFEXITED(status) || WEXITSTATUS(status) != 0);
    /* OpenMPI names the rank and the node. */
    char want[512];
    snprintf(want, sizeof want, "rank 1 with PID");
    if (!strstr(text, want) || !strstr(text, host) || !strstr(text, "signal 9"))
        fail_msg("expected mpirun to name rank 1 on %s killed by signal 9: %s", host, text);
    expect_untouched(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_ranks_bit_identical),
        cmocka_unit_test(test_spectral_ranks_bit_identical),
        cmocka_unit_test(test_four_ranks_bit_identical),
        cmocka_unit_test(test_summary_names_ranks),
        cmocka_unit_test(test_time_limit_passes),
        cmocka_unit_test(test_target_error_ranks),
        cmocka_unit_test(test_failing_rank_named),
        cmocka_unit_test(test_missing_module_refused),
        cmocka_unit_test(test_mismatched_rank_refused),
        cmocka_unit_test(test_killed_rank_fails_run),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
