#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assert_util.h"
#include "film/exr.h"
#include "film/png.h"
#include <png.h>
#include "core/noise.h"
#include "textures/texture.h"

typedef struct {
    scene_desc sd;
    texture_set *set;
} built;

/* Parses "WorldBegin <textures>" (named file `name` in HAZE_TMP, so that
 * image names resolve there) and builds its textures; the error of the
 * first failing texture goes to *err. */
static hz_status build(const char *textures, built *b, hz_error *err)
{
    char src[4096], name[512];
    snprintf(src, sizeof src, "WorldBegin\n%s", textures);
    snprintf(name, sizeof name, "%s/textures.pbrt", HAZE_TMP);
    if (scene_parse_string(src, name, &b->sd, err) != HZ_OK)
        return HZ_ERROR;
    hz_errors errs;
    memset(&errs, 0, sizeof errs);
    hz_status st = texture_set_create(&b->sd, transform_identity(), &errs, &b->set, err);
    if (st == HZ_OK && errs.count > 0)
        return hz_errors_finish(&errs, NULL, 0, err);
    free(errs.items);
    return st;
}

static void unbuild(built *b)
{
    texture_set_destroy(b->set);
    scene_desc_free(&b->sd);
}

static rgb at(const built *b, const char *name, bool spectrum, double u, double v)
{
    const texture *t = texture_set_find(b->set, name, spectrum);
    if (!t)
        fail_msg("no texture \"%s\"", name);
    texture_ctx c = {.u = u, .v = v};
    return texture_eval(t, &c);
}

static void assert_rgb(rgb got, double r, double g, double bl, double tol)
{
    assert_near(got.r, r, tol);
    assert_near(got.g, g, tol);
    assert_near(got.b, bl, tol);
}

static void expect_error(const char *textures, const char *want)
{
    built b;
    hz_error err;
    memset(&b, 0, sizeof b);
    hz_status st = build(textures, &b, &err);
    unbuild(&b);
    assert_int_equal(st, HZ_ERROR);
    if (!strstr(err.message, want))
        fail_msg("got \"%s\", want \"%s\"", err.message, want);
    assert_non_null(err.loc.file);
}

static void test_constant_scale_mix(void **state)
{
    (void)state;
    built b;
    hz_error err;
    assert_int_equal(build("Texture \"c\" \"spectrum\" \"constant\" \"rgb value\" [0.2 0.4 0.6]\n"
                           "Texture \"f\" \"float\" \"constant\" \"float value\" 0.25\n"
                           "Texture \"one\" \"float\" \"constant\"\n"
                           "Texture \"s\" \"spectrum\" \"scale\" \"texture tex\" \"c\" "
                           "\"texture scale\" \"f\"\n"
                           "Texture \"m\" \"spectrum\" \"mix\" \"texture tex1\" \"c\" "
                           "\"rgb tex2\" [1 1 1] \"texture amount\" \"f\"\n"
                           "Texture \"md\" \"float\" \"mix\"\n",
                           &b, &err),
                     HZ_OK);
    assert_rgb(at(&b, "c", true, 0.3, 0.7), 0.2, 0.4, 0.6, 0);
    assert_near(at(&b, "f", false, 0, 0).r, 0.25, 0);
    assert_near(at(&b, "one", false, 0, 0).r, 1.0, 0); /* pbrt-v4's default value */
    assert_rgb(at(&b, "s", true, 0, 0), 0.05, 0.1, 0.15, 1e-15);
    assert_rgb(at(&b, "m", true, 0, 0), 0.4, 0.55, 0.7, 1e-15);
    assert_near(at(&b, "md", false, 0, 0).r, 0.5, 0); /* tex1 0, tex2 1, amount 0.5 */
    assert_null(texture_set_find(b.set, "f", true));
    unbuild(&b);
}

static void test_checkerboard(void **state)
{
    (void)state;
    built b;
    hz_error err;
    assert_int_equal(build("Texture \"k\" \"float\" \"checkerboard\" \"float uscale\" 4 "
                           "\"float vscale\" 2 \"float udelta\" 0.5\n"
                           "Texture \"d\" \"float\" \"checkerboard\"\n",
                           &b, &err),
                     HZ_OK);
    /* s = 4u + 0.5, t = 2v: floor(s) + floor(t) even -> tex1 (1), odd -> tex2 (0). */
    assert_near(at(&b, "k", false, 0.01, 0.1).r, 1.0, 0);  /* s 0.54, t 0.2 */
    assert_near(at(&b, "k", false, 0.2, 0.1).r, 0.0, 0);   /* s 1.3 */
    assert_near(at(&b, "k", false, 0.2, 0.6).r, 1.0, 0);   /* s 1.3, t 1.2 */
    assert_near(at(&b, "k", false, -0.2, 0.1).r, 0.0, 0);  /* s -0.3: square -1 */
    assert_near(at(&b, "d", false, 0.5, 0.5).r, 1.0, 0);
    assert_near(at(&b, "d", false, 1.5, 0.5).r, 0.0, 0);
    /* A footprint of many squares averages to one half (pbrt-v4's box). */
    texture_ctx c = {.u = 0.3, .v = 0.7, .dudx = 40, .dvdy = 40};
    assert_near(texture_eval(texture_set_find(b.set, "d", false), &c).r, 0.5, 0.01);
    unbuild(&b);
}

static void test_bilerp(void **state)
{
    (void)state;
    built b;
    hz_error err;
    assert_int_equal(build("Texture \"b\" \"float\" \"bilerp\" \"float v00\" 1 \"float v01\" 2 "
                           "\"float v10\" 3 \"float v11\" 4\n",
                           &b, &err),
                     HZ_OK);
    assert_near(at(&b, "b", false, 0, 0).r, 1, 1e-15);
    assert_near(at(&b, "b", false, 0, 1).r, 2, 1e-15);
    assert_near(at(&b, "b", false, 1, 0).r, 3, 1e-15);
    assert_near(at(&b, "b", false, 1, 1).r, 4, 1e-15);
    assert_near(at(&b, "b", false, 0.5, 0.5).r, 2.5, 1e-15);
    unbuild(&b);
}

/* A 2x2 EXR named `name` of the channels R (1 2 / 3 4), G = 10 R, B = 0
 * and, when a >= 0, A = a. */
static void write_exr_rgba(const char *name, double a)
{
    exr_image img;
    hz_error err;
    int n = a >= 0.0 ? 4 : 3;
    assert_int_equal(exr_image_alloc(&img, 2, 2, n, &err), HZ_OK);
    const char *names[4] = {"A", "B", "G", "R"};
    const float r[4] = {1, 2, 3, 4};
    for (int c = 0; c < n; ++c) {
        const char *cn = names[c + 4 - n];
        snprintf(img.channels[c].name, sizeof img.channels[c].name, "%s", cn);
        for (int i = 0; i < 4; ++i)
            img.channels[c].pixels[i] = cn[0] == 'R'   ? r[i]
                                        : cn[0] == 'G' ? 10 * r[i]
                                        : cn[0] == 'A' ? (float)a
                                                       : 0;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/%s", HAZE_TMP, name);
    assert_int_equal(exr_write(path, &img, &err), HZ_OK);
    exr_image_free(&img);
}

/* A 2x2 EXR: top row (1, 2), bottom row (3, 4) in R; G = 10 R; B = 0. */
static void write_exr(const char *name) { write_exr_rgba(name, -1.0); }

static void test_imagemap_exr(void **state)
{
    (void)state;
    write_exr("tex_2x2.exr");
    built b;
    hz_error err;
    assert_int_equal(
        build("Texture \"p\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x2.exr\" "
              "\"string filter\" \"point\"\n"
              "Texture \"l\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x2.exr\"\n"
              "Texture \"c\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x2.exr\" "
              "\"string wrap\" \"clamp\"\n"
              "Texture \"k\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x2.exr\" "
              "\"string wrap\" \"black\" \"string filter\" \"point\"\n"
              "Texture \"s\" \"float\" \"imagemap\" \"string filename\" \"tex_2x2.exr\" "
              "\"float scale\" 0.5 \"bool invert\" true \"string filter\" \"point\"\n"
              "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x2.exr\" "
              "\"string filter\" \"trilinear\"\n",
              &b, &err),
        HZ_OK);
    /* Texel centres: (u, v) = ((x + 0.5) / 2, 1 - (y + 0.5) / 2). */
    assert_rgb(at(&b, "p", true, 0.25, 0.75), 1, 10, 0, 0);
    assert_rgb(at(&b, "p", true, 0.75, 0.75), 2, 20, 0, 0);
    assert_rgb(at(&b, "p", true, 0.25, 0.25), 3, 30, 0, 0);
    assert_rgb(at(&b, "p", true, 0.75, 0.25), 4, 40, 0, 0);
    assert_rgb(at(&b, "l", true, 0.25, 0.75), 1, 10, 0, 1e-6);
    assert_rgb(at(&b, "l", true, 0.75, 0.25), 4, 40, 0, 1e-6);
    assert_rgb(at(&b, "l", true, 0.5, 0.5), 2.5, 25, 0, 1e-6);
    /* Repeat: u = 0 lies between texel 1 of the row and texel 0 of the next period. */
    assert_rgb(at(&b, "l", true, 0.0, 0.75), 1.5, 15, 0, 1e-6);
    assert_rgb(at(&b, "p", true, 1.25, -0.25), 1, 10, 0, 0);
    /* Clamp: the edge texel. */
    assert_rgb(at(&b, "c", true, 0.0, 0.75), 1, 10, 0, 1e-6);
    /* Black outside. */
    assert_rgb(at(&b, "k", true, 1.25, 0.75), 0, 0, 0, 0);
    /* A footprint of the whole image (width 2 max |ds|, |dt| = 1): the 1x1
     * top of the pyramid, the mean, for every filter (pbrt-v4's level choice). */
    texture_ctx wide = {.u = 0.25, .v = 0.75, .dudx = 0.5};
    assert_rgb(texture_eval(texture_set_find(b.set, "l", true), &wide), 2.5, 25, 0, 1e-6);
    assert_rgb(texture_eval(texture_set_find(b.set, "p", true), &wide), 2.5, 25, 0, 1e-6);
    /* Half of it: level 0 (trilinear blends only from level 1 on, as pbrt-v4). */
    texture_ctx half = {.u = 0.25, .v = 0.75, .dudx = 0.25};
    assert_rgb(texture_eval(texture_set_find(b.set, "t", true), &half), 1, 10, 0, 1e-6);
    /* Between: level 0.5 -> level 0 for trilinear. */
    texture_ctx mid = {.u = 0.25, .v = 0.75, .dudx = 0.25 * sqrt(2.0)};
    assert_rgb(texture_eval(texture_set_find(b.set, "t", true), &mid), 1, 10, 0, 1e-6);
    /* Float from R: 1 - 0.5 * R, clamped at 0. */
    assert_near(at(&b, "s", false, 0.25, 0.75).r, 0.5, 0);
    assert_near(at(&b, "s", false, 0.75, 0.25).r, 0.0, 0);
    unbuild(&b);
}

/* A 2x1 PNG named `name` in HAZE_TMP, of libpng's simplified `format`. */
static void write_png_2x1(const char *name, png_uint_32 format, const void *pixels)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", HAZE_TMP, name);
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    pi.width = 2;
    pi.height = 1;
    pi.format = format;
    assert_true(png_image_write_to_file(&pi, path, 0, pixels, 0, NULL));
}

static void test_imagemap_png(void **state)
{
    (void)state;
    char path[512];
    hz_error err;
    snprintf(path, sizeof path, "%s/tex_2x1.png", HAZE_TMP);
    const uint8_t px[6] = {255, 128, 0, 0, 64, 255};
    assert_int_equal(png_out_write_rgb8(path, 2, 1, px, &err), HZ_OK);
    built b;
    assert_int_equal(
        build("Texture \"s\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x1.png\" "
              "\"string filter\" \"point\"\n"
              "Texture \"l\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x1.png\" "
              "\"string filter\" \"point\" \"string encoding\" \"linear\"\n"
              "Texture \"g\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_2x1.png\" "
              "\"string filter\" \"point\" \"string encoding\" \"gamma 2\"\n",
              &b, &err),
        HZ_OK);
    double s128 = pow((128 / 255.0 + 0.055) / 1.055, 2.4);
    assert_rgb(at(&b, "s", true, 0.25, 0.5), 1, s128, 0, 1e-6);
    assert_rgb(at(&b, "l", true, 0.75, 0.5), 0, 64 / 255.0, 1, 1e-6);
    assert_rgb(at(&b, "g", true, 0.25, 0.5), 1, (128 / 255.0) * (128 / 255.0), 0, 1e-6);
    unbuild(&b);
    /* A 16-bit grey PNG: read at 16 bits, then decoded by the encoding. */
    const uint16_t px16[2] = {32768, 65535};
    write_png_2x1("tex_16.png", PNG_FORMAT_LINEAR_Y, px16);
    assert_int_equal(
        build("Texture \"l\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_16.png\" "
              "\"string filter\" \"point\" \"string encoding\" \"linear\"\n"
              "Texture \"s\" \"float\" \"imagemap\" \"string filename\" \"tex_16.png\" "
              "\"string filter\" \"point\"\n",
              &b, &err),
        HZ_OK);
    double h = 32768 / 65535.0;
    assert_rgb(at(&b, "l", true, 0.25, 0.5), h, h, h, 1e-6);
    assert_near(at(&b, "s", false, 0.25, 0.5).r, pow((h + 0.055) / 1.055, 2.4), 1e-6);
    assert_near(at(&b, "s", false, 0.75, 0.5).r, 1.0, 1e-6);
    unbuild(&b);
    /* An 8-bit grey PNG whose gAMA chunk says linear: its sample is read as
     * stored (pbrt-v4 ignores gAMA), 128 / 255 with encoding "linear". */
    static const uint8_t gama_png[83] = {
        0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48,
        0x44, 0x52, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x00, 0x00, 0x00,
        0x00, 0x3a, 0x7e, 0x9b, 0x55, 0x00, 0x00, 0x00, 0x04, 0x67, 0x41, 0x4d, 0x41, 0x00,
        0x01, 0x86, 0xa0, 0x31, 0xe8, 0x96, 0x5f, 0x00, 0x00, 0x00, 0x0a, 0x49, 0x44, 0x41,
        0x54, 0x78, 0x9c, 0x63, 0x68, 0x00, 0x00, 0x00, 0x82, 0x00, 0x81, 0x77, 0xcd, 0x72,
        0xb6, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
    snprintf(path, sizeof path, "%s/tex_gama.png", HAZE_TMP);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(gama_png, 1, sizeof gama_png, f), sizeof gama_png);
    fclose(f);
    assert_int_equal(
        build("Texture \"l\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_gama.png\" "
              "\"string encoding\" \"linear\"\n",
              &b, &err),
        HZ_OK);
    assert_rgb(at(&b, "l", true, 0.5, 0.5), 128 / 255.0, 128 / 255.0, 128 / 255.0, 1e-6);
    unbuild(&b);
    /* A file that is not a PNG: an error naming it. */
    f = fopen(path, "wb");
    assert_non_null(f);
    fputs("not a png", f);
    fclose(f);
    expect_error("Texture \"l\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_gama.png\"\n",
                 "cannot read PNG");
}

/* pbrt-v4's float image textures: a bilinear lookup reads the mean of R, G
 * and B (or A, when not all one), a texel lookup (point, ewa) reads R. */
static void test_imagemap_float_channels(void **state)
{
    (void)state;
    write_exr_rgba("f_rgb.exr", -1.0);
    write_exr_rgba("f_rgba.exr", 0.25);
    write_exr_rgba("f_rgb1.exr", 1.0);
    const uint8_t px[8] = {255, 0, 0, 51, 0, 255, 0, 255};
    write_png_2x1("f_rgba.png", PNG_FORMAT_RGBA, px);
    built b;
    hz_error err;
#define FT(n, f, extra) "Texture \"" n "\" \"float\" \"imagemap\" \"string filename\" \"" f "\" " extra "\n"
    assert_int_equal(build(FT("bl", "f_rgb.exr", "") FT("pt", "f_rgb.exr", "\"string filter\" \"point\"")
                               FT("ew", "f_rgb.exr", "\"string filter\" \"ewa\"")
                               FT("tr", "f_rgb.exr", "\"string filter\" \"trilinear\"")
                               FT("al", "f_rgba.exr", "") FT("one", "f_rgb1.exr", "")
                               FT("neg", "f_rgb.exr", "\"float scale\" -1")
                               FT("png", "f_rgba.png", "\"string encoding\" \"linear\"")
                               FT("pngpt", "f_rgba.png", "\"string filter\" \"point\"")
                               "Texture \"sp\" \"spectrum\" \"imagemap\" \"string filename\" "
                               "\"f_rgba.png\" \"string encoding\" \"linear\"\n",
                           &b, &err),
                     HZ_OK);
#undef FT
    assert_near(at(&b, "bl", false, 0.25, 0.75).r, 11.0 / 3.0, 1e-6);
    assert_near(at(&b, "tr", false, 0.75, 0.25).r, 44.0 / 3.0, 1e-5);
    assert_near(at(&b, "pt", false, 0.25, 0.75).r, 1.0, 0);
    /* ewa: a texel lookup with a footprint, a bilinear one without. */
    texture_ctx fp = {.u = 0.25, .v = 0.75, .dudx = 0.25};
    assert_near(texture_eval(texture_set_find(b.set, "ew", false), &fp).r, 1.0, 1e-6);
    assert_near(at(&b, "ew", false, 0.25, 0.75).r, 11.0 / 3.0, 1e-6);
    /* The whole image's footprint: the coarsest level's R, for every filter. */
    texture_ctx wide = {.u = 0.25, .v = 0.75, .dudx = 0.5};
    assert_near(texture_eval(texture_set_find(b.set, "bl", false), &wide).r, 2.5, 1e-6);
    assert_near(at(&b, "al", false, 0.25, 0.75).r, 0.25, 1e-6);
    assert_near(at(&b, "one", false, 0.25, 0.75).r, 11.0 / 3.0, 1e-6);
    /* Not inverted: not clamped. */
    assert_near(at(&b, "neg", false, 0.25, 0.75).r, -11.0 / 3.0, 1e-6);
    /* An RGBA PNG: bilinear reads alpha, point reads R (sRGB-decoded). */
    assert_near(at(&b, "png", false, 0.25, 0.5).r, 0.2, 1e-6);
    assert_near(at(&b, "png", false, 0.75, 0.5).r, 1.0, 1e-6);
    assert_near(at(&b, "pngpt", false, 0.25, 0.5).r, 1.0, 1e-6);
    assert_near(at(&b, "pngpt", false, 0.75, 0.5).r, 0.0, 1e-6);
    /* Its colour is not premultiplied. */
    assert_rgb(at(&b, "sp", true, 0.25, 0.5), 1, 0, 0, 1e-6);
    unbuild(&b);
}

static void test_errors(void **state)
{
    (void)state;
    expect_error("Texture \"a\" \"spectrum\" \"nosuch\"\n", "\"nosuch\" is not supported");
    expect_error("Texture \"a\" \"float\" \"constant\" \"float valu\" 1\n", "valu");
    expect_error("Texture \"a\" \"float\" \"scale\" \"texture tex\" \"missing\"\n",
                 "no float texture named \"missing\"");
    expect_error("Texture \"a\" \"float\" \"checkerboard\" \"string mapping\" \"polar\"\n",
                 "mapping");
    expect_error("Texture \"a\" \"float\" \"imagemap\" \"string filename\" \"none.exr\"\n",
                 "none.exr");
    expect_error("Texture \"a\" \"float\" \"imagemap\" \"string filename\" \"tex_2x2.exr\" "
                 "\"string wrap\" \"spiral\"\n",
                 "spiral");
}

/* The 3D textures at p (texture space = render space here) with footprint
 * (dpdx, dpdy). */
static double at3(const built *b, const char *name, vec3 p, vec3 dpdx, vec3 dpdy)
{
    const texture *t = texture_set_find(b->set, name, false);
    if (!t)
        fail_msg("no texture \"%s\"", name);
    texture_ctx c = {.p = p, .dpdx = dpdx, .dpdy = dpdy};
    return texture_eval_float(t, &c);
}

/* pbrt-v4's FBm and Turbulence, octave by octave from the noise itself:
 * with no footprint every octave counts; a footprint of 2^-5 per pixel
 * leaves -1 - log2(2^-10) / 2 = 4 octaves exactly (the partial one faded to
 * nothing), and turbulence counts each dropped octave as 0.2 (and, as
 * pbrt-v4's loop does, the partial one twice). */
static void test_fbm_and_turbulence(void **state)
{
    (void)state;
    built b;
    hz_error err;
    assert_int_equal(build("Texture \"f\" \"float\" \"fbm\" \"integer octaves\" 6 "
                           "\"float roughness\" 0.6\n"
                           "Texture \"w\" \"float\" \"wrinkled\" \"integer octaves\" 6 "
                           "\"float roughness\" 0.6\n",
                           &b, &err),
                     HZ_OK);
    vec3 p = v3(0.37, 1.21, -2.53), zero = v3(0, 0, 0), step = v3(0.03125, 0, 0);
    double fbm6 = 0.0, fbm4 = 0.0, turb4 = 0.0, lambda = 1.0, o = 1.0;
    for (int i = 0; i < 6; ++i) {
        float n = noise3((float)(lambda * p.x), (float)(lambda * p.y), (float)(lambda * p.z));
        fbm6 += o * n;
        if (i < 4) {
            fbm4 += o * n;
            turb4 += o * fabs(n);
        } else {
            turb4 += o * 0.2; /* the dropped octaves 4 and 5 */
        }
        if (i == 4)
            turb4 += o * 0.2; /* pbrt-v4 also adds the partial octave 4, faded to 0.2 */
        lambda = (float)(lambda * 1.99f);
        o = (float)(o * 0.6f);
    }
    assert_near(at3(&b, "f", p, zero, zero), fbm6, 1e-5);
    assert_near(at3(&b, "f", p, step, zero), fbm4, 1e-5);
    assert_near(at3(&b, "w", p, step, zero), turb4, 1e-5);
    /* A larger footprint than one unit leaves nothing of fbm. */
    assert_near(at3(&b, "f", p, v3(4, 0, 0), zero), 0.0, 1e-7);
    unbuild(&b);
}

/* dots: one dot of radius 0.35 per cell where the noise says so, as pbrt-v4
 * renders it ("outside" in the dots, "inside" between: pbrt-v4's swap);
 * directionmix: |n . dir| of tex1; marble is spectrum only. */
static void test_dots_directionmix(void **state)
{
    (void)state;
    built b;
    hz_error err;
    assert_int_equal(build("Texture \"d\" \"float\" \"dots\" \"float inside\" 0.25 "
                           "\"float outside\" 0.75\n"
                           "Texture \"m\" \"float\" \"directionmix\" \"float tex1\" 1 "
                           "\"float tex2\" 3 \"vector3 dir\" [0 0 2]\n",
                           &b, &err),
                     HZ_OK);
    int cells_with_dots = 0;
    for (int sc = 0; sc < 16; ++sc)
        for (int tc = 0; tc < 16; ++tc) {
            bool dot = noise3(sc + 0.5f, tc + 0.5f, 0.5f) > 0.0f;
            /* The dot's centre: shifted by at most 0.15 from the cell's. */
            double s0 = sc + 0.15f * noise3(sc + 1.5f, tc + 2.8f, 0.5f);
            double t0 = tc + 0.15f * noise3(sc + 4.5f, tc + 9.8f, 0.5f);
            assert_near(at(&b, "d", false, s0, t0).r, dot ? 0.75 : 0.25, 0.0);
            /* The cell's corner region is never in a dot. */
            assert_near(at(&b, "d", false, sc + 0.49, tc + 0.49).r, 0.25, 0.0);
            cells_with_dots += dot;
        }
    assert_true(cells_with_dots > 64 && cells_with_dots < 192);
    const texture *m = texture_set_find(b.set, "m", false);
    texture_ctx c = {.n = v3(0.6, 0.0, -0.8)};
    assert_near(texture_eval_float(m, &c), 0.8 * 1 + 0.2 * 3, 1e-12);
    unbuild(&b);
    expect_error("Texture \"a\" \"spectrum\" \"fbm\"\n", "makes float textures only");
    expect_error("Texture \"a\" \"float\" \"marble\"\n", "makes spectrum textures only");
    expect_error("Texture \"a\" \"float\" \"directionmix\" \"vector3 dir\" [0 0 0]\n",
                 "non-zero");
}

static double at_p(const built *b, const char *name, vec3 p)
{
    const texture *t = texture_set_find(b->set, name, false);
    if (!t)
        fail_msg("no texture \"%s\"", name);
    texture_ctx c = {.p = p};
    return texture_eval_float(t, &c);
}

/* pbrt-v4's 2D mappings read back through bilerp (s with v10 = v11 = 1, t
 * with v01 = v11 = 1) at points of the texture's space, and the 3D
 * checkerboard: tex1 where floor(x) + floor(y) + floor(z) is even. */
static void test_mappings(void **state)
{
    (void)state;
    built b;
    hz_error err;
    const char *s_of = "\"float v00\" 0 \"float v10\" 1 \"float v01\" 0 \"float v11\" 1";
    const char *t_of = "\"float v00\" 0 \"float v10\" 0 \"float v01\" 1 \"float v11\" 1";
    char text[4096];
    snprintf(text, sizeof text,
             "Texture \"ss\" \"float\" \"bilerp\" \"string mapping\" \"spherical\" %s\n"
             "Texture \"st\" \"float\" \"bilerp\" \"string mapping\" \"spherical\" %s\n"
             "Texture \"cs\" \"float\" \"bilerp\" \"string mapping\" \"cylindrical\" %s\n"
             "Texture \"ct\" \"float\" \"bilerp\" \"string mapping\" \"cylindrical\" %s\n"
             "Translate 1 0 0\n"
             "Texture \"ps\" \"float\" \"bilerp\" \"string mapping\" \"planar\" "
             "\"vector3 v1\" [2 0 0] \"vector3 v2\" [0 0 3] \"float udelta\" 0.25 %s\n"
             "Texture \"c3\" \"float\" \"checkerboard\" \"integer dimension\" 3\n",
             s_of, t_of, s_of, t_of, s_of);
    assert_int_equal(build(text, &b, &err), HZ_OK);
    /* Spherical: s = theta / pi, t = phi / 2 pi. */
    assert_near(at_p(&b, "ss", v3(1, 0, 0)), 0.5, 1e-12);
    assert_near(at_p(&b, "ss", v3(0, 0, 2)), 0.0, 1e-12);
    assert_near(at_p(&b, "st", v3(0, 0.5, 0.5)), 0.25, 1e-12);
    /* Cylindrical: s = (pi + atan2(y, x)) / 2 pi, t = z (bilerp takes t as is). */
    assert_near(at_p(&b, "cs", v3(0, 1, 0.25)), 0.75, 1e-12);
    assert_near(at_p(&b, "ct", v3(0, 1, 0.25)), 0.25, 1e-12);
    /* Planar in the space after Translate 1 0 0: s = 0.25 + (p - (1, 0, 0)) . v1. */
    assert_near(at_p(&b, "ps", v3(1.2, 5, 0)), 0.25 + 0.4, 1e-12);
    /* The 3D checkerboard too is in the translated space: x - 1. */
    assert_near(at_p(&b, "c3", v3(0.5, 0.5, 0.5)), 0.0, 0.0);
    assert_near(at_p(&b, "c3", v3(1.5, 0.5, 0.5)), 1.0, 0.0);
    assert_near(at_p(&b, "c3", v3(1.5, -0.5, 0.5)), 0.0, 0.0);
    unbuild(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_scale_mix),
        cmocka_unit_test(test_checkerboard),
        cmocka_unit_test(test_bilerp),
        cmocka_unit_test(test_imagemap_exr),
        cmocka_unit_test(test_imagemap_png),
        cmocka_unit_test(test_imagemap_float_channels),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_fbm_and_turbulence),
        cmocka_unit_test(test_dots_directionmix),
        cmocka_unit_test(test_mappings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
