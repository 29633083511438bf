/* Integrator "volpath": selection (haze's default stays singlescatter),
 * parameters and their messages, thread-count determinism, and a scene
 * without media running no media code. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>

#include "cli_util.h"
#include "media_test_util.h"

static const char *scene_body =
    "WorldBegin\n"
    "LightSource \"spot\" \"rgb I\" [6 5 4] \"point3 from\" [0 2 0] \"point3 to\" [0 0 0]\n"
    "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 3 2]\nTranslate -0.9 1.2 0.6\n"
    "Shape \"sphere\" \"float radius\" 0.2\nAttributeEnd\n"
    "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES
    "/fog_sphere.vdb\" \"rgb sigma_a\" [0.1 0.1 0.1] \"rgb sigma_s\" [4 3 2]\n"
    "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
    "Shape \"sphere\" \"float radius\" 1.1\nAttributeEnd\n"
    "Shape \"trianglemesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "
    "\"integer indices\" [0 1 2 0 2 3]\n";

static const char *camera_text =
    "LookAt 0 0.5 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
    "Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 8\n";

static char *render_file(const char *name, const char *integrator, const char *args)
{
    char *scene = sfmt("%s/%s.pbrt", HAZE_TMP, name), *exr = sfmt("%s/%s.exr", HAZE_TMP, name);
    char *text = sfmt("%s%s\n%s", camera_text, integrator, scene_body);
    write_text_file(scene, text);
    char *cmd = sfmt("render '%s' --quiet -o '%s' %s", scene, exr, args);
    char out[4096];
    if (run_haze(cmd, out, sizeof out) != 0)
        fail_msg("haze %s: %s", cmd, out);
    free(cmd);
    free(text);
    free(scene);
    return exr;
}

/* The scene with Integrator line `integrator` over the medium scene body is
 * refused with a message containing `what`. */
static void expect_integrator_refused(const char *integrator, const char *what)
{
    char msg[1024];
    char *text = sfmt("%s%s\n%s", camera_text, integrator, scene_body);
    build_scene_expect_error(text, msg, sizeof msg);
    if (!strstr(msg, what))
        fail_msg("expected \"%s\" in: %s", what, msg);
    free(text);
}

/* Same scene and seed: the same bytes on one thread and on two. */
static void test_threads_byte_identical(void **state)
{
    (void)state;
    const char *vp = "Integrator \"volpath\" \"integer maxdepth\" 8";
    char *a = render_file("volpath_t1", vp, "--threads 1");
    char *b = render_file("volpath_t2", vp, "--threads 2");
    assert_true(files_equal(a, b));
    free(a);
    free(b);
}

/* pbrt-v4's "path" is volpath without media: the same image where there are
 * none; with media (which pbrt-v4's path ignores) it is refused. */
static void test_path_is_volpath_without_media(void **state)
{
    (void)state;
    const char *body = "WorldBegin\n"
                       "LightSource \"spot\" \"rgb I\" [6 5 4] \"point3 from\" [0 2 0]"
                       " \"point3 to\" [0 0 0]\n"
                       "Shape \"sphere\" \"float radius\" 0.5\n"
                       "Shape \"trianglemesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "
                       "\"integer indices\" [0 1 2 0 2 3]\n";
    char *pa = sfmt("%sIntegrator \"path\" \"integer maxdepth\" 3\n%s", camera_text, body);
    char *vp = sfmt("%sIntegrator \"volpath\" \"integer maxdepth\" 3\n%s", camera_text, body);
    render_scene *a = build_scene_or_fail(pa, NULL), *b = build_scene_or_fail(vp, NULL);
    renderer_options opt = {.threads = 2};
    render_stats st;
    hz_error err = {0};
    assert_int_equal(renderer_run(a, &opt, &st, &err), HZ_OK);
    assert_int_equal(renderer_run(b, &opt, &st, &err), HZ_OK);
    film_accumulators fa, fb;
    film_get_accumulators(render_scene_film(a), &fa);
    film_get_accumulators(render_scene_film(b), &fb);
    assert_int_equal(fa.double_count[0], fb.double_count[0]);
    assert_memory_equal(fa.doubles[0], fb.doubles[0], fa.double_count[0] * sizeof(double));
    assert_true(film_get_pixel(render_scene_film(a), 12, 8, 1.0).r > 0.0);
    render_scene_destroy(a);
    render_scene_destroy(b);
    free(pa);
    free(vp);
    expect_integrator_refused("Integrator \"path\"",
                              "test.pbrt:5:1: Integrator \"path\" with media");
}

/* pbrt-v4's bdpt, mlt, sppm and its other path tracers render with volpath
 * (the same converged image), maxdepth and regularize honoured: the same
 * pixels as volpath with them, media refused where pbrt-v4's ignores them,
 * BDPT's debugging views refused. */
static void test_other_integrators_are_volpath(void **state)
{
    (void)state;
    char *vp = render_file("stand_in_volpath",
                           "Integrator \"volpath\" \"integer maxdepth\" 3 \"bool regularize\" true",
                           "--threads 2");
    static const char *others[] = {
        /* pbrt-v3's rrthreshold (transparent-machines): read, not used */
        "Integrator \"volpath\" \"integer maxdepth\" 3 \"bool regularize\" true "
        "\"float rrthreshold\" 0",
        "Integrator \"bdpt\" \"integer maxdepth\" 3 \"bool regularize\" true",
        "Integrator \"mlt\" \"integer maxdepth\" 3 \"bool regularize\" true \"integer chains\" 9 "
        "\"float sigma\" 0.1"};
    for (int i = 0; i < 3; ++i) {
        char *name = sfmt("stand_in_%d", i);
        char *exr = render_file(name, others[i], "--threads 2");
        assert_true(exr_pixels_equal(exr, vp));
        free(exr);
        free(name);
    }
    char *other_depth = render_file("stand_in_depth", "Integrator \"bdpt\" \"integer maxdepth\" 1",
                                    "--threads 2");
    assert_false(exr_pixels_equal(other_depth, vp));
    free(other_depth);
    free(vp);
    expect_integrator_refused("Integrator \"sppm\"",
                              "test.pbrt:5:1: Integrator \"sppm\" with media");
    expect_integrator_refused("Integrator \"bdpt\" \"bool visualizestrategies\" true",
                              "\"visualizestrategies\" shows BDPT's strategies");
}

/* A scene naming no Integrator renders exactly as "singlescatter". */
static void test_default_is_singlescatter(void **state)
{
    (void)state;
    char *a = render_file("default_integrator", "", "--threads 2");
    char *b = render_file("named_singlescatter", "Integrator \"singlescatter\"", "--threads 2");
    char *c = render_file("named_volpath", "Integrator \"volpath\"", "--threads 2");
    assert_true(exr_pixels_equal(a, b)); /* headers name their scenes */
    assert_false(exr_pixels_equal(a, c));
    free(a);
    free(b);
    free(c);
    /* haze info says so too. */
    char out[8192];
    char *cmd = sfmt("info '%s/default_integrator.pbrt'", HAZE_TMP);
    assert_int_equal(run_haze(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "integrator      singlescatter, transmittance jittered"));
    free(cmd);
}

/* Material "" and "none" are pbrt-v4's no-material: the same as
 * "interface" (the medium's boundary sphere here), pixel for pixel. */
static void test_empty_material_is_interface(void **state)
{
    (void)state;
    const char *names[] = {"\"\"", "\"none\""};
    char *a = render_file("material_interface", "Integrator \"volpath\"", "--threads 2");
    for (int k = 0; k < 2; ++k) {
        char *scene = sfmt("%s/material_empty_%d.pbrt", HAZE_TMP, k);
        char *exr = sfmt("%s/material_empty_%d.exr", HAZE_TMP, k);
        char *body = strdup(scene_body);
        char *m = strstr(body, "Material \"interface\"");
        assert_non_null(m);
        char *text = sfmt("%sIntegrator \"volpath\"\n%.*sMaterial %s%s", camera_text,
                          (int)(m - body), body, names[k], m + strlen("Material \"interface\""));
        write_text_file(scene, text);
        char *cmd = sfmt("render '%s' --quiet --threads 2 -o '%s'", scene, exr);
        char out[4096];
        if (run_haze(cmd, out, sizeof out) != 0)
            fail_msg("haze %s: %s", cmd, out);
        assert_true(exr_pixels_equal(a, exr));
        free(cmd);
        free(text);
        free(body);
        free(exr);
        free(scene);
    }
    free(a);
}

/* Builds `text` with warnings captured; returns the status and fills msg with
 * the error or the warnings. */
static hz_status build_with_warnings(const char *text, char *msg, size_t n)
{
    scene_desc sd;
    hz_error err = {0};
    assert_int_equal(scene_parse_string(text, "test.pbrt", &sd, &err), HZ_OK);
    FILE *warn = tmpfile();
    assert_non_null(warn);
    render_options def = {.seed = 0};
    render_scene *rs = NULL;
    hz_status st = render_scene_create(&sd, &def, warn, &rs, &err);
    scene_desc_free(&sd);
    render_scene_destroy(rs);
    if (st != HZ_OK) {
        copy_text(msg, n, err.message);
    } else {
        rewind(warn);
        size_t got = fread(msg, 1, n - 1, warn);
        msg[got] = '\0';
    }
    fclose(warn);
    return st;
}

static void test_parameters(void **state)
{
    (void)state;
    char msg[1024];
    assert_int_equal(build_with_warnings("Integrator \"volpath\" \"string lightsampler\" "
                                         "\"exhaustive\"\nWorldBegin\n",
                                         msg, sizeof msg),
                     HZ_OK);
    assert_string_equal(msg, "test.pbrt:1:22: warning: Integrator \"volpath\" \"lightsampler\" "
                             "\"exhaustive\" is not supported; using \"bvh\"\n");
    assert_int_equal(build_with_warnings("Integrator \"volpath\" \"string lightsampler\" \"bvh\"\n"
                                         "WorldBegin\n",
                                         msg, sizeof msg),
                     HZ_OK);
    assert_string_equal(msg, "");
    assert_int_equal(build_with_warnings("Integrator \"volpath\" \"bool regularize\" true\n"
                                         "WorldBegin\n",
                                         msg, sizeof msg),
                     HZ_OK);
    assert_string_equal(msg, "");
    assert_int_equal(build_with_warnings("Integrator \"volpath\"\n"
                                         "  \"string lightsampler\" \"nearest\"\nWorldBegin\n",
                                         msg, sizeof msg),
                     HZ_ERROR);
    assert_string_equal(msg, "test.pbrt:2:3: \"lightsampler\" \"nearest\" is not one of "
                             "\"uniform\", \"power\", \"bvh\", \"exhaustive\"");
    assert_int_equal(build_with_warnings("Integrator \"volpath\" \"integer maxdepth\" -1\n"
                                         "WorldBegin\n",
                                         msg, sizeof msg),
                     HZ_ERROR);
    assert_string_equal(msg, "test.pbrt:1:22: \"maxdepth\" must be >= 0");
    /* No Integrator: silent without media, one warning with them (pbrt-v4
     * would render multiple scattering). */
    const char *medium = "MakeNamedMedium \"f\" \"string type\" \"homogeneous\"\n";
    assert_int_equal(build_with_warnings("WorldBegin\n", msg, sizeof msg), HZ_OK);
    assert_string_equal(msg, "");
    char *text = sfmt("WorldBegin\n%s", medium);
    assert_int_equal(build_with_warnings(text, msg, sizeof msg), HZ_OK);
    assert_string_equal(msg, "test.pbrt: warning: the scene names no Integrator: haze renders "
                             "single scattering (\"singlescatter\", its default), pbrt-v4 "
                             "multiple scattering (\"volpath\", maxdepth 5); name Integrator "
                             "\"volpath\" for pbrt-v4's image\n");
    free(text);
    text = sfmt("Integrator \"singlescatter\"\nWorldBegin\n%s", medium);
    assert_int_equal(build_with_warnings(text, msg, sizeof msg), HZ_OK);
    assert_string_equal(msg, "");
    free(text);
}

/* Renders n camera rays through a grid of pixels of scene a and of scene b
 * with the same samples and asserts equal radiance, sample for sample;
 * returns the sum of the green channel and fills each scene's counters. */
static double expect_same_radiance(render_scene *a, render_scene *b, int n, int cols, vec2 p0,
                                   vec2 step, integrator_counters *ca, integrator_counters *cb)
{
    const camera *cam = render_scene_camera(a);
    sampler sa = *render_scene_sampler(a), sb = *render_scene_sampler(b);
    double lit = 0.0;
    for (int i = 0; i < n; ++i) {
        camera_sample cs = {v2(p0.x + i % cols * step.x, p0.y + i / cols * step.y), v2(0.5, 0.5),
                            0.5, 1.0};
        ray_differential rd;
        assert_true(camera_generate_ray_differential(cam, cs, &rd));
        sampler_state sta, stb;
        sampler_start(&sa, i % cols, i / cols, 0, &sta);
        sampler_start(&sb, i % cols, i / cols, 0, &stb);
        double da, db;
        rgb la = render_scene_li(a, &rd, &sta, &da, ca);
        rgb lb = render_scene_li(b, &rd, &stb, &db, cb);
        assert_true(la.r == lb.r && la.g == lb.g && la.b == lb.b);
        lit += la.g;
    }
    return lit;
}

/* A scene naming no Integrator whose media include one only volpath renders
 * (a cloud, an rgbgrid) renders pbrt-v4's default, volpath maxdepth 5, with
 * one warning: the same radiance, sample for sample, as naming it; naming
 * singlescatter stays an error. */
static void test_cloud_without_integrator(void **state)
{
    (void)state;
    const char *world =
        "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n%s"
        "WorldBegin\n"
        "LightSource \"distant\" \"point3 from\" [0 1 -1] \"point3 to\" [0 0 0] \"rgb L\" [3 3 3]\n"
        "MakeNamedMedium \"c\" \"string type\" \"cloud\" \"point3 p0\" [-1 -1 -1] "
        "\"point3 p1\" [1 1 1] \"float density\" 4\n"
        "AttributeBegin\nMediumInterface \"c\" \"\"\nMaterial \"interface\"\n"
        "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n";
    char msg[1024];
    char *text = sfmt(world, "");
    assert_int_equal(build_with_warnings(text, msg, sizeof msg), HZ_OK);
    assert_string_equal(msg, "test.pbrt: warning: the scene names no Integrator and has a "
                             "\"cloud\" medium, which only \"volpath\" renders: haze renders "
                             "pbrt-v4's default, \"volpath\" with maxdepth 5\n");
    render_scene *a = build(text);
    free(text);
    text = sfmt(world, "Integrator \"volpath\" \"integer maxdepth\" 5\n");
    render_scene *b = build(text);
    free(text);
    integrator_counters ca = {0}, cb = {0};
    double lit = expect_same_radiance(a, b, 256, 16, v2(280.0, 200.0), v2(45.0, 20.0), &ca, &cb);
    assert_true(lit > 0.0);
    assert_true(ca.density_lookups > 0);
    render_scene_destroy(a);
    render_scene_destroy(b);
    text = sfmt(world, "Integrator \"singlescatter\"\n");
    assert_int_equal(build_with_warnings(text, msg, sizeof msg), HZ_ERROR);
    assert_non_null(strstr(msg, "a \"cloud\" medium needs Integrator \"volpath\""));
    free(text);
}

/* Media nothing references (no shape names one, the camera sits in none)
 * cost nothing: the radiance is the scene's without them, sample for sample,
 * under both integrators (shadow rays stay occlusion tests, no sampler
 * dimension is spent on media). */
static void test_unreferenced_media_are_free(void **state)
{
    (void)state;
    const char *fmt =
        "LookAt 0 0.5 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n%s\n"
        "WorldBegin\n%s"
        "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [0 2 -1]\n"
        "LightSource \"infinite\" \"rgb L\" [0.2 0.2 0.2]\n"
        "Shape \"sphere\" \"float radius\" 0.8\n"
        "Shape \"trianglemesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "
        "\"integer indices\" [0 1 2 0 2 3]\n";
    const char *unused = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
                         "MakeNamedMedium \"smoke\" \"string type\" \"nanovdb\" "
                         "\"string filename\" \"" HAZE_SCENES "/../volumes/box.vdb\"\n";
    const char *integ[] = {"Integrator \"singlescatter\"", "Integrator \"volpath\""};
    for (int k = 0; k < 2; ++k) {
        char *ta = sfmt(fmt, integ[k], ""), *tb = sfmt(fmt, integ[k], unused);
        render_scene *a = build(ta), *b = build(tb);
        integrator_counters ca = {.timed = true}, cb = {.timed = true};
        double lit =
            expect_same_radiance(a, b, 64, 8, v2(560.0, 300.0), v2(20.0, 20.0), &ca, &cb);
        assert_true(lit > 0.0);
        assert_int_equal(ca.shadow_rays, cb.shadow_rays);
        assert_int_equal(cb.media_ns, 0);
        assert_int_equal(cb.majorant_steps, 0);
        render_scene_destroy(a);
        render_scene_destroy(b);
        free(ta);
        free(tb);
    }
}

/* A medium elsewhere costs the shadow rays that cannot reach it nothing: a
 * ray from a surface in vacuum that crosses no box around a medium-changing
 * shape stays an occlusion test (no walk, no media time), and the radiance is
 * the scene's without the medium, sample for sample. */
static void test_media_elsewhere_are_free(void **state)
{
    (void)state;
    const char *fmt =
        "LookAt 0 0.5 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
        "Integrator \"singlescatter\"\nWorldBegin\n%s"
        "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [0 2 -1]\n"
        "Shape \"sphere\" \"float radius\" 0.8\n"
        "Shape \"trianglemesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "
        "\"integer indices\" [0 1 2 0 2 3]\n";
    const char *puff = "MakeNamedMedium \"puff\" \"string type\" \"homogeneous\"\n"
                       "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"puff\" \"\"\n"
                       "Translate 2.5 2.5 2.5\nShape \"sphere\" \"float radius\" 0.3\n"
                       "AttributeEnd\n";
    char *ta = sfmt(fmt, ""), *tb = sfmt(fmt, puff);
    render_scene *a = build(ta), *b = build(tb);
    integrator_counters ca = {.timed = true}, cb = {.timed = true};
    double lit = expect_same_radiance(a, b, 64, 8, v2(560.0, 300.0), v2(20.0, 20.0), &ca, &cb);
    assert_true(lit > 0.0);
    assert_true(cb.shadow_rays > 0);
    assert_int_equal(ca.shadow_rays, cb.shadow_rays);
    assert_int_equal(cb.media_ns, 0);
    render_scene_destroy(a);
    render_scene_destroy(b);
    free(ta);
    free(tb);
}

/* Surfaces only: the media counters stay at zero, even timed. */
static void test_no_media_no_media_code(void **state)
{
    (void)state;
    render_scene *rs = build(
        "LookAt 0 0.5 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
        "Integrator \"volpath\"\nWorldBegin\n"
        "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [0 2 -1]\n"
        "LightSource \"infinite\" \"rgb L\" [0.2 0.2 0.2]\n"
        "Shape \"sphere\" \"float radius\" 0.8\n"
        "Shape \"trianglemesh\" \"point3 P\" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "
        "\"integer indices\" [0 1 2 0 2 3]\n");
    const camera *cam = render_scene_camera(rs);
    integrator_counters c = {.timed = true};
    sampler smp = *render_scene_sampler(rs);
    rgb sum = rgb_grey(0.0);
    for (int i = 0; i < 64; ++i) {
        camera_sample cs = {v2(560.0 + i % 8 * 20.0, 300.0 + i / 8 * 20.0), v2(0.5, 0.5), 0.5,
                              1.0};
        ray_differential rd;
        assert_true(camera_generate_ray_differential(cam, cs, &rd));
        sampler_state st;
        sampler_start(&smp, i % 8, i / 8, 0, &st);
        double depth;
        sum = rgb_add(sum, render_scene_li(rs, &rd, &st, &depth, &c));
    }
    assert_true(sum.r > 0.0);
    assert_true(c.shadow_rays > 0);
    assert_int_equal(c.density_lookups, 0);
    assert_int_equal(c.majorant_steps, 0);
    assert_int_equal(c.media_ns, 0);
    render_scene_destroy(rs);
}

/* ---- every scene of scenes/: volpath maxdepth 1 against singlescatter ---- */

/* The scene file with its Integrator directive (and that directive's
 * indented continuation lines) replaced by `integrator`. */
static char *with_integrator(const char *path, const char *integrator)
{
    size_t n = 0;
    char *text = (char *)read_whole_file(path, &n);
    assert_non_null(text);
    char *out = malloc(n + strlen(integrator) + 2);
    assert_non_null(out);
    size_t k = (size_t)sprintf(out, "%s\n", integrator);
    bool skipping = false;
    for (size_t i = 0; i < n;) {
        size_t e = i;
        while (e < n && text[e] != '\n')
            ++e;
        bool directive = strncmp(text + i, "Integrator", 10) == 0;
        bool continuation = e > i && (text[i] == ' ' || text[i] == '\t');
        skipping = directive || (skipping && continuation);
        if (!skipping) {
            memcpy(out + k, text + i, e - i);
            k += e - i;
            out[k++] = '\n';
        }
        i = e + 1;
    }
    out[k] = '\0';
    free(text);
    return out;
}

typedef struct {
    const render_scene *rs;
    int x0, y0, dx, dy, cols, spp;
    pstat *out;
} spread_job;

static void spread_pixel(void *ctx, int x, int y)
{
    spread_job *j = ctx;
    j->out[y * j->cols + x] = pixel_stats_raw(j->rs, j->x0 + x * j->dx, j->y0 + y * j->dy, j->spp);
}

/* 16 x 12 pixels spread over the film, `spp` samples each. */
static pstat *spread_stats(const char *path, const char *text, int spp)
{
    scene_desc sd;
    hz_error err = {0};
    if (scene_parse_string(text, path, &sd, &err) != HZ_OK)
        fail_msg("%s: %s", path, err.message);
    render_options opt = {.seed = 0};
    render_scene *rs = NULL;
    hz_status st = render_scene_create(&sd, &opt, NULL, &rs, &err);
    scene_desc_free(&sd);
    if (st != HZ_OK)
        fail_msg("%s: %s", path, err.message);
    const camera *cam = render_scene_camera(rs);
    int w = cam->xres, h = cam->yres;
    spread_job j = {rs, w / 32, h / 24, w / 16, h / 12, 16, spp, calloc(16 * 12, sizeof(pstat))};
    assert_non_null(j.out);
    for_each_pixel_parallel(16, 12, spread_pixel, &j);
    render_scene_destroy(rs);
    return j.out;
}

/* Per 4x4 block of the spread pixels and over the image, within noise. The
 * uniform light sampler keeps the comparison's tails light: with power
 * sampling, narrow bright spot lights in fog (foggy-dof) are chosen rarely and
 * their shafts come in rare large samples, whose 64-sample error estimates are
 * too small. HAZE_DEBUG_SCENE=name, HAZE_DEBUG_SPP=n and HAZE_DEBUG_BLOCKS=1
 * narrow, deepen and detail a run. */
static void test_scenes_maxdepth_1_matches_singlescatter(void **state)
{
    (void)state;
    /* Every scene of scenes/, whatever is added there. */
    DIR *dir = opendir(HAZE_SCENES);
    assert_non_null(dir);
    char *scenes[64];
    size_t count = 0;
    for (struct dirent *de; (de = readdir(dir));) {
        size_t n = strlen(de->d_name);
        if (n > 5 && strcmp(de->d_name + n - 5, ".pbrt") == 0 && count < 64)
            scenes[count++] = sfmt("%.*s", (int)(n - 5), de->d_name);
    }
    closedir(dir);
    assert_true(count >= 9);
    for (size_t s = 0; s < count; ++s) {
        const char *only = getenv("HAZE_DEBUG_SCENE");
        if (only && strcmp(only, scenes[s]) != 0) {
            free(scenes[s]);
            continue;
        }
        int spp = getenv("HAZE_DEBUG_SPP") ? atoi(getenv("HAZE_DEBUG_SPP")) : 128;
        char *path = sfmt("%s/%s.pbrt", HAZE_SCENES, scenes[s]);
        char *ta = with_integrator(path, "Integrator \"singlescatter\" \"string transmittance\" "
                                         "\"ratio\"");
        char *tb = with_integrator(path, "Integrator \"volpath\" \"integer maxdepth\" 1");
        pstat *a = spread_stats(path, ta, spp), *b = spread_stats(path, tb, spp);
        double worst = 0.0, da = 0.0, va = 0.0, ma = 0.0, mb = 0.0;
        for (int by = 0; by < 3; ++by)
            for (int bx = 0; bx < 4; ++bx)
                for (int c = 0; c < 3; ++c) {
                    double d = 0.0, v = 0.0;
                    for (int y = 4 * by; y < 4 * by + 4; ++y)
                        for (int x = 4 * bx; x < 4 * bx + 4; ++x) {
                            const pstat *pa = &a[y * 16 + x], *pb = &b[y * 16 + x];
                            d += ch(pa->mean, c) - ch(pb->mean, c);
                            v += ch(pa->se, c) * ch(pa->se, c) + ch(pb->se, c) * ch(pb->se, c);
                            ma += ch(pa->mean, c);
                            mb += ch(pb->mean, c);
                        }
                    double zb = v > 0.0 ? fabs(d) / sqrt(v) : d != 0.0 ? INFINITY : 0.0;
                    if (getenv("HAZE_DEBUG_BLOCKS") && zb > 4.0)
                        for (int y = 4 * by; y < 4 * by + 4; ++y)
                            for (int x = 4 * bx; x < 4 * bx + 4; ++x)
                                print_message("  %d %d c%d: %g +- %g vs %g +- %g\n", x, y, c,
                                              ch(a[y * 16 + x].mean, c), ch(a[y * 16 + x].se, c),
                                              ch(b[y * 16 + x].mean, c), ch(b[y * 16 + x].se, c));
                    worst = fmax(worst, zb);
                    da += d;
                    va += v;
                }
        double z = va > 0.0 ? fabs(da) / sqrt(va) : 0.0;
        if (verbose())
            print_message("%-14s mean %.5f vs %.5f: image z %.2f, worst block z %.2f\n",
                          scenes[s], ma / 576, mb / 576, z, worst);
        assert_true(z < 4.0);
        assert_true(worst < 4.5);
        free(a);
        free(b);
        free(ta);
        free(tb);
        free(path);
        free(scenes[s]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_byte_identical),
        cmocka_unit_test(test_default_is_singlescatter),
        cmocka_unit_test(test_path_is_volpath_without_media),
        cmocka_unit_test(test_other_integrators_are_volpath),
        cmocka_unit_test(test_empty_material_is_interface),
        cmocka_unit_test(test_parameters),
        cmocka_unit_test(test_cloud_without_integrator),
        cmocka_unit_test(test_unreferenced_media_are_free),
        cmocka_unit_test(test_media_elsewhere_are_free),
        cmocka_unit_test(test_no_media_no_media_code),
        cmocka_unit_test(test_scenes_maxdepth_1_matches_singlescatter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
