#define _POSIX_C_SOURCE 200809L
/* Textures through whole renders of the haze binary: a checkerboard ground
 * filtered to its mean far away and exact near, an image of one colour equal
 * to that colour as a constant material. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "cli_util.h"
#include "render_test_util.h"
#include "core/vec.h"
#include "film/exr.h"

enum { W = 96, H = 72 };

static void render_or_fail(const char *name, const char *text, exr_image *img)
{
    char scene[1024], args[4096], out[8192], path[1024];
    snprintf(scene, sizeof scene, "%s/%s.pbrt", HAZE_TMP, name);
    write_text_file(scene, text);
    snprintf(path, sizeof path, "%s/%s.exr", HAZE_TMP, name);
    snprintf(args, sizeof args, "render '%s' -o '%s' --quiet --threads 2 --color rgb", scene, path);
    int rc = run_haze(args, out, sizeof out);
    if (rc != 0) {
        print_error("haze exited %d: %s\n", rc, out);
        fail();
    }
    hz_error err = {0};
    if (exr_read(path, img, &err) != HZ_OK) {
        print_error("%s\n", err.message);
        fail();
    }
}

/* Mean of channel `ch` over [x0, x1) x [y0, y1). */
static double region_mean(const exr_image *img, const char *ch, int x0, int x1, int y0, int y1)
{
    const exr_channel *c = exr_find_channel(img, ch);
    assert_non_null(c);
    double s = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            s += c->pixels[y * img->width + x];
    return s / ((x1 - x0) * (y1 - y0));
}

/* A ground of unit squares (red 0.8 / blue 0.8) under a white sky, seen at a
 * grazing angle; maxdepth 1, so a pixel is the reflectance it sees. */
static const char checker_fmt[] =
    "LookAt 0 1 0  0 0.8 10  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 60\n"
    "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
    "Integrator \"volpath\" \"integer maxdepth\" 1\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
    "Texture \"ck\" \"spectrum\" \"checkerboard\" \"float uscale\" 2000 \"float vscale\" 2000\n"
    "  \"rgb tex1\" [0.8 0 0] \"rgb tex2\" [0 0 0.8]\n"
    "Material \"diffuse\" \"texture reflectance\" \"ck\"\n"
    "Shape \"trianglemesh\" \"point3 P\" [-1000 0 -1000  1000 0 -1000  1000 0 1000  -1000 0 1000]\n"
    "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n";

static void test_checkerboard_ground(void **state)
{
    (void)state;
    char text[4096];
    snprintf(text, sizeof text, checker_fmt, W, H);
    exr_image img;
    render_or_fail("tex_checker", text, &img);
    /* Far (rows 37-39, just below the horizon at row 34.75, z ~ 15-25): many
     * squares per pixel, filtered to the mean 0.4 of both colours. */
    double far_r = region_mean(&img, "R", 0, W, 37, 40);
    double far_b = region_mean(&img, "B", 0, W, 37, 40);
    print_message("far rows: R %.4f B %.4f\n", far_r, far_b);
    assert_true(fabs(far_r - 0.4) < 0.04 && fabs(far_b - 0.4) < 0.04);
    /* Near (bottom rows: z in (1.6, 1.8), x within 0.1 of 0): squares of tens
     * of pixels, x = 0 an edge at the centre column; each side one colour. */
    double near_r = region_mean(&img, "R", W / 2 - 4, W / 2 - 2, H - 3, H - 1);
    double near_b = region_mean(&img, "B", W / 2 - 4, W / 2 - 2, H - 3, H - 1);
    double near_r2 = region_mean(&img, "R", W / 2 + 2, W / 2 + 4, H - 3, H - 1);
    double near_b2 = region_mean(&img, "B", W / 2 + 2, W / 2 + 4, H - 3, H - 1);
    print_message("near: (%.4f, %.4f) and (%.4f, %.4f)\n", near_r, near_b, near_r2, near_b2);
    /* One side red only, the other blue only (exact zeros in the other). */
    assert_true((near_r > 0.75 && near_b == 0.0 && near_r2 == 0.0 && near_b2 > 0.75) ||
                (near_b > 0.75 && near_r == 0.0 && near_b2 == 0.0 && near_r2 > 0.75));
    exr_image_free(&img);
}

static const char plane_fmt[] =
    "LookAt 0 1 -2  0 0 3  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 50\n"
    "Film \"rgb\" \"integer xresolution\" 48 \"integer yresolution\" 36\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
    "Integrator \"volpath\" \"integer maxdepth\" 3\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
    "%s\n"
    "Shape \"trianglemesh\" \"point3 P\" [-4 0 -4  4 0 -4  4 0 8  -4 0 8]\n"
    "  \"integer indices\" [0 1 2 0 2 3]\n"
    "Shape \"sphere\" \"float radius\" 0.5\n";

static double worst_difference(const exr_image *ia, const exr_image *ib)
{
    const char *ch[3] = {"R", "G", "B"};
    double worst = 0;
    for (int c = 0; c < 3; ++c) {
        const float *pa = exr_find_channel(ia, ch[c])->pixels;
        const float *pb = exr_find_channel(ib, ch[c])->pixels;
        for (int i = 0; i < ia->width * ia->height; ++i)
            worst = fmax(worst, fabs(pa[i] - pb[i]));
    }
    return worst;
}

/* Mean |difference| of horizontal neighbours over the mean, channel R, in
 * the centre [w/4, 3w/4)^2: near 0 for a checker finer than the pixels that
 * is filtered over each pixel's footprint, near 1 when point-sampled. */
static double neighbour_contrast(const exr_image *img)
{
    const exr_channel *c = exr_find_channel(img, "R");
    assert_non_null(c);
    int w = img->width, lo = w / 4, hi = 3 * w / 4;
    double d = 0.0, m = 0.0;
    for (int y = lo; y < hi; ++y)
        for (int x = lo; x < hi; ++x) {
            d += fabs(c->pixels[y * w + x + 1] - c->pixels[y * w + x]);
            m += c->pixels[y * w + x];
        }
    return m > 0.0 ? d / m : INFINITY;
}

/* A checker of 0.01 squares, about 7 to a pixel, on a wall 10 away: seen
 * directly, in a 45-degree mirror halfway, and through a glass slab, lit by
 * a distant light that nothing shadows (radiance: the reflectance). The
 * differentials of the camera rays follow the specular bounces (pbrt-v4's
 * SpawnRay), so the wall is filtered to its mean in all three views; with the
 * footprint known only at the camera ray's first hit, the mirrored and
 * refracted views point-sample it: neighbours then differ by the squares'
 * whole contrast. Pixel centres (no jitter), so each pixel sees one point. */
static void test_footprint_through_specular_bounces(void **state)
{
    (void)state;
    static const char head[] =
        "LookAt 0 0 0  0 0 1  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 20\n"
        "Film \"rgb\" \"integer xresolution\" 48 \"integer yresolution\" 48\n"
        "Sampler \"zsobol\" \"integer pixelsamples\" 64\n"
        "Integrator \"volpath\" \"integer maxdepth\" 4\n"
        "Option \"bool disablepixeljitter\" true\n"
        "WorldBegin\n"
        "LightSource \"distant\" \"point3 from\" [1 3 -1] \"point3 to\" [0 0 0]\n"
        "  \"rgb L\" [10.4195 10.4195 10.4195]\n"
        "Texture \"ck\" \"spectrum\" \"checkerboard\" \"float uscale\" 4000 \"float vscale\" 4000\n"
        "  \"rgb tex1\" [0.8 0 0] \"rgb tex2\" [0 0 0.8]\n"
        "AttributeBegin\n"
        "Material \"diffuse\" \"texture reflectance\" \"ck\"\n";
    static const char *views[4][2] = {
        {"direct", "Shape \"trianglemesh\" \"point3 P\" [-20 -20 10  20 -20 10  20 20 10  -20 20 10]\n"
                   "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n"
                   "AttributeEnd\n"},
        {"mirror", "Shape \"trianglemesh\" \"point3 P\" [-5 -20 -15  -5 -20 25  -5 20 25  -5 20 -15]\n"
                   "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n"
                   "AttributeEnd\n"
                   "Material \"conductor\" \"rgb reflectance\" [0.9 0.9 0.9] \"float roughness\" 0\n"
                   "Shape \"trianglemesh\" \"point3 P\" [2.1213 -3 2.8787  2.1213 3 2.8787\n"
                   "  -2.1213 3 7.1213  -2.1213 -3 7.1213] \"integer indices\" [0 1 2 0 2 3]\n"},
        {"glass", "Shape \"trianglemesh\" \"point3 P\" [-20 -20 10  20 -20 10  20 20 10  -20 20 10]\n"
                  "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n"
                  "AttributeEnd\n"
                  "Material \"dielectric\" \"float eta\" 1.5\n"
                  "Shape \"trianglemesh\" \"point3 P\" [-5 -5 3  5 -5 3  5 5 3  -5 5 3\n"
                  "  -5 -5 4  5 -5 4  5 5 4  -5 5 4] \"integer indices\" [0 2 1 0 3 2  4 5 6 4 6 7]\n"},
        /* A mirror 10 away, turned 8.35 degrees, sends the view back to a
         * wall 3 beside the camera: 20 along the path, 3 from the camera.
         * The camera's own estimate there (camera_approximate_dpdxy, what a
         * hit without differentials gets) is a tenth of a square (0.1 here):
         * point-sampled, contrast 0.54; the differentials carried through
         * the mirror give 0.001. */
        {"folded", "Texture \"fine\" \"spectrum\" \"checkerboard\" \"float uscale\" 200\n"
                   "  \"float vscale\" 200 \"rgb tex1\" [0.8 0 0] \"rgb tex2\" [0 0 0.8]\n"
                   "Material \"diffuse\" \"texture reflectance\" \"fine\"\n"
                   "Shape \"trianglemesh\" \"point3 P\" [-3 -10 -12  -3 -10 8  -3 10 8  -3 10 -12]\n"
                   "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n"
                   "AttributeEnd\n"
                   "Material \"conductor\" \"rgb reflectance\" [0.9 0.9 0.9] \"float roughness\" 0\n"
                   "Shape \"trianglemesh\" \"point3 P\" [-1.9789 -2 10.2905  -1.9789 2 10.2905\n"
                   "  1.9789 2 9.7095  1.9789 -2 9.7095] \"integer indices\" [0 1 2 0 2 3]\n"},
    };
    double mean_direct = 0.0;
    for (int v = 0; v < 4; ++v) {
        char text[4096], name[64];
        snprintf(text, sizeof text, "%s%s", head, views[v][1]);
        snprintf(name, sizeof name, "tex_footprint_%s", views[v][0]);
        exr_image img;
        render_or_fail(name, text, &img);
        double contrast = neighbour_contrast(&img);
        double mean = region_mean(&img, "R", 12, 36, 12, 36);
        print_message("%s: neighbour contrast %.4f, mean R %.4f\n", views[v][0], contrast, mean);
        if (v == 0)
            mean_direct = mean;
        /* Point-sampled, a pixel is 0 or 0.8: the contrast would be ~1. */
        assert_true(contrast < 0.1);
        /* The checker's mean 0.4, less what the mirror's 0.9 and the slab's
         * two Fresnel transmissions (0.92) take. */
        assert_true(fabs(mean_direct - 0.4) < 1e-3);
        assert_true(mean > 0.8 * mean_direct && mean < 1.01 * mean_direct);
        exr_image_free(&img);
    }
}

static void test_constant_image_is_constant_material(void **state)
{
    (void)state;
    exr_image tex;
    hz_error err;
    assert_int_equal(exr_image_alloc(&tex, 4, 4, 3, &err), HZ_OK);
    const char *names[3] = {"B", "G", "R"};
    const float v[3] = {0.75f, 0.5f, 0.25f};
    for (int c = 0; c < 3; ++c) {
        snprintf(tex.channels[c].name, sizeof tex.channels[c].name, "%s", names[c]);
        for (int i = 0; i < 16; ++i)
            tex.channels[c].pixels[i] = v[c];
    }
    char path[1024];
    snprintf(path, sizeof path, "%s/tex_const.exr", HAZE_TMP);
    assert_int_equal(exr_write(path, &tex, &err), HZ_OK);
    exr_image_free(&tex);

    char a[4096], b[4096];
    snprintf(a, sizeof a, plane_fmt,
             "Texture \"im\" \"spectrum\" \"imagemap\" \"string filename\" \"tex_const.exr\"\n"
             "Texture \"r\" \"float\" \"constant\" \"float value\" 0.3\n"
             "Material \"coateddiffuse\" \"texture reflectance\" \"im\" \"texture roughness\" "
             "\"r\"");
    snprintf(b, sizeof b, plane_fmt,
             "Material \"coateddiffuse\" \"rgb reflectance\" [0.25 0.5 0.75] "
             "\"float roughness\" 0.3");
    exr_image ia, ib;
    render_or_fail("tex_const_a", a, &ia);
    render_or_fail("tex_const_b", b, &ib);
    double worst = worst_difference(&ia, &ib);
    print_message("imagemap vs constant: worst pixel difference %.3g\n", worst);
    assert_true(worst < 1e-5);
    exr_image_free(&ia);
    exr_image_free(&ib);
}

/* The coated materials' layer as textures (pbrt-v4's float "thickness" and
 * "g", spectrum "albedo"; pbrt-v4-scenes' kroken gives "texture thickness"):
 * constant textures render exactly as the same constants, and the layer does
 * change the image (so a texture read and then ignored would fail). */
static void test_coated_layer_textures(void **state)
{
    (void)state;
    static const char *bases[2] = {
        "\"string type\" \"coateddiffuse\" \"rgb reflectance\" [0.2 0.4 0.6]",
        "\"string type\" \"coatedconductor\" \"float interface.roughness\" 0.1"};
    for (int b = 0; b < 2; ++b) {
        char textured[4096], constant[4096], clear[4096], mat[1024];
        snprintf(mat, sizeof mat,
                 "Texture \"th\" \"float\" \"constant\" \"float value\" 0.5\n"
                 "Texture \"al\" \"spectrum\" \"constant\" \"rgb value\" [0.9 0.5 0.1]\n"
                 "Texture \"g\" \"float\" \"constant\" \"float value\" 0.3\n"
                 "MakeNamedMaterial \"m\" %s \"texture thickness\" \"th\" \"texture albedo\" \"al\" "
                 "\"texture g\" \"g\"\nNamedMaterial \"m\"",
                 bases[b]);
        snprintf(textured, sizeof textured, plane_fmt, mat);
        snprintf(mat, sizeof mat,
                 "MakeNamedMaterial \"m\" %s \"float thickness\" 0.5 \"rgb albedo\" [0.9 0.5 0.1] "
                 "\"float g\" 0.3\nNamedMaterial \"m\"",
                 bases[b]);
        snprintf(constant, sizeof constant, plane_fmt, mat);
        snprintf(mat, sizeof mat, "MakeNamedMaterial \"m\" %s\nNamedMaterial \"m\"", bases[b]);
        snprintf(clear, sizeof clear, plane_fmt, mat);
        exr_image it, ic, i0;
        render_or_fail("coat_tex", textured, &it);
        render_or_fail("coat_const", constant, &ic);
        render_or_fail("coat_clear", clear, &i0);
        double same = worst_difference(&it, &ic), layer = worst_difference(&ic, &i0);
        print_message("%s: textured vs constant %.3g, layer vs none %.3g\n",
                      b ? "coatedconductor" : "coateddiffuse", same, layer);
        assert_true(same < 1e-5);
        assert_true(layer > 0.02);
        exr_image_free(&it);
        exr_image_free(&ic);
        exr_image_free(&i0);
    }
}

/* A texture that shows (u, v) as red and green, under a white sky with
 * maxdepth 1: a diffuse pixel is its reflectance exactly (cosine sampling). */
static const char uv_fmt[] =
    "LookAt 0 0 -5  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 40\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
    "Integrator \"volpath\" \"integer maxdepth\" 1\n"
    "WorldBegin\n"
    "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
    "Texture \"uv\" \"spectrum\" \"bilerp\" \"rgb v00\" [0 0 0] \"rgb v01\" [0 1 0]\n"
    "  \"rgb v10\" [1 0 0] \"rgb v11\" [1 1 0]\n"
    "Material \"diffuse\" \"texture reflectance\" \"uv\"\n"
    "%s\n";

typedef void (*uv_of_fn)(vec3 p, double *u, double *v);

static double phi_of(vec3 p)
{
    double phi = atan2(p.y, p.x);
    return phi < 0 ? phi + 2 * HZ_PI : phi;
}

static void uv_sphere(vec3 p, double *u, double *v)
{
    *u = phi_of(p) / (2 * HZ_PI);
    *v = (acos(p.z) - HZ_PI) / (0 - HZ_PI);
}

/* zmin -0.9, zmax 0.5, phimax 270 */
static void uv_partial_sphere(vec3 p, double *u, double *v)
{
    double th0 = acos(-0.9), th1 = acos(0.5);
    *u = phi_of(p) / (1.5 * HZ_PI);
    *v = (acos(p.z) - th0) / (th1 - th0);
}

static void uv_given(vec3 p, double *u, double *v)
{
    *u = 0.5 * (p.x + 1) / 2;
    *v = 0.2 + 0.8 * (p.y + 1) / 2;
}

/* Triangles (p0 p1 p2) and (p0 p2 p3) of the square [-1, 1]^2, each with
 * pbrt-v4's default (0,0), (1,0), (1,1). */
static void uv_default_triangles(vec3 p, double *u, double *v)
{
    if (fabs(p.x - p.y) < 1e-6) { /* on the shared edge: either triangle's */
        *u = *v = NAN;
    } else if (p.x > p.y) {
        *u = (p.x + 1) / 2;
        *v = (p.y + 1) / 2;
    } else {
        *u = (p.y + 1) / 2;
        *v = (p.y - p.x) / 2;
    }
}

static void uv_bilinear(vec3 p, double *u, double *v)
{
    *u = (p.x + 1) / 2;
    *v = (p.y + 1) / 2;
}

/* radius 1, innerradius 0.2 */
static void uv_disk(vec3 p, double *u, double *v)
{
    *u = phi_of(p) / (2 * HZ_PI);
    *v = (1 - sqrt(p.x * p.x + p.y * p.y)) / 0.8;
}

/* Rotate 90 about x: object (x, y, z) is world (x, -z, y). */
static void uv_cylinder(vec3 w, double *u, double *v)
{
    vec3 p = v3(w.x, w.z, -w.y);
    *u = phi_of(p) / (2 * HZ_PI);
    *v = (p.z + 1) / 2;
}

static void check_uv(const char *shape, uv_of_fn uv_of, double tol)
{
    char text[4096];
    snprintf(text, sizeof text, uv_fmt, shape);
    render_scene *rs = build_scene_or_fail(text, NULL);
    int hits = 0;
    double worst = 0;
    for (int y = 2; y < 32; y += 3)
        for (int x = 2; x < 32; x += 3) {
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            /* The far side (z > 0) is the inside of a partial sphere seen
             * through its cut, in its own shadow: not the texture alone. */
            if (!e.hit || e.p_world.z > 1e-9)
                continue;
            double u, v;
            uv_of(e.p_world, &u, &v);
            if (isnan(u))
                continue;
            worst = fmax(worst, fmax(fabs(e.L.r - u), fabs(e.L.g - v)));
            if (!(fabs(e.L.r - u) <= tol && fabs(e.L.g - v) <= tol))
                fail_msg("%s: at (%g %g %g) got uv (%.6f %.6f), want (%.6f %.6f)", shape,
                         e.p_world.x, e.p_world.y, e.p_world.z, e.L.r, e.L.g, u, v);
            ++hits;
        }
    print_message("%.40s...: %d hits, worst %.2g\n", shape, hits, worst);
    assert_true(hits > 10);
    render_scene_destroy(rs);
}

static void test_uv_on_shapes(void **state)
{
    (void)state;
    check_uv("Shape \"sphere\"", uv_sphere, 1e-6);
    check_uv("Shape \"sphere\" \"float zmin\" -0.9 \"float zmax\" 0.5 \"float phimax\" 270",
             uv_partial_sphere, 1e-6);
    check_uv("Shape \"trianglemesh\" \"point3 P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0]\n"
             "  \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0.2 0.5 0.2 0.5 1 0 1]",
             uv_given, 1e-6);
    check_uv("Shape \"trianglemesh\" \"point3 P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0]\n"
             "  \"integer indices\" [0 1 2 0 2 3]",
             uv_default_triangles, 1e-6);
    check_uv("Shape \"bilinearmesh\" \"point3 P\" [-1 -1 0 1 -1 0 -1 1 0 1 1 0]",
             uv_bilinear, 1e-6);
    check_uv("Shape \"disk\" \"float innerradius\" 0.2", uv_disk, 2e-3);
    check_uv("Rotate 90 1 0 0 Shape \"cylinder\"", uv_cylinder, 2e-3);
}

/* pbrt-v4's "normalmap": a 1x1 EXR of the tangent-space normal
 * (sin t, 0, cos t) (or (0, sin t, cos t)), stored as 0.5 + 0.5 n, tilts a
 * quad's shading normal toward its dp/du (dp/dv) by t: a diffuse quad under
 * a distant light reads rho / pi E max(0, n . l) exactly. */
static void test_normal_map(void **state)
{
    (void)state;
    const double t = 30.0 * HZ_PI / 180.0;
    const vec3 local[2] = {v3(sin(t), 0, cos(t)), v3(0, sin(t), cos(t))};
    const vec3 lights[3] = {v3(1, 0, 1), v3(-1, 0, 1), v3(0, 1, 1)};
    for (int k = 0; k < 2; ++k) {
        exr_image img;
        hz_error err;
        assert_int_equal(exr_image_alloc(&img, 1, 1, 3, &err), HZ_OK);
        const char *names[3] = {"B", "G", "R"};
        const double val[3] = {local[k].z, local[k].y, local[k].x};
        for (int c = 0; c < 3; ++c) {
            snprintf(img.channels[c].name, sizeof img.channels[c].name, "%s", names[c]);
            img.channels[c].pixels[0] = (float)(0.5 + 0.5 * val[c]);
        }
        char path[1024];
        snprintf(path, sizeof path, "%s/normal_map_%d.exr", HAZE_TMP, k);
        assert_int_equal(exr_write(path, &img, &err), HZ_OK);
        exr_image_free(&img);
        /* dp/du = +x, dp/dv = +y, n = +z: the local normal is the world one */
        vec3 n = v3_normalize(v3(0.5 + 0.5 * local[k].x - 0.5, 0.5 + 0.5 * local[k].y - 0.5,
                                 0.5 + 0.5 * local[k].z - 0.5));
        for (int li = 0; li < 3; ++li) {
            vec3 l = v3_normalize(lights[li]);
            char text[2048];
            snprintf(text, sizeof text,
                     "LookAt 0 0 5  0 0 0  0 1 0\n"
                     "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
                     "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                     "Integrator \"volpath\" \"integer maxdepth\" 1\n"
                     "WorldBegin\nLightSource \"distant\" \"point3 from\" [%g %g %g] "
                     "\"point3 to\" [0 0 0] \"rgb L\" [3 3 3]\n"
                     "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5] "
                     "\"string normalmap\" \"%s\"\n"
                     "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "
                     "\"point2 uv\" [0 0 1 0 1 1 0 1] \"integer indices\" [0 1 2 0 2 3]\n",
                     lights[li].x, lights[li].y, lights[li].z, path);
            render_scene *rs = build_scene_or_fail(text, NULL);
            pixel_eval e = eval_pixel(rs, 4.5, 4.5, 1);
            double want = 0.5 * HZ_INV_PI * 3.0 * fmax(0.0, v3_dot(n, l));
            expect_close(e.L.g, want, 1e-4, 1e-6, "normal map", 4, 4);
            render_scene_destroy(rs);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_checkerboard_ground),
        cmocka_unit_test(test_constant_image_is_constant_material),
        cmocka_unit_test(test_coated_layer_textures),
        cmocka_unit_test(test_uv_on_shapes),
        cmocka_unit_test(test_normal_map),
        cmocka_unit_test(test_footprint_through_specular_bounces),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
