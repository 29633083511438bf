#define _POSIX_C_SOURCE 200809L
/* Regions for render farms (issue 9): haze render --pixelbounds/--cropwindow
 * renders a region to an EXR whose data window is that region, and haze merge
 * assembles regions into a file byte-identical to the full render (fog with
 * every AOV in float, the same in savefp16, the VDB smoke scene; quadrants of
 * uneven size and a 3x2 crop window split, rendered with 1 and 2 threads);
 * the regions of a --target-error render merge, with the whole image's
 * samples, estimate and steps in the header.
 * Refused merges (gap, overlap, display window, channels, pixel types,
 * attributes, partial render, part outside its display window, missing file)
 * exit 1 with a message naming the files and regions and leave an existing
 * output untouched; bad options exit 2. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli_util.h"
#include "film/exr.h"

enum { W = 37, H = 29, XS = 18, YS = 14 }; /* quadrant splits: uneven on purpose */

static char dir[512];

/* Film parameters of the scene variants. */
#define AOVS "\"bool writedepth\" true \"bool writevariance\" true \"bool writesamplecount\" true"

/* A small lit sphere and floor in homogeneous fog (the camera in it). */
static void write_scene(const char *name, int w, int h, const char *film_extra)
{
    char path[1200], text[4096];
    snprintf(path, sizeof path, "%s/%s.pbrt", dir, name);
    snprintf(text, sizeof text,
             "LookAt 0 1 -4  0 0.5 0  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 40\n"
             "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
             "    \"string filename\" \"unused.exr\" %s\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
             "WorldBegin\n"
             "LightSource \"point\" \"point3 from\" [1 3 -1] \"rgb I\" [8 7 6]\n"
             "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
             "    \"rgb sigma_a\" [0.05 0.05 0.05] \"rgb sigma_s\" [0.3 0.3 0.3]\n"
             "MediumInterface \"\" \"fog\"\n"
             "Material \"diffuse\" \"rgb reflectance\" [0.5 0.4 0.3]\n"
             "Shape \"sphere\" \"float radius\" 0.7\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "    \"point3 P\" [-5 -0.7 -5 5 -0.7 -5 5 -0.7 5 -5 -0.7 5]\n",
             w, h, film_extra);
    write_text_file(path, text);
}

/* The same scene rendered spectrally: volpath in a coloured fog (--color
 * auto picks spectral rendering for it). */
static void write_spectral_scene(const char *name)
{
    char path[1200], text[4096];
    snprintf(path, sizeof path, "%s/%s.pbrt", dir, name);
    snprintf(text, sizeof text,
             "LookAt 0 1 -4  0 0.5 0  0 1 0\n"
             "Camera \"perspective\" \"float fov\" 40\n"
             "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
             "    \"string filename\" \"unused.exr\" %s\n"
             "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
             "Integrator \"volpath\"\n"
             "WorldBegin\n"
             "LightSource \"point\" \"point3 from\" [1 3 -1] \"blackbody I\" [2700]\n"
             "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
             "    \"rgb sigma_a\" [0.02 0.05 0.1] \"rgb sigma_s\" [0.3 0.2 0.1]\n"
             "MediumInterface \"\" \"fog\"\n"
             "Material \"conductor\"\n"
             "Shape \"sphere\" \"float radius\" 0.7\n"
             "Material \"diffuse\" \"rgb reflectance\" [0.5 0.4 0.3]\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "    \"point3 P\" [-5 -0.7 -5 5 -0.7 -5 5 -0.7 5 -5 -0.7 5]\n",
             W, H, AOVS);
    write_text_file(path, text);
}

static void path_in(char *buf, size_t n, const char *name)
{
    snprintf(buf, n, "%s/%s", dir, name);
}

/* The scene file of a variant: a name under dir, or an absolute path. */
static void scene_path(char *buf, size_t n, const char *scene)
{
    if (scene[0] == '/')
        snprintf(buf, n, "%s", scene);
    else
        snprintf(buf, n, "%s/%s.pbrt", dir, scene);
}

/* haze render SCENE -o dir/OUT EXTRA; fails the test unless it exits 0. */
static void render(const char *scene, const char *out, const char *extra)
{
    char s[1200], o[1200], args[4096], msg[8192];
    scene_path(s, sizeof s, scene);
    path_in(o, sizeof o, out);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet %s", s, o, extra);
    if (run_haze(args, msg, sizeof msg) != 0)
        fail_msg("haze %s:\n%s", args, msg);
}

/* haze merge dir/PARTS... -o dir/OUT (names separated by spaces); returns the
 * exit status, output in msg. Killed after 60 s: a merge must never hang
 * (on a FIFO part). */
static int merge(const char *parts, const char *out, char *msg, size_t n)
{
    char args[4096];
    int len = snprintf(args, sizeof args, "merge");
    char copy[2048];
    snprintf(copy, sizeof copy, "%s", parts);
    for (char *save = NULL, *p = strtok_r(copy, " ", &save); p; p = strtok_r(NULL, " ", &save))
        len += snprintf(args + len, sizeof args - (size_t)len, " '%s/%s'", dir, p);
    snprintf(args + len, sizeof args - (size_t)len, " -o '%s/%s'", dir, out);
    return run_haze_within(60, args, msg, n);
}

static void assert_same_bytes(const char *a, const char *b)
{
    char pa[1200], pb[1200];
    path_in(pa, sizeof pa, a);
    path_in(pb, sizeof pb, b);
    size_t na = 0, nb = 0;
    unsigned char *da = read_whole_file(pa, &na), *db = read_whole_file(pb, &nb);
    assert_non_null(da);
    assert_non_null(db);
    if (na != nb || memcmp(da, db, na) != 0)
        fail_msg("%s (%zu bytes) and %s (%zu bytes) differ", a, na, b, nb);
    free(da);
    free(db);
}

static void read_exr(const char *name, exr_image *img)
{
    char p[1200];
    hz_error err = {0};
    path_in(p, sizeof p, name);
    if (exr_read(p, img, &err) != HZ_OK)
        fail_msg("%s", err.message);
}

/* Renders the four quadrants of `scene` as PREFIX00..PREFIX11 (x then y
 * half; alternately 1 and 2 threads). */
static void render_quadrants(const char *scene, const char *prefix, const char *extra)
{
    const int xs[3] = {0, XS, W}, ys[3] = {0, YS, H};
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            char out[256], opts[512];
            snprintf(out, sizeof out, "%s%d%d.exr", prefix, i, j);
            snprintf(opts, sizeof opts, "%s --threads %d --pixelbounds %d,%d,%d,%d", extra,
                     1 + (i + j) % 2, xs[i], xs[i + 1], ys[j], ys[j + 1]);
            render(scene, out, opts);
        }
}

/* The region file holds exactly the full render's pixels of its region. */
static void check_region_file(const char *full_name, const char *part_name, int x0, int x1, int y0,
                              int y1)
{
    exr_image full, part;
    read_exr(full_name, &full);
    read_exr(part_name, &part);
    assert_int_equal(part.display_width, W);
    assert_int_equal(part.display_height, H);
    assert_int_equal(part.data_x0, x0);
    assert_int_equal(part.data_y0, y0);
    assert_int_equal(part.width, x1 - x0);
    assert_int_equal(part.height, y1 - y0);
    assert_int_equal(part.channel_count, full.channel_count);
    for (int c = 0; c < full.channel_count; c++) {
        assert_string_equal(part.channels[c].name, full.channels[c].name);
        assert_int_equal(part.channels[c].half, full.channels[c].half);
        for (int y = y0; y < y1; y++)
            assert_memory_equal(part.channels[c].pixels + (size_t)(y - y0) * (size_t)part.width,
                                full.channels[c].pixels + (size_t)y * W + (size_t)x0,
                                (size_t)part.width * sizeof(float));
    }
    exr_image_free(&full);
    exr_image_free(&part);
}

static void quadrant_case(const char *scene, const char *prefix, const char *extra,
                          const char *const *channels, int channel_count, int half_channels)
{
    char full[256], parts[1024], merged[256], msg[4096];
    snprintf(full, sizeof full, "%sfull.exr", prefix);
    snprintf(merged, sizeof merged, "%smerged.exr", prefix);
    render(scene, full, extra);
    render_quadrants(scene, prefix, extra);
    snprintf(parts, sizeof parts, "%s00.exr %s10.exr %s01.exr %s11.exr", prefix, prefix, prefix,
             prefix);
    if (merge(parts, merged, msg, sizeof msg) != 0)
        fail_msg("merge: %s", msg);
    assert_string_equal(msg, "");
    assert_same_bytes(merged, full);
    /* Any order of the parts gives the same file. */
    snprintf(parts, sizeof parts, "%s11.exr %s01.exr %s10.exr %s00.exr", prefix, prefix, prefix,
             prefix);
    assert_int_equal(merge(parts, merged, msg, sizeof msg), 0);
    assert_same_bytes(merged, full);
    char q[256];
    snprintf(q, sizeof q, "%s10.exr", prefix);
    check_region_file(full, q, XS, W, 0, YS);
    /* The channels (sorted by the EXR writer) and their types are what was asked. */
    exr_image img;
    read_exr(merged, &img);
    assert_int_equal(img.channel_count, channel_count);
    int halves = 0;
    for (int c = 0; c < channel_count; c++) {
        assert_string_equal(img.channels[c].name, channels[c]);
        halves += img.channels[c].half;
    }
    assert_int_equal(halves, half_channels);
    assert_int_equal(img.data_x0, 0);
    assert_int_equal(img.width, W);
    exr_image_free(&img);
}

static const char *const all_channels[] = {"A", "B", "G", "R", "SampleCount.Y",
                                           "Variance.B", "Variance.G", "Variance.R", "Z"};

static void test_quadrants_float(void **state)
{
    (void)state;
    quadrant_case("fog", "fog", "", all_channels, 9, 0);
}

/* Spectral rendering (the wavelengths are the sampler's): regions merge to
 * the whole image byte for byte too. */
static void test_quadrants_spectral(void **state)
{
    (void)state;
    quadrant_case("fogsp", "sp", "", all_channels, 9, 0);
    exr_image img;
    read_exr("spfull.exr", &img);
    bool spectral = false;
    for (int i = 0; i < img.attribute_count; ++i)
        spectral |= strcmp(img.attribute_names[i], "haze:color") == 0 &&
                    strcmp(img.attribute_values[i], "spectral") == 0;
    exr_image_free(&img);
    assert_true(spectral);
}

static void test_quadrants_fp16(void **state)
{
    (void)state;
    quadrant_case("fog16", "h", "--seed 3", all_channels, 9, 4); /* R G B A half, AOVs float */
}

/* The VDB smoke regression scene (grid medium, jittered marching), 40x50. */
static void test_quadrants_smoke(void **state)
{
    (void)state;
    const char *scene = HAZE_TESTS "/regression/scenes/smoke.pbrt";
    render(scene, "smfull.exr", "--spp 2");
    const int xs[3] = {0, 23, 40}, ys[3] = {0, 17, 50};
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            char out[64], opts[256];
            snprintf(out, sizeof out, "sm%d%d.exr", i, j);
            snprintf(opts, sizeof opts, "--spp 2 --threads %d --pixelbounds %d,%d,%d,%d",
                     1 + j, xs[i], xs[i + 1], ys[j], ys[j + 1]);
            render(scene, out, opts);
        }
    char msg[4096];
    if (merge("sm00.exr sm01.exr sm10.exr sm11.exr", "smmerged.exr", msg, sizeof msg) != 0)
        fail_msg("merge: %s", msg);
    assert_same_bytes("smmerged.exr", "smfull.exr");
}

/* The regions of a --target-error render of the smoke scene (each stops on
 * its own estimate; each part's pilot picks its step) merge: the pixels are
 * the parts', the header has the most samples and passes, the means over the
 * pixels of the mean samples and of the estimate, and the parts' steps. A
 * fixed-spp part does not mix with them. */
static void test_target_error_parts(void **state)
{
    (void)state;
    const char *scene = HAZE_TESTS "/regression/scenes/smoke.pbrt";
    render(scene, "te0.exr", "--target-error 3e-2 --spp 64 --pixelbounds 0,40,0,12");
    render(scene, "te1.exr", "--target-error 3e-2 --spp 64 --pixelbounds 0,40,12,50 --threads 1");
    render(scene, "fixed1.exr", "--spp 4 --pixelbounds 0,40,12,50");
    char msg[4096];
    if (merge("te0.exr te1.exr", "temerged.exr", msg, sizeof msg) != 0)
        fail_msg("merge: %s", msg);
    exr_image a, b, m;
    read_exr("te0.exr", &a);
    read_exr("te1.exr", &b);
    read_exr("temerged.exr", &m);
    for (int c = 0; c < m.channel_count; ++c)
        for (int y = 0; y < m.height; ++y) {
            const exr_image *p = y < 12 ? &a : &b;
            assert_memory_equal(m.channels[c].pixels + (size_t)y * 40,
                                p->channels[c].pixels + (size_t)(y - p->data_y0) * 40,
                                40 * sizeof(float));
        }
    double wa = 40.0 * 12.0, wb = 40.0 * 38.0;
    const char *sa = exr_attribute(&a, "haze:spp"), *sb = exr_attribute(&b, "haze:spp");
    assert_int_equal(atoi(exr_attribute(&m, "haze:spp")), atoi(sa) > atoi(sb) ? atoi(sa) : atoi(sb));
    const char *names[] = {"haze:spp_mean", "haze:estimated_error"};
    for (int i = 0; i < 2; ++i) {
        double va = atof(exr_attribute(&a, names[i])), vb = atof(exr_attribute(&b, names[i]));
        double want = (va * wa + vb * wb) / (wa + wb), got = atof(exr_attribute(&m, names[i]));
        if (fabs(got - want) > 5e-3 * want) /* the header's values have 3 digits */
            fail_msg("%s: %g, want %g (%g and %g)", names[i], got, want, va, vb);
    }
    assert_true(atof(exr_attribute(&m, "haze:estimated_error")) <= 3e-2);
    const char *ta = exr_attribute(&a, "haze:stepsize"), *tb = exr_attribute(&b, "haze:stepsize");
    char steps[256];
    snprintf(steps, sizeof steps, strcmp(ta, tb) ? "%s; %s" : "%s", ta, tb);
    assert_string_equal(exr_attribute(&m, "haze:stepsize"), steps);
    assert_string_equal(exr_attribute(&m, "haze:render"), exr_attribute(&a, "haze:render"));
    exr_image_free(&a);
    exr_image_free(&b);
    exr_image_free(&m);
    assert_int_equal(merge("te0.exr fixed1.exr", "temixed.exr", msg, sizeof msg), 1);
    assert_non_null(strstr(msg, "merge: "));
}

/* --cropwindow thirds by halves: pbrt-v4's ceil rule gives columns [0,13),
 * [13,25), [25,37) and rows [0,15), [15,29); shared edges need no care. */
static void test_cropwindow(void **state)
{
    (void)state;
    const char *xf[4] = {"0", "0.33333333", "0.66666667", "1"}, *yf[3] = {"0", "0.5", "1"};
    char parts[1024] = "", msg[4096];
    size_t len = 0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++) {
            char out[64], opts[256];
            snprintf(out, sizeof out, "crop%d%d.exr", i, j);
            snprintf(opts, sizeof opts, "--threads %d --cropwindow %s,%s,%s,%s", 1 + i % 2, xf[i],
                     xf[i + 1], yf[j], yf[j + 1]);
            render("fog", out, opts);
            len += (size_t)snprintf(parts + len, sizeof parts - len, "%s%s", len ? " " : "", out);
        }
    render("fog", "cropfull.exr", "--cropwindow 0,1,0,1");
    assert_same_bytes("cropfull.exr", "fogfull.exr"); /* the whole window is the full render */
    if (merge(parts, "cropmerged.exr", msg, sizeof msg) != 0)
        fail_msg("merge: %s", msg);
    assert_same_bytes("cropmerged.exr", "fogfull.exr");
    check_region_file("fogfull.exr", "crop11.exr", 13, 25, 15, 29);
    check_region_file("fogfull.exr", "crop00.exr", 0, 13, 0, 15);
}

/* The command-line region overrides the Film's own pixelbounds. */
static void test_overrides_film(void **state)
{
    (void)state;
    write_scene("fogpb", W, H, AOVS " \"integer pixelbounds\" [0 5 0 5]");
    render("fogpb", "pbover.exr", "--pixelbounds 18,37,0,14");
    check_region_file("fogfull.exr", "pbover.exr", XS, W, 0, YS);
    render("fogpb", "pbown.exr", "");
    check_region_file("fogfull.exr", "pbown.exr", 0, 5, 0, 5);
    /* A frame too large to render whole (the film limit is 64 GiB) renders in regions. */
    write_scene("huge", 200000, 150000, "");
    char s[1200], msg[4096], args[4096];
    scene_path(s, sizeof s, "huge");
    snprintf(args, sizeof args, "render '%s' -o '%s/hugefull.exr' --quiet", s, dir);
    assert_int_equal(run_haze(args, msg, sizeof msg), 1);
    assert_non_null(strstr(msg, "Film of 200000x150000 pixels would need"));
    render("huge", "huge.exr", "--pixelbounds 100000,100008,75000,75004");
    exr_image img;
    read_exr("huge.exr", &img);
    assert_int_equal(img.display_width, 200000);
    assert_int_equal(img.display_height, 150000);
    assert_int_equal(img.data_x0, 100000);
    assert_int_equal(img.data_y0, 75000);
    assert_int_equal(img.width, 8);
    assert_int_equal(img.height, 4);
    exr_image_free(&img);
}

/* A refused merge: exit 1, the message, and the existing output untouched,
 * with no temporary file left beside it. */
static void expect_refused(const char *parts, const char *expected)
{
    char out[1200], msg[4096];
    path_in(out, sizeof out, "keep.exr");
    write_text_file(out, "an existing output\n");
    int rc = merge(parts, "keep.exr", msg, sizeof msg);
    if (rc != 1 || !strstr(msg, expected))
        fail_msg("merge %s: exit %d, expected 1 and \"%s\", got:\n%s", parts, rc, expected, msg);
    assert_non_null(strstr(msg, "haze: merge: "));
    const char *nl = strchr(msg, '\n');
    assert_true(nl && nl[1] == '\0'); /* one line */
    size_t n = 0;
    unsigned char *bytes = read_whole_file(out, &n);
    assert_non_null(bytes);
    assert_int_equal(n, strlen("an existing output\n"));
    assert_memory_equal(bytes, "an existing output\n", n);
    free(bytes);
    assert_int_equal(count_temporaries_in(dir), 0); /* no temporary file left behind */
}

/* Writes dir/OUT: the EXR `in` with its data window moved to (x0, y0) and
 * an extra attribute (name NULL: none). */
static void rewrite(const char *in, const char *out, int x0, int y0, const char *name,
                    const char *value)
{
    exr_image img;
    hz_error err = {0};
    char p[1200];
    read_exr(in, &img);
    img.data_x0 = x0;
    img.data_y0 = y0;
    if (name)
        assert_int_equal(exr_image_add_attribute(&img, name, value, &err), HZ_OK);
    path_in(p, sizeof p, out);
    if (exr_write(p, &img, &err) != HZ_OK)
        fail_msg("%s", err.message);
    exr_image_free(&img);
}

static void test_refusals(void **state)
{
    (void)state;
    /* Parts of other images: 38 pixels wide; no statistics; half R G B A. */
    write_scene("fog38", W + 1, H, AOVS);
    render("fog38", "w38.exr", "--pixelbounds 18,38,14,29");
    write_scene("fogz", W, H, "\"bool writedepth\" true");
    render("fogz", "z11.exr", "--pixelbounds 18,37,14,29");
    render("fog16", "h11b.exr", "--pixelbounds 18,37,14,29");
    render("fog", "ov.exr", "--pixelbounds 10,30,0,14");
    rewrite("fog11.exr", "partial11.exr", XS, YS, "haze:partial", "true");
    rewrite("fog11.exr", "attr11.exr", XS, YS, "owner", "someone");
    rewrite("fog11.exr", "out11.exr", XS + 1, YS, NULL, NULL);

    expect_refused("fog00.exr fog10.exr fog01.exr",
                   "merge: no part covers pixels [18,37)x[14,29) of the 37x29 image (the parts "
                   "cover 788 of 1073 pixels)");
    expect_refused("fog10.exr fog01.exr fog11.exr",
                   "merge: no part covers pixels [0,18)x[0,14) of the 37x29 image");
    expect_refused("fog00.exr ov.exr fog01.exr fog11.exr",
                   "merge: " HAZE_TMP "/regions/fog00.exr [0,18)x[0,14) overlaps " HAZE_TMP
                   "/regions/ov.exr [10,30)x[0,14)");
    expect_refused("fog00.exr fog10.exr fog01.exr fog11.exr fog10.exr",
                   "/regions/fog10.exr is given twice");
    expect_refused("fog00.exr fog10.exr fog01.exr w38.exr",
                   "/regions/w38.exr has a 38x29 display window but " HAZE_TMP
                   "/regions/fog00.exr has 37x29: parts of different images");
    expect_refused("fog00.exr fog10.exr fog01.exr z11.exr",
                   "/regions/z11.exr has channels A,B,G,R,Z (float) but " HAZE_TMP
                   "/regions/fog00.exr has A,B,G,R,SampleCount.Y,Variance.B,Variance.G,"
                   "Variance.R,Z (float)");
    expect_refused("fog00.exr fog10.exr fog01.exr h11b.exr",
                   "/regions/h11b.exr has channels A:half,B:half,G:half,R:half,SampleCount.Y:float,"
                   "Variance.B:float,Variance.G:float,Variance.R:float,Z:float but");
    expect_refused("fog00.exr fog10.exr fog01.exr partial11.exr",
                   "/regions/partial11.exr is a partial render (interrupted: header attribute "
                   "haze:partial); render its region again");
    expect_refused("fog00.exr fog10.exr fog01.exr attr11.exr",
                   "/regions/attr11.exr has header attribute \"owner\" but " HAZE_TMP
                   "/regions/fog00.exr does not");
    expect_refused("fog00.exr fog10.exr fog01.exr out11.exr",
                   "/regions/out11.exr [19,38)x[14,29) is not inside its 37x29 display window");
    expect_refused("fog00.exr fog10.exr missing.exr fog11.exr",
                   "merge: " HAZE_TMP "/regions/missing.exr: cannot read EXR");
    /* A FIFO part is refused, not waited on for a writer. */
    char fifo[1200];
    path_in(fifo, sizeof fifo, "fifo11.exr");
    unlink(fifo);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    expect_refused("fog00.exr fog10.exr fog01.exr fifo11.exr",
                   "merge: " HAZE_TMP "/regions/fifo11.exr: cannot read: is a FIFO; haze reads "
                   "only regular files");
}

/* Usage errors of haze render dir/fog.pbrt OPTS: exit 2 with the message and
 * the help hint; nothing rendered. */
static void expect_usage(const char *opts, const char *expected)
{
    char msg[4096], out[1200], full[4096];
    path_in(out, sizeof out, "usage.exr");
    remove(out);
    snprintf(full, sizeof full, "render '%s/fog.pbrt' -o '%s' --quiet %s", dir, out, opts);
    int rc = run_haze(full, msg, sizeof msg);
    if (rc != 2 || !strstr(msg, expected) || !strstr(msg, "Try 'haze"))
        fail_msg("haze %s: exit %d, expected 2 and \"%s\", got:\n%s", full, rc, expected, msg);
    struct stat st;
    assert_int_not_equal(stat(out, &st), 0);
}

static void test_cli_errors(void **state)
{
    (void)state;
    struct {
        const char *opts, *message;
    } cases[] = {
        {"--pixelbounds 0,18,0", "--pixelbounds needs four integers x0,x1,y0,y1, not '0,18,0'"},
        {"--pixelbounds 0,18,0,14,3", "--pixelbounds needs four integers x0,x1,y0,y1, not '0,18,0,14,3'"},
        {"--pixelbounds 0,1.5,0,14", "--pixelbounds needs four integers x0,x1,y0,y1, not '0,1.5,0,14'"},
        {"--pixelbounds a,b,c,d", "--pixelbounds needs four integers x0,x1,y0,y1, not 'a,b,c,d'"},
        {"--pixelbounds ''", "--pixelbounds needs four integers x0,x1,y0,y1, not ''"},
        {"--pixelbounds", "option --pixelbounds needs a value"},
        {"--pixelbounds 5,5,0,14",
         "--pixelbounds 5,5,0,14: pixel bounds [5,5)x[0,14) are empty (need x0 < x1 and y0 < y1)"},
        {"--pixelbounds 0,18,14,2", "pixel bounds [0,18)x[14,2) are empty"},
        {"--pixelbounds 0,38,0,14",
         "--pixelbounds 0,38,0,14: pixel bounds [0,38)x[0,14) are not inside the 37x29 image "
         "(0 <= x0 < x1 <= 37, 0 <= y0 < y1 <= 29)"},
        {"--pixelbounds -1,5,0,14", "pixel bounds [-1,5)x[0,14) are not inside the 37x29 image"},
        {"--pixelbounds 40,50,30,40", "pixel bounds [40,50)x[30,40) are not inside"},
        {"--cropwindow 0,0.5,0", "--cropwindow needs four numbers x0,x1,y0,y1, not '0,0.5,0'"},
        {"--cropwindow 0,x,0,1", "--cropwindow needs four numbers x0,x1,y0,y1, not '0,x,0,1'"},
        {"--cropwindow nan,1,0,1", "--cropwindow needs four numbers x0,x1,y0,y1, not 'nan,1,0,1'"},
        {"--cropwindow 0,1.5,0,1", "--cropwindow 0,1.5,0,1: crop window values must lie in [0, 1], got 1.5"},
        {"--cropwindow -0.1,1,0,1", "crop window values must lie in [0, 1], got -0.1"},
        {"--cropwindow 0.5,0.5,0,1", "crop window [0.5,0.5]x[0,1] is empty (need x0 < x1 and y0 < y1)"},
        {"--cropwindow 0.001,0.002,0,1",
         "crop window [0.001,0.002]x[0,1] covers no pixel of the 37x29 image"},
        {"--pixelbounds 0,18,0,14 --cropwindow 0,1,0,1", "--pixelbounds and --cropwindow cannot both be given"},
        {"--cropwindow 0,1,0,1 --pixelbounds 0,18,0,14", "--pixelbounds and --cropwindow cannot both be given"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        expect_usage(cases[i].opts, cases[i].message);
    /* merge usage */
    char msg[4096];
    assert_int_equal(run_haze("merge", msg, sizeof msg), 2);
    assert_non_null(strstr(msg, "haze: merge needs at least one part"));
    assert_int_equal(run_haze("merge a.exr", msg, sizeof msg), 2);
    assert_non_null(strstr(msg, "haze: merge needs an output: -o FULL.exr"));
    assert_int_equal(run_haze("merge a.exr -o", msg, sizeof msg), 2);
    assert_non_null(strstr(msg, "haze: merge: option -o needs a value"));
    assert_int_equal(run_haze("merge a.exr --frobnicate -o b.exr", msg, sizeof msg), 2);
    assert_non_null(strstr(msg, "haze: merge: unknown option '--frobnicate'"));
    assert_int_equal(run_haze("merge --help", msg, sizeof msg), 0);
    assert_non_null(strstr(msg, "usage: haze merge PART.exr... -o FULL.exr"));
    assert_int_equal(run_haze("render --help", msg, sizeof msg), 0);
    assert_non_null(strstr(msg, "--pixelbounds x0,x1,y0,y1"));
    assert_non_null(strstr(msg, "--cropwindow x0,x1,y0,y1"));
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "%s/regions", HAZE_TMP);
    mkdir(dir, 0755);
    write_scene("fog", W, H, AOVS);
    write_spectral_scene("fogsp");
    write_scene("fog16", W, H, AOVS " \"bool savefp16\" true");
    return 0;
}

int main(void)
{
    /* In order: later tests use the files of earlier ones. */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quadrants_float),
        cmocka_unit_test(test_quadrants_spectral), cmocka_unit_test(test_quadrants_fp16),
        cmocka_unit_test(test_quadrants_smoke), cmocka_unit_test(test_target_error_parts),
        cmocka_unit_test(test_cropwindow),
        cmocka_unit_test(test_overrides_film),  cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_cli_errors),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
