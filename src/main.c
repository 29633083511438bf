/* haze: command line. Exit status 0 on success, 1 on scene or render errors,
 * 2 on usage errors, 130 when a render was interrupted by SIGINT, SIGTERM or
 * SIGHUP (docs/faults.md). */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/diff.h"
#include "cli/info.h"
#include "cli/merge.h"
#include "cli/outputs.h"
#include "core/clock.h"
#include "integrator/walk.h"
#include "mpi/distributed.h"
#include "render/progress.h"
#include "render/progressive.h"
#include "render/step_pilot.h"
#include "render/render_scene.h"
#include "render/renderer.h"
#include "scene/scene_desc.h"

enum { EXIT_SCENE = 1, EXIT_USAGE = 2, EXIT_INTERRUPTED = 130 };
/* --target-error without --spp: the most samples a pixel may take. */
enum { ADAPTIVE_MAX_SPP = 16384 };

/* The only mutable globals of haze, shared with the signal handler: the
 * interrupt flag the renderer polls, and the temporary output file to remove
 * when a second signal ends the process at once. */
static volatile sig_atomic_t interrupted;
static tmp_file_note output_note;

static void on_interrupt(int sig)
{
    (void)sig;
    if (interrupted) {
        if (output_note.valid)
            unlink(output_note.path);
        _exit(EXIT_INTERRUPTED);
    }
    interrupted = 1;
}

/* First SIGINT/SIGTERM/SIGHUP (a closed terminal or ssh session is a render
 * stopped like any other): give the tiles under way a second, write what is
 * done; second: exit at once. A signal ignored when haze started (a
 * background job of a non-interactive shell ignores SIGINT, nohup ignores
 * SIGHUP) stays ignored. */
static void install_interrupt_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sigaddset(&sa.sa_mask, SIGINT);
    sigaddset(&sa.sa_mask, SIGTERM);
    sigaddset(&sa.sa_mask, SIGHUP);
    sa.sa_flags = SA_RESTART;
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    for (int i = 0; i < 3; ++i) {
        struct sigaction old;
        if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(sigs[i], &sa, NULL);
    }
}

static const char usage_text[] =
    "usage: haze render SCENE.pbrt [options]\n"
    "       haze info FILE          describe a .vdb, .nvdb, .exr, .bsdf or .pbrt file\n"
    "       haze diff A.exr B.exr [--channels R,G,B] [--metric NAME --threshold X]\n"
    "                 [--ztest [--alpha A] [--accept F]]\n"
    "                 [--heatmap OUT.exr|OUT.png]   compare two images (haze diff --help)\n"
    "       haze merge PART.exr... -o FULL.exr   assemble region renders (haze merge --help)\n"
    "       haze --help | --version\n"
    "\n"
    "render options:\n"
    "  -o, --output FILE.exr   write the image here (overrides the Film's filename)\n"
    "  --spp N                 samples per pixel (overrides the Sampler's count)\n"
    "  --threads N             render threads (default: all cores)\n"
    "  --seed N                random seed (default 0; a Sampler's \"integer seed\" wins)\n"
    "  --preview FILE.png      also write a tonemapped sRGB PNG\n"
    "  --pixelbounds x0,x1,y0,y1  render only pixels [x0,x1) x [y0,y1) (overrides the Film's)\n"
    "  --cropwindow x0,x1,y0,y1   render only this fraction of the image, values in [0,1],\n"
    "                          pixels ceil(res * crop) as pbrt-v4 (not with --pixelbounds)\n"
    "  --quiet                 no progress bar and no summary\n"
    "  --stats                 after the summary, 'stat NAME VALUE' lines: rays, lookups and\n"
    "                          majorant steps per pixel, time split, memory (docs/performance.md)\n"
    "  --disable-pixel-jitter  every camera ray through its pixel's centre (as pbrt-v4)\n"
    "  --color auto|rgb|spectral  carry colour along paths as RGB or as four wavelengths\n"
    "                          per sample, as pbrt-v4; auto (default): spectral for\n"
    "                          coloured media, metals, coatings, hair (docs/spectral.md)\n"
    "  --portable-isa          Embree at SSE4.2 on every machine: byte-identical images\n"
    "                          across x86 machines (default: the CPU's widest ISA)\n"
    "  --time-limit SECONDS    render in passes (1, 1, 2, 4, ... spp up to the Sampler's\n"
    "                          count) and write the complete passes done when the time\n"
    "                          since start runs out (docs/progressive.md)\n"
    "  --target-error E        adaptive sampling: pixels take samples (0.2 / sqrt(E) at\n"
    "                          least, at most --spp, default 16384) until the image's\n"
    "                          estimated relMSE is E; marching estimators get a step\n"
    "                          picked for E first, whose bias takes part of E\n";

typedef struct {
    const char *scene;
    const char *output;
    const char *preview;
    int spp, threads;
    unsigned long long seed;
    int seed_given;           /* --seed was given (it wins over Option "seed") */
    int quiet;
    int stats;                /* --stats */
    int disable_pixel_jitter; /* --disable-pixel-jitter */
    int portable_isa;         /* --portable-isa */
    render_color color;       /* --color */
    film_region region;     /* --pixelbounds / --cropwindow */
    const char *region_opt; /* which of the two, and its text, for messages */
    const char *region_arg;
    double time_limit;      /* --time-limit seconds, 0: none */
    double target_error;    /* --target-error, 0: none */
    double start_seconds;   /* hz_clock_seconds() when haze started */
} cli;

static int usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "haze: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\nTry 'haze --help'.\n");
    return EXIT_USAGE;
}

static int parse_count(const char *s, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end != '\0' || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

/* "x0,x1,y0,y1": four integers (pixels) or four finite numbers (crop). */
static int parse_region(const char *s, film_region_kind kind, film_region *out)
{
    const char *p = s;
    for (int i = 0; i < 4; ++i) {
        char *end;
        errno = 0;
        if (kind == FILM_REGION_PIXELS) {
            long v = strtol(p, &end, 10);
            if (v < -(1L << 30) || v > (1L << 30))
                return -1;
            out->v[i] = (double)v;
        } else {
            out->v[i] = strtod(p, &end);
        }
        if (errno || end == p || *end != (i < 3 ? ',' : '\0') || out->v[i] != out->v[i])
            return -1;
        p = end + 1;
    }
    out->kind = kind;
    return 0;
}

/* Returns -1 on success, else the exit status. */
static int parse_render_args(int argc, char **argv, cli *c)
{
    for (int i = 2; i < argc; ++i) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        long n;
        if (!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--spp") ||
            !strcmp(a, "--threads") || !strcmp(a, "--seed") || !strcmp(a, "--preview") ||
            !strcmp(a, "--pixelbounds") || !strcmp(a, "--cropwindow") ||
            !strcmp(a, "--time-limit") || !strcmp(a, "--target-error") ||
            !strcmp(a, "--color")) {
            if (!val)
                return usage_error("option %s needs a value", a);
            ++i;
            if (!strcmp(a, "-o") || !strcmp(a, "--output"))
                c->output = val;
            else if (!strcmp(a, "--preview"))
                c->preview = val;
            else if (!strcmp(a, "--pixelbounds") || !strcmp(a, "--cropwindow")) {
                bool pixels = !strcmp(a, "--pixelbounds");
                if (c->region_opt && strcmp(c->region_opt, a) != 0)
                    return usage_error("%s", "--pixelbounds and --cropwindow cannot both be given");
                if (parse_region(val, pixels ? FILM_REGION_PIXELS : FILM_REGION_CROP, &c->region))
                    return usage_error(pixels ? "--pixelbounds needs four integers x0,x1,y0,y1, not '%s'"
                                              : "--cropwindow needs four numbers x0,x1,y0,y1, not '%s'",
                                       val);
                c->region_opt = a;
                c->region_arg = val;
            }
            else if (!strcmp(a, "--color")) {
                if (!strcmp(val, "auto"))
                    c->color = RENDER_COLOR_AUTO;
                else if (!strcmp(val, "rgb"))
                    c->color = RENDER_COLOR_RGB;
                else if (!strcmp(val, "spectral"))
                    c->color = RENDER_COLOR_SPECTRAL;
                else
                    return usage_error("--color needs auto, rgb or spectral, not '%s'", val);
            } else if (!strcmp(a, "--target-error")) {
                char *end;
                errno = 0;
                double e = strtod(val, &end);
                if (errno || end == val || *end != '\0' || !(e >= 1e-8 && e <= 1.0))
                    return usage_error("--target-error needs a relative error in [1e-8, 1], "
                                       "not '%s'", val);
                c->target_error = e;
            } else if (!strcmp(a, "--time-limit")) {
                char *end;
                errno = 0;
                double t = strtod(val, &end);
                if (errno || end == val || *end != '\0' || !(t > 0.0 && t <= 1e9))
                    return usage_error("--time-limit needs a number of seconds in (0, 1e9], "
                                       "not '%s'", val);
                c->time_limit = t;
            } else if (!strcmp(a, "--spp")) {
                if (parse_count(val, 1, 1 << 24, &n))
                    return usage_error("--spp needs an integer in [1, 16777216], not '%s'", val);
                c->spp = (int)n;
            } else if (!strcmp(a, "--threads")) {
                if (parse_count(val, 1, 4096, &n))
                    return usage_error("--threads needs an integer in [1, 4096], not '%s'", val);
                c->threads = (int)n;
            } else {
                if (parse_count(val, 0, LONG_MAX, &n))
                    return usage_error("--seed needs a non-negative integer, not '%s'", val);
                c->seed = (unsigned long long)n;
                c->seed_given = 1;
            }
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            c->quiet = 1;
        } else if (!strcmp(a, "--stats")) {
            c->stats = 1;
        } else if (!strcmp(a, "--disable-pixel-jitter")) {
            c->disable_pixel_jitter = 1;
        } else if (!strcmp(a, "--portable-isa")) {
            c->portable_isa = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            return usage_error("unknown option '%s'", a);
        } else if (!c->scene) {
            c->scene = a;
        } else {
            return usage_error("more than one scene given ('%s')", a);
        }
    }
    if (!c->scene)
        return usage_error("%s", "render needs a scene file");
    return -1;
}

static void format_count(char *buf, size_t n, long long v) { snprintf(buf, n, "%lld", v); }

/* The image (an EXR, or the PNG the Film names) at `path`. */
static hz_status write_image_file(const render_outputs *outs, const film *f, const char *path,
                                  double ratio, const film_output *out, hz_error *err)
{
    return outs->image_png ? film_write_png_with(f, path, ratio, out, err)
                           : film_write_exr_with(f, path, ratio, out, err);
}

_Static_assert((int)RENDERER_TILE_RANGES <= (int)EXR_ATTRIBUTE_VALUE_SIZE,
               "haze:tile_ranges fits in an EXR attribute");

/* Writes the image (and the PNG preview) of an interrupted render: rendered
 * tiles only, with EXR header attributes describing which. */
static int write_partial(const render_outputs *outs, film *f, double ratio,
                         const render_stats *stats)
{
    if (stats->tiles_done == 0) {
        fprintf(stderr, "haze: interrupted before any tile was rendered: nothing written\n");
        return EXIT_INTERRUPTED;
    }
    char tiles_done[32], tile_count[32], tile_size[32], pixels_done[32], pixels_total[32], spp[32];
    format_count(tiles_done, sizeof tiles_done, stats->tiles_done);
    format_count(tile_count, sizeof tile_count, stats->tile_count);
    format_count(tile_size, sizeof tile_size, RENDERER_TILE_SIZE);
    format_count(pixels_done, sizeof pixels_done, stats->pixels);
    format_count(pixels_total, sizeof pixels_total, stats->pixels_total);
    format_count(spp, sizeof spp, stats->spp);
    const film_attribute attrs[] = {
        {"haze:partial", "true"},
        {"haze:tiles_done", tiles_done},
        {"haze:tile_count", tile_count},
        {"haze:tile_size", tile_size},
        {"haze:tile_order", "row-major over the data window; haze:tile_ranges lists the "
                            "rendered tiles"},
        {"haze:tile_ranges", stats->tile_ranges},
        {"haze:pixels_done", pixels_done},
        {"haze:pixels_total", pixels_total},
        {"haze:spp", spp},
        {"haze:render", outs->render_id},
    };
    film_output out = {attrs, (int)(sizeof attrs / sizeof attrs[0]), &output_note, stats->threads};
    char image_path[PATH_MAX + 16], png_path[PATH_MAX + 16];
    outputs_partial_path(outs->image, image_path, sizeof image_path);
    hz_error err = {0};
    if (write_image_file(outs, f, image_path, ratio, &out, &err) != HZ_OK) {
        hz_error_print(stderr, &err);
        return EXIT_SCENE;
    }
    bool preview = outs->png[0] != '\0';
    if (preview) {
        outputs_partial_path(outs->png, png_path, sizeof png_path);
        if (film_write_png_with(f, png_path, ratio, &out, &err) != HZ_OK) {
            hz_error_print(stderr, &err);
            return EXIT_SCENE;
        }
    }
    fprintf(stderr, "haze: interrupted: wrote %d of %d tiles to %s%s%s\n", stats->tiles_done,
            stats->tile_count, image_path, preview ? " and " : "", preview ? png_path : "");
    return EXIT_INTERRUPTED;
}

static double peak_memory_mib(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0.0;
    return ru.ru_maxrss / 1024.0;
}

/* Resident memory now (/proc/self/statm), 0 when unknown. */
static double resident_memory_mib(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f)
        return 0.0;
    unsigned long size = 0, resident = 0;
    int n = fscanf(f, "%lu %lu", &size, &resident);
    fclose(f);
    return n == 2 ? resident * (double)sysconf(_SC_PAGESIZE) / (1024.0 * 1024.0) : 0.0;
}

/* --target-error E that the render did not reach says so, and why: the
 * image's `estimate` (noise and the step's `bias`; < 0: none) is above E
 * because the passes stopped at the --spp cap or the time limit
 * (`deadline`), or because the step's bias is more than the half of E the
 * pilot could give it, or else every pixel had the samples its share asked
 * for. */
static void warn_target_missed(double target, double estimate, double bias, int spp, int cap,
                               bool deadline)
{
    if (estimate < 0.0) {
        fprintf(stderr, "haze: warning: --target-error %g: no error estimate, which needs two "
                        "samples a pixel (--spp %d)\n", target, cap);
        return;
    }
    if (!(estimate > target * (1.0 + 1e-9))) /* noise <= E - bias, rounded */
        return;
    const char *why = spp >= cap               ? "the --spp cap stopped the passes"
                      : deadline             ? "the time limit stopped the passes"
                      : bias > 0.5 * target ? "the finest marching step's estimated bias is "
                                              "more than half of it"
                                            : "every pixel took the samples of its share";
    fprintf(stderr, "haze: warning: --target-error %g not reached: estimated relMSE %.3g at %d "
                    "samples a pixel at most (%s)\n", target, estimate, spp, why);
}

/* When each phase of a render began (hz_clock_seconds), for --stats. */
typedef struct {
    double start, parse, build, render, write, end;
    double pilot_seconds; /* --target-error's step pilot, part of the render */
    medium_work pilot_work; /* what the media did on demand during the pilot */
} phase_times;

/* --stats: one 'stat NAME VALUE' line per figure (docs/performance.md). */
static void print_stats(const render_scene *rs, const render_stats *st, double baseline_mib,
                        const phase_times *ph)
{
    double px = st->pixels > 0 ? (double)st->pixels : 1.0, mib = 1.0 / (1024.0 * 1024.0);
    render_memory mem = render_scene_memory(rs);
    double other = st->time_busy_s - st->time_media_s - st->time_film_s;
    printf("stat wall_s %.4f\n", st->wall_seconds);
    printf("stat threads %d\n", st->threads);
    printf("stat pixels %ld\n", st->pixels);
    printf("stat spp %d\n", st->spp);
    printf("stat camera_rays %llu\n", (unsigned long long)st->camera_rays);
    printf("stat shadow_rays %llu\n", (unsigned long long)st->shadow_rays);
    printf("stat rays_per_s %.0f\n",
           st->wall_seconds > 0 ? (st->camera_rays + st->shadow_rays) / st->wall_seconds : 0.0);
    printf("stat density_lookups_per_pixel %.2f\n", st->density_lookups / px);
    printf("stat majorant_steps_per_pixel %.2f\n", st->majorant_steps / px);
    render_marching m;
    if (render_scene_marching(rs, &m) && m.auto_steps)
        printf("stat auto_step_scale %g\n", m.auto_scale);
    printf("stat spectral %d\n", render_scene_spectral(rs) ? 1 : 0);
    printf("stat time_busy_s %.4f\n", st->time_busy_s);
    printf("stat time_surfaces_s %.4f\n", other > 0.0 ? other : 0.0);
    printf("stat time_media_s %.4f\n", st->time_media_s);
    printf("stat time_film_s %.4f\n", st->time_film_s);
    printf("stat time_start_s %.4f\n", ph->parse - ph->start);
    printf("stat time_parse_s %.4f\n", ph->build - ph->parse);
    printf("stat time_build_s %.4f\n", ph->render - ph->build);
    printf("stat time_render_s %.4f\n", ph->write - ph->render);
    printf("stat time_pilot_s %.4f\n", ph->pilot_seconds);
    medium_work work = render_scene_media_work(rs);
    printf("stat majorant_bricks_built %zu\n", work.majorant_bricks);
    printf("stat cpu_majorant_build_s %.4f\n", work.majorant_seconds);
    printf("stat pilot_majorant_bricks_built %zu\n", ph->pilot_work.majorant_bricks);
    printf("stat cpu_pilot_majorant_build_s %.4f\n", ph->pilot_work.majorant_seconds);
    printf("stat time_write_s %.4f\n", ph->end - ph->write);
    printf("stat memory_peak_mib %.2f\n", peak_memory_mib());
    printf("stat memory_baseline_mib %.2f\n", baseline_mib);
    printf("stat memory_grids_mib %.3f\n", mem.grids * mib);
    printf("stat memory_majorants_mib %.3f\n", mem.majorants * mib);
    printf("stat memory_film_mib %.3f\n", mem.film * mib);
    printf("stat memory_embree_mib %.3f\n", mem.embree * mib);
    printf("stat memory_shadow_caches_mib %.3f\n", mem.shadow_caches * mib);
}

/* "static", or what moves: "motion: camera, surfaces, 1 medium". */
static void format_motion(render_motion m, char *buf, size_t n)
{
    if (!m.camera && !m.surfaces && m.media == 0) {
        snprintf(buf, n, "static");
        return;
    }
    char media[32];
    snprintf(media, sizeof media, "%zu medi%s", m.media, m.media == 1 ? "um" : "a");
    const char *parts[3] = {m.camera ? "camera" : NULL, m.surfaces ? "surfaces" : NULL,
                            m.media ? media : NULL};
    size_t len = (size_t)snprintf(buf, n, "motion:");
    const char *sep = " ";
    for (int i = 0; i < 3 && len < n; ++i)
        if (parts[i]) {
            len += (size_t)snprintf(buf + len, n - len, "%s%s", sep, parts[i]);
            sep = ", ";
        }
}

/* A --pixelbounds / --cropwindow region that does not fit the scene's film is
 * a usage error, found before the scene is built (the film's own errors are
 * left to render_scene_create). */
static int check_region(const cli *c, scene_desc *sd)
{
    film_params fp;
    hz_error err = {0};
    bool bad = false;
    if (c->region.kind == FILM_REGION_NONE ||
        film_params_from_entity_region(&sd->film, &c->region, &fp, &bad, &err) == HZ_OK || !bad)
        return 0;
    fprintf(stderr, "haze: %s %s: %s\nTry 'haze --help'.\n", c->region_opt, c->region_arg, err.message);
    return -1;
}

/* One render's scene and where its image goes, from the parse to the write. */
typedef struct {
    scene_desc sd;
    bool read;             /* sd holds a scene to free */
    render_scene *rs;      /* NULL until built */
    film *f;
    const film_params *fp;
    render_outputs outs;   /* resolved on rank 0 only */
    uint64_t inputs_hash;
    bool no_jitter;        /* --disable-pixel-jitter or the scene's Option */
    bool abandoned;        /* render threads still run: the scene must stay */
} render_job;

static render_options render_options_from_cli(const cli *c)
{
    bool adaptive = c->target_error > 0;
    return (render_options){.seed = c->seed,
                            .seed_given = c->seed_given != 0,
                            .spp = c->spp > 0 ? c->spp : adaptive ? ADAPTIVE_MAX_SPP : 0,
                            .output = c->output,
                            .region = c->region,
                            .statistics = adaptive,
                            .portable_isa = c->portable_isa != 0,
                            .color = c->color};
}

/* The EXR's "haze:render" for an image of `spp` samples a pixel. */
static void set_render_id(render_job *job, int spp)
{
    snprintf(job->outs.render_id, sizeof job->outs.render_id, "%016llx",
             (unsigned long long)outputs_render_id(job->inputs_hash, job->rs, spp, job->no_jitter));
}

/* Parses and builds the scene and resolves its outputs and id; every rank
 * then agrees it is ready (under mpirun one rank's failure stops them all).
 * Returns 0 or the exit status. */
static int load_scene(const cli *c, distributed *dist, render_job *job, phase_times *ph,
                      hz_error *err)
{
    bool rank0 = distributed_rank(dist) == 0;
    hz_errors parse_errs = {0};
    job->read = scene_parse_file_all(c->scene, &job->sd, &parse_errs, err) == HZ_OK;
    bool parsed = job->read && parse_errs.count == 0 && parse_errs.dropped == 0;
    /* Every rank has the same arguments: under mpirun all of them stop here. */
    if (parsed && check_region(c, &job->sd) != 0)
        return EXIT_USAGE;
    render_options ro = render_options_from_cli(c);
    hz_status st = HZ_ERROR;
    ph->build = hz_clock_seconds();
    if (parsed)
        st = render_scene_create(&job->sd, &ro, rank0 ? stderr : NULL, &job->rs, err);
    else if (job->read) /* the scene's other problems too, in one report */
        render_scene_check(&job->sd, &ro, &parse_errs, err);
    job->f = st == HZ_OK ? render_scene_film(job->rs) : NULL;
    job->fp = job->f ? film_get_params(job->f) : NULL;
    if (st == HZ_OK && rank0 &&
        outputs_resolve(&job->sd, job->fp->filename, !c->output, c->preview, &job->outs, err) !=
            HZ_OK)
        st = HZ_ERROR;
    if (st == HZ_OK && scene_inputs_hash(&job->sd, &job->inputs_hash, err) != HZ_OK)
        st = HZ_ERROR;
    job->no_jitter = c->disable_pixel_jitter ||
                     (job->rs && render_scene_options(job->rs).disable_pixel_jitter);
    if (st == HZ_OK)
        set_render_id(job, render_scene_sampler(job->rs)->spp);
    if (distributed_agree(dist, st, err,
                          st == HZ_OK ? distributed_fingerprint(job->inputs_hash, job->rs) : 0,
                          stderr) != HZ_OK)
        return EXIT_SCENE;
    return 0;
}

/* --target-error: the marching step's bias, chosen before the passes
 * measure the noise; rank 0 says which step unless --quiet. */
static void choose_step(const cli *c, render_scene *rs, bool rank0,
                        const volatile sig_atomic_t *cancel, step_choice *steps, phase_times *ph)
{
    medium_work w0 = render_scene_media_work(rs);
    step_pilot_choose(rs, c->target_error, c->threads, cancel, steps);
    ph->pilot_seconds = hz_clock_seconds() - ph->render;
    medium_work w1 = render_scene_media_work(rs);
    ph->pilot_work = (medium_work){w1.majorant_bricks - w0.majorant_bricks,
                                   w1.majorant_seconds - w0.majorant_seconds};
    if (!steps->applies || !rank0 || c->quiet)
        return;
    char cache[64] = "";
    if (steps->shadow_cache > 0.0)
        snprintf(cache, sizeof cache, ", shadow cache %g", steps->shadow_cache);
    fprintf(stderr,
            "haze: --target-error %g: marching step %g voxels (shadow %g%s), estimated "
            "bias relMSE %.2g (a pilot of %d pixels, %d renders)\n",
            c->target_error, steps->step, steps->shadow_step, cache, steps->bias,
            steps->pixels, steps->renders);
}

static double mean_spp(const render_stats *st)
{
    return st->pixels > 0 ? st->samples / (double)st->pixels : 0.0;
}

/* The image's estimated relMSE: its noise and the step's bias; -1: none. */
static double image_estimate(const render_stats *st, double bias)
{
    return st->estimate >= 0.0 ? st->estimate + bias : -1.0;
}

/* The EXR header attributes of a complete render, and the text they point
 * at (which must outlive the write). */
typedef struct {
    char spp[32], passes[32], limit[32], target[32], mean_spp[32], estimated[32];
    char stepsize[64], auto_steps[64];
    film_attribute items[10];
    int count;
} image_attributes;

static void image_attributes_fill(image_attributes *a, const render_scene *rs,
                                  const char *render_id, const cli *c,
                                  const progressive_goal *goal, const render_stats *st,
                                  const step_choice *steps)
{
    bool adaptive = goal->target_error > 0, progressive = goal->deadline > 0 || adaptive;
    format_count(a->spp, sizeof a->spp, st->spp);
    format_count(a->passes, sizeof a->passes, st->passes);
    snprintf(a->limit, sizeof a->limit, "%g", c->time_limit);
    snprintf(a->target, sizeof a->target, "%g", c->target_error);
    snprintf(a->mean_spp, sizeof a->mean_spp, "%.3f", mean_spp(st));
    double estimate = image_estimate(st, goal->bias);
    snprintf(a->estimated, sizeof a->estimated, "%.3g", estimate);
    snprintf(a->stepsize, sizeof a->stepsize, "%g %g", steps->step, steps->shadow_step);
    if (steps->shadow_cache > 0.0) /* "step shadowstep shadowcache" */
        snprintf(a->stepsize, sizeof a->stepsize, "%g %g %g", steps->step, steps->shadow_step,
                 steps->shadow_cache);
    a->count = 0;
    a->items[a->count++] = (film_attribute){"haze:render", render_id};
    render_marching m;
    if (render_scene_marching(rs, &m) && m.auto_steps && m.auto_scale > 1.0) {
        /* "auto" scaled the steps: its least factor (the pilot's step includes it) */
        snprintf(a->auto_steps, sizeof a->auto_steps, "%g", m.auto_scale);
        a->items[a->count++] = (film_attribute){"haze:auto_step_scale", a->auto_steps};
    }
    if (render_scene_spectral(rs)) /* RGB images keep their bytes */
        a->items[a->count++] = (film_attribute){"haze:color", "spectral"};
    if (progressive) {
        a->items[a->count++] = (film_attribute){"haze:spp", a->spp};
        a->items[a->count++] = (film_attribute){"haze:passes", a->passes};
    }
    if (goal->deadline > 0)
        a->items[a->count++] = (film_attribute){"haze:time_limit_s", a->limit};
    if (adaptive) {
        a->items[a->count++] = (film_attribute){"haze:target_error", a->target};
        a->items[a->count++] = (film_attribute){"haze:spp_mean", a->mean_spp};
        if (estimate >= 0.0)
            a->items[a->count++] = (film_attribute){"haze:estimated_error", a->estimated};
        if (steps->applies)
            a->items[a->count++] = (film_attribute){"haze:stepsize", a->stepsize};
    }
}

/* Writes the image (and the PNG preview) of a complete render. Returns 0 or
 * the exit status. */
static int write_image(const cli *c, render_job *job, const render_stats *st,
                       const progressive_goal *goal, const step_choice *steps, double ratio,
                       phase_times *ph, hz_error *err)
{
    /* The id names the samples taken; a --target-error render's, the cap (its
     * regions take samples of their own, and merge). */
    if (!(goal->target_error > 0) && st->spp != render_scene_sampler(job->rs)->spp)
        set_render_id(job, st->spp);
    image_attributes attrs;
    image_attributes_fill(&attrs, job->rs, job->outs.render_id, c, goal, st, steps);
    film_output out = {attrs.items, attrs.count, &output_note, st->threads};
    ph->write = hz_clock_seconds();
    if (write_image_file(&job->outs, job->f, job->outs.image, ratio, &out, err) != HZ_OK ||
        (c->preview && film_write_png_with(job->f, job->outs.png, ratio, &out, err) != HZ_OK)) {
        hz_error_print(stderr, err);
        return EXIT_SCENE;
    }
    return 0;
}

/* After the image is written: a missed --target-error, and samples or rays
 * the render dropped. */
static void warn_after_render(const render_job *job, const render_stats *st,
                              const progressive_goal *goal)
{
    if (goal->target_error > 0)
        warn_target_missed(goal->target_error, image_estimate(st, goal->bias), goal->bias,
                           st->spp, render_scene_sampler(job->rs)->spp, goal->deadline > 0);
    long bad = film_nonfinite_count(job->f);
    if (bad > 0)
        fprintf(stderr, "haze: warning: %ld non-finite sample values were dropped\n", bad);
    if (st->lost_paths > 0)
        fprintf(stderr,
                "haze: warning: %llu rays crossed more than %d interfaces and were dropped "
                "(black)\n",
                (unsigned long long)st->lost_paths, WALK_MAX_CROSSINGS);
}

/* The one line on stdout that sums up a complete render (not under --quiet). */
static void print_summary(const render_job *job, const render_stats *st,
                          const progressive_goal *goal, distributed *dist)
{
    const film_params *fp = job->fp;
    bool adaptive = goal->target_error > 0, progressive = goal->deadline > 0 || adaptive;
    char wall[32];
    progress_format_duration(st->wall_seconds, wall, sizeof wall);
    double rays = (double)(st->camera_rays + st->shadow_rays);
    char lookups[64] = "";
    if (st->density_lookups > 0)
        snprintf(lookups, sizeof lookups, "%.1f density lookups/pixel", /* pixels > 0 here */
                 (double)st->density_lookups / (double)st->pixels);
    char motion[96], ranks[32] = "";
    format_motion(render_scene_motion(job->rs), motion, sizeof motion);
    if (distributed_size(dist) > 1)
        snprintf(ranks, sizeof ranks, " on %d ranks", distributed_size(dist));
    char pass_note[96] = "";
    if (adaptive)
        snprintf(pass_note, sizeof pass_note, " at most (%.2f spp mean)", mean_spp(st));
    if (progressive)
        snprintf(pass_note + strlen(pass_note), sizeof pass_note - strlen(pass_note),
                 " in %d pass%s", st->passes, st->passes == 1 ? "" : "es");
    printf("%s: %dx%d (%d x %d pixels rendered), %d spp%s, %d threads%s, %s, "
           "%.2f Mrays/s (%llu camera + %llu shadow), %s%s%s, peak memory %.1f MiB\n",
           fp->filename, fp->xres, fp->yres, fp->bounds.x1 - fp->bounds.x0,
           fp->bounds.y1 - fp->bounds.y0, st->spp, pass_note, st->threads, ranks, wall,
           st->wall_seconds > 0 ? rays / st->wall_seconds * 1e-6 : 0.0,
           (unsigned long long)st->camera_rays, (unsigned long long)st->shadow_rays, lookups,
           lookups[0] ? ", " : "", motion, peak_memory_mib());
    distributed_print_report(dist, stdout);
}

/* Renders the loaded scene (after --target-error's step pilot) and, on rank
 * 0, writes the image and reports. Returns 0 or the exit status. */
static int render_loaded_scene(const cli *c, distributed *dist, render_job *job,
                               phase_times *ph, double baseline_mib, hz_error *err)
{
    bool rank0 = distributed_rank(dist) == 0, mpi = distributed_size(dist) > 1;
    if (!mpi) /* under mpirun a signal ends the job (docs/mpi.md) */
        install_interrupt_handlers();
    renderer_options opt = {.threads = c->threads,
                            .progress = (!c->quiet && isatty(STDERR_FILENO)) ? stderr : NULL,
                            .cancel = mpi ? NULL : &interrupted,
                            .disable_pixel_jitter = job->no_jitter,
                            .timing = c->stats != 0};
    render_stats stats;
    memset(&stats, 0, sizeof stats);
    double deadline = c->time_limit > 0 ? c->start_seconds + c->time_limit : 0.0;
    progressive_goal goal = {deadline, c->target_error, 0.0};
    bool adaptive = c->target_error > 0, progressive = deadline > 0 || adaptive;
    step_choice steps = {0};
    ph->render = hz_clock_seconds();
    if (adaptive) {
        choose_step(c, job->rs, rank0, opt.cancel, &steps, ph);
        if (steps.applies)
            goal.bias = steps.bias;
    }
    hz_status st = HZ_OK;
    if (opt.cancel && *opt.cancel) /* a signal stopped the step pilot: no tile starts */
        stats.interrupted = true;
    else
        st = distributed_render(dist, job->rs, &opt, progressive ? &goal : NULL, &stats, err);
    job->abandoned = stats.abandoned > 0;
    if (st != HZ_OK) {
        if (rank0)
            hz_error_print(stderr, err);
        return EXIT_SCENE;
    }
    if (!rank0)
        return 0; /* rank 0 holds the whole film */
    double ratio = camera_imaging_ratio(render_scene_camera(job->rs), job->fp);
    if (stats.interrupted)
        return write_partial(&job->outs, job->f, ratio, &stats);
    int rc = write_image(c, job, &stats, &goal, &steps, ratio, ph, err);
    if (rc != 0)
        return rc;
    /* A signal after the last tile: the image is complete and written as
     * usual, but the run still reports the interruption. */
    int exit_code = interrupted ? EXIT_INTERRUPTED : 0;
    warn_after_render(job, &stats, &goal);
    if (!c->quiet)
        print_summary(job, &stats, &goal, dist);
    ph->end = hz_clock_seconds();
    if (c->stats)
        print_stats(job->rs, &stats, baseline_mib, ph);
    return exit_code;
}

/* Under mpirun every rank builds the scene; only rank 0 checks and writes the
 * output and prints (docs/mpi.md). */
static int run_render(const cli *c, distributed *dist)
{
    hz_error err = {0};
    double baseline_mib = c->stats ? resident_memory_mib() : 0.0;
    phase_times ph = {.start = c->start_seconds, .parse = hz_clock_seconds()};
    render_job job = {.rs = NULL};
    int exit_code = load_scene(c, dist, &job, &ph, &err);
    if (exit_code == 0)
        exit_code = render_loaded_scene(c, dist, &job, &ph, baseline_mib, &err);
    if (job.abandoned) {
        /* Abandoned render threads still read the scene: neither it nor the
         * libraries (exit's destructors) may go away under them. */
        fflush(stdout);
        fflush(stderr);
        _exit(exit_code);
    }
    render_scene_destroy(job.rs);
    if (job.read)
        scene_desc_free(&job.sd);
    return exit_code;
}

/* haze info FILE: the file's kind is told by its content, not its extension. */
static int run_info(int argc, char **argv)
{
    const char *file = NULL;
    for (int i = 2; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            fputs(usage_text, stdout);
            return 0;
        }
        if (a[0] == '-' && a[1] != '\0')
            return usage_error("unknown option '%s'", a);
        if (file)
            return usage_error("info takes one file ('%s' is extra)", a);
        file = a;
    }
    if (!file)
        return usage_error("%s", "info needs a file");
    hz_error err = {0};
    if (info_describe(file, stdout, &err) != HZ_OK) {
        hz_error_print(stderr, &err);
        return EXIT_SCENE;
    }
    return 0;
}

int main(int argc, char **argv)
{
    /* Exceeding the file size limit is then a failed write (EFBIG), reported
     * with the temporary file removed, instead of a kill that leaves it behind. */
    signal(SIGXFSZ, SIG_IGN);
    if (argc < 2)
        return usage_error("%s", "no command given");
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        fputs(usage_text, stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version")) {
        printf("haze %s\n", HAZE_VERSION);
        return 0;
    }
    if (!strcmp(cmd, "render")) {
        cli c = {0};
        c.start_seconds = hz_clock_seconds();
        for (int i = 2; i < argc; ++i)
            if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
                fputs(usage_text, stdout);
                return 0;
            }
        int rc = parse_render_args(argc, argv, &c);
        if (rc >= 0)
            return rc;
        distributed *dist = NULL;
        hz_error err = {0};
        if (distributed_create(&dist, &err) != HZ_OK) {
            hz_error_print(stderr, &err);
            return EXIT_SCENE;
        }
        rc = run_render(&c, dist);
        distributed_destroy(dist);
        return rc;
    }
    if (!strcmp(cmd, "info"))
        return run_info(argc, argv);
    if (!strcmp(cmd, "diff"))
        return diff_command(argc - 1, argv + 1, stdout, stderr);
    if (!strcmp(cmd, "merge"))
        return merge_command(argc - 1, argv + 1, stdout, stderr);
    return usage_error("unknown command '%s' (commands: render, info, diff, merge)", cmd);
}
