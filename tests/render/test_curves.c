/* pbrt-v4's "curve" shape against closed forms: which rays hit a curve (the
 * points within half its width of it, between its end planes), the shading
 * of flat, cylinder and ribbon curves under a distant light (pbrt-v4's
 * normals: a cylinder's rounds over v), no self-shadowing under a uniform
 * sky, the refusals, and packets of rays against single rays. (Against
 * pbrt-v4's own images of the same files: coverage within 0.4%, shading
 * within 0.3%; docs/scene-format.md.) */
#include "render_test_util.h"

#include <embree3/rtcore.h>

#include "geometry/geometry.h"

/* The bezier of the tests: a planar S in z = 0. */
static const double S[4][2] = {{-1.5, -1.0}, {-0.5, 1.0}, {0.5, -1.0}, {1.5, 1.0}};

static void bezier(double u, double p[2], double dp[2])
{
    double a = 1.0 - u;
    for (int k = 0; k < 2; ++k) {
        p[k] = a * a * a * S[0][k] + 3 * a * a * u * S[1][k] + 3 * a * u * u * S[2][k] +
               u * u * u * S[3][k];
        dp[k] = 3 * (a * a * (S[1][k] - S[0][k]) + 2 * a * u * (S[2][k] - S[1][k]) +
                     u * u * (S[3][k] - S[2][k]));
    }
}

/* Distance from (x, y) to the S (dense search, then refined), and whether
 * the nearest point is an interior one (not clipped by an end plane). */
static double distance_to_s(double x, double y, bool *interior)
{
    double best = INFINITY, bu = 0.0;
    for (int i = 0; i <= 2000; ++i) {
        double u = i / 2000.0, p[2], dp[2];
        bezier(u, p, dp);
        double d = hypot(p[0] - x, p[1] - y);
        if (d < best)
            best = d, bu = u;
    }
    for (double h = 1.0 / 2000.0; h > 1e-9; h *= 0.5)
        for (int s = -1; s <= 1; s += 2) {
            double u = fmin(fmax(bu + s * h, 0.0), 1.0), p[2], dp[2];
            bezier(u, p, dp);
            double d = hypot(p[0] - x, p[1] - y);
            if (d < best)
                best = d, bu = u;
        }
    *interior = bu > 1e-6 && bu < 1.0 - 1e-6;
    return best;
}

/* The S of width 0.1 seen straight down at 200x200 over [-2, 2]^2 under a
 * white sky, `extra` on its Shape (a checkerboard "half" in u is defined). */
static void s_scene(char *text, size_t n, const char *extra)
{
    snprintf(text, n,
             "LookAt 0 0 5  0 0 0  0 1 0\n"
             "Camera \"orthographic\" \"float screenwindow\" [-2 2 -2 2]\n"
             "Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 200\n"
             "Integrator \"volpath\" \"integer maxdepth\" 1\n"
             "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
             "Texture \"half\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 1 "
             "\"float tex1\" 1 \"float tex2\" 0\n"
             "Shape \"curve\" \"point3 P\" [-1.5 -1 0  -0.5 1 0  0.5 -1 0  1.5 1 0] "
             "\"float width\" 0.1 %s\n",
             extra);
}

/* An orthographic view straight down on the S of width 0.1: every pixel
 * centre clearly inside (distance < 0.4 w) is hit and every one clearly
 * outside (> 0.6 w, or beyond the end planes) is not; pbrt-v4's test
 * measures the distance to a nearby curve point, not the nearest one, so the
 * band between is free. The hit count times the pixel area gives the area,
 * width x length (3.8808), within 1%. */
static void test_coverage(void **state)
{
    (void)state;
    const int res = 200;
    const double half = 2.0, w = 0.1, px = 2 * half / res;
    char text[1400];
    s_scene(text, sizeof text, "");
    render_scene *rs = build_scene_or_fail(text, NULL);
    int hits = 0, wrong = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            /* pbrt-v4's camera: screen x runs along world -x here (left-handed). */
            double wx = half - (x + 0.5) * px, wy = half - (y + 0.5) * px;
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            hits += e.hit;
            bool interior;
            double d = distance_to_s(wx, wy, &interior);
            if (!interior && d > 0.05 * w)
                wrong += e.hit; /* past an end plane */
            else if (d < 0.4 * w)
                wrong += !e.hit;
            else if (d > 0.6 * w)
                wrong += e.hit;
        }
    assert_int_equal(wrong, 0);
    double area = hits * px * px, want = w * 3.8808437;
    if (fabs(area / want - 1.0) > 0.01)
        fail_msg("covered area %g, want %g", area, want);
    render_scene_destroy(rs);
}

/* Pixel centres that see the S with `extra` on its Shape. */
static int covered(const char *extra)
{
    const int res = 200;
    char text[1400];
    s_scene(text, sizeof text, extra);
    render_scene *rs = build_scene_or_fail(text, NULL);
    int hits = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x)
            hits += eval_pixel(rs, x + 0.5, y + 0.5, 1).hit;
    render_scene_destroy(rs);
    return hits;
}

/* Alpha on curves, as on every pbrt-v4 shape: 0 hides the curve, 1/2 keeps
 * half its hits (each ray deciding), a checkerboard in u keeps the first
 * half of the S (u < 1/2) and hides the rest: by symmetry half the hits. */
static void test_alpha(void **state)
{
    (void)state;
    int all = covered(""), none = covered("\"float alpha\" 0");
    int half = covered("\"float alpha\" 0.5"), first = covered("\"texture alpha\" \"half\"");
    double sd = sqrt(all * 0.25);
    print_message("curve hits: alpha 1 %d, 0 %d, 0.5 %d (want %.0f +- %.0f), u < 1/2 %d\n", all,
                  none, half, all / 2.0, 4 * sd, first);
    assert_true(all > 900); /* area 0.388 over pixels of 0.0004 */
    assert_int_equal(none, 0);
    assert_true(fabs(half - all / 2.0) < 4.0 * sd);
    assert_true(fabs(first - all / 2.0) < 0.01 * all);
}

/* A straight curve along x (width 0.5) seen from +z under a distant light
 * from l = (0, 1, 0.2), diffuse 0.5: radiance 0.5/pi * 3 * max(0, n.l) with
 * pbrt-v4's normals, at pixel centres y across the width (v = 0.5 - y / w):
 * flat and ribbon (N = +z) face the viewer; a cylinder's normal is turned by
 * theta = -90 + 180 v degrees about the curve, (0, sin theta, cos theta). */
static void test_shading(void **state)
{
    (void)state;
    const char *types[3] = {"\"string type\" \"flat\"", "\"string type\" \"cylinder\"",
                            "\"string type\" \"ribbon\" \"normal N\" [0 0 1  0 0 1]"};
    vec3 l = v3_normalize(v3(0, 1, 0.2));
    for (int k = 0; k < 3; ++k) {
        char text[1024];
        snprintf(text, sizeof text,
                 "LookAt 0 0 5  0 0 0  0 1 0\n"
                 "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
                 "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 64\n"
                 "Integrator \"volpath\" \"integer maxdepth\" 1\n"
                 "WorldBegin\nLightSource \"distant\" \"point3 from\" [0 1 0.2] "
                 "\"point3 to\" [0 0 0] \"rgb L\" [3 3 3]\n"
                 "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
                 "Shape \"curve\" \"point3 P\" [-2 0 0  -1 0 0  1 0 0  2 0 0] "
                 "\"float width\" 0.5 %s\n",
                 types[k]);
        render_scene *rs = build_scene_or_fail(text, NULL);
        for (int py = 24; py < 40; py += 3) {
            double y = 0.5 - (py + 0.5) / 64.0, v = 0.5 - y / 0.5;
            double th = (-90.0 + 180.0 * v) * HZ_PI / 180.0;
            vec3 n = k == 1 ? v3(0, sin(th), cos(th)) : v3(0, 0, 1);
            double want = 0.5 * HZ_INV_PI * 3.0 * fmax(0.0, v3_dot(n, l));
            pixel_eval e = eval_pixel(rs, 32.5, py + 0.5, 1);
            assert_true(e.hit);
            expect_close(e.L.r, want, 1e-6, 1e-6, types[k], 32, py);
        }
        render_scene_destroy(rs);
    }
}

/* Under a uniform sky of radiance 1 a diffuse curve of albedo 0.5 reads 0.5
 * everywhere: no ray leaving it hits the curve itself (pbrt-v4's offset of
 * the leaving rays by the width), whatever the type. */
static void test_no_self_shadowing(void **state)
{
    (void)state;
    const char *types[3] = {"\"string type\" \"flat\"", "\"string type\" \"cylinder\"",
                            "\"string type\" \"ribbon\" \"normal N\" [0 0 1  0 1 1]"};
    for (int k = 0; k < 3; ++k) {
        char text[1024];
        snprintf(text, sizeof text,
                 "LookAt 0 0 5  0 0 0  0 1 0\n"
                 "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
                 "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 64\n"
                 "Sampler \"zsobol\" \"integer pixelsamples\" 256\n"
                 "Integrator \"volpath\" \"integer maxdepth\" 1\n"
                 "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                 "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
                 "Shape \"curve\" \"point3 P\" [-2 0 0  -1 0 0  1 0 0  2 0 0] "
                 "\"float width\" 0.5 %s\n",
                 types[k]);
        render_scene *rs = build_scene_or_fail(text, NULL);
        for (int py = 26; py < 38; py += 3) {
            pixel_eval e = eval_pixel(rs, 20.5, py + 0.5, 256);
            assert_true(e.hit);
            expect_close(e.L.r, 0.5, 0.02, 0, types[k], 20, py);
        }
        render_scene_destroy(rs);
    }
}

/* Hair without absorption on a curve under a uniform sky of radiance 1
 * reads 1 everywhere across it (the white furnace through the integrators:
 * the hair's frame from dp/du, h from v, light from both sides), under
 * volpath and singlescatter. */
static void test_hair_furnace(void **state)
{
    (void)state;
    const char *integrators[2] = {"Integrator \"volpath\" \"integer maxdepth\" 1",
                                  "Integrator \"singlescatter\""};
    for (int k = 0; k < 2; ++k) {
        char text[1024];
        snprintf(text, sizeof text,
                 "LookAt 0 0 5  0 0 0  0 1 0\n"
                 "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
                 "Film \"rgb\" \"integer xresolution\" 64 \"integer yresolution\" 64\n"
                 "Sampler \"zsobol\" \"integer pixelsamples\" 1024\n%s\n"
                 "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                 "Material \"hair\" \"rgb sigma_a\" [0 0 0] \"float beta_m\" 0.5 "
                 "\"float beta_n\" 0.5\n"
                 "Shape \"curve\" \"point3 P\" [-2 0.1 0  -1 0 0.3  1 0 -0.3  2 -0.1 0] "
                 "\"float width\" 0.5 \"string type\" \"cylinder\"\n",
                 integrators[k]);
        render_scene *rs = build_scene_or_fail(text, NULL);
        for (int py = 26; py < 38; py += 3) {
            pixel_eval e = eval_pixel(rs, 24.5, py + 0.5, 1024);
            assert_true(e.hit);
            expect_close(e.L.g, 1.0, 0.03, 0, integrators[k], 24, py);
        }
        render_scene_destroy(rs);
    }
}

static void test_refusals(void **state)
{
    (void)state;
    char msg[1024];
    static const char *const cases[][2] = {
        {"AttributeBegin\nAreaLightSource \"diffuse\"\nShape \"curve\" \"point3 P\" [0 0 0 1 0 0 "
         "2 0 0 3 0 0]\nAttributeEnd\n",
         "AreaLightSource on a curve is not supported"},
        {"MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\nMaterial \"interface\"\n"
         "MediumInterface \"m\" \"\"\nShape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n",
         "a curve cannot separate media"},
        {"Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"string type\" \"ribbon\"\n",
         "needs \"normal N\""},
        {"Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"normal N\" [0 0 1 0 0 1]\n",
         "used by \"ribbon\" curves only"},
        {"Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]\n",
         "needs 4 + 3 n control points"},
        {"Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"integer degree\" 4\n",
         "\"degree\" must be 2 or 3"},
        {"Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"string basis\" \"hermite\"\n",
         "\"basis\" must be"},
        {"Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"float width\" -1\n",
         "widths must be finite and >= 0"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char *text = cat("Camera \"perspective\"\nWorldBegin\n", cases[i][0], "");
        build_scene_expect_error(text, msg, sizeof msg);
        if (!strstr(msg, cases[i][1]) || !strstr(msg, "test.pbrt:"))
            fail_msg("case %zu: got \"%s\", want \"%s\"", i, msg, cases[i][1]);
        free(text);
    }
}

/* Embree's packets reach haze's user geometry (curves, spheres) with N > 1
 * lanes: rays straight down through the S and a sphere under it, traced one
 * by one and as packets of 8 (every other lane off), give the same hits, u
 * and t, and the same shadow-ray verdicts. */
static void test_packets(void **state)
{
    (void)state;
    char text[1600];
    s_scene(text, sizeof text, "");
    strcat(text, "AttributeBegin\nTranslate 0.3 0 -1\nShape \"sphere\" \"float radius\" 0.8\n"
                 "AttributeEnd\n");
    render_scene *rs = build_scene_or_fail(text, NULL);
    RTCScene scene = geometry_embree_scene(render_scene_geometry(rs));
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    int hits = 0, blocked = 0;
    unsigned first = RTC_INVALID_GEOMETRY_ID, other = RTC_INVALID_GEOMETRY_ID;
    for (int row = 0; row < 40; ++row)
        for (int x0 = 0; x0 < 40; x0 += 8) {
            RTC_ALIGN(32) int valid[8];
            RTC_ALIGN(32) struct RTCRayHit8 rh8;
            RTC_ALIGN(32) struct RTCRay8 r8;
            struct RTCRayHit one[8];
            for (int k = 0; k < 8; ++k) {
                float x = -2.0f + 0.1f * (float)(x0 + k) + 0.05f, y = -2.0f + 0.1f * row + 0.05f;
                valid[k] = (k & 1) ? 0 : -1;
                memset(&one[k], 0, sizeof one[k]);
                one[k].ray.org_x = x, one[k].ray.org_y = y, one[k].ray.org_z = 5.0f;
                one[k].ray.dir_z = -1.0f;
                one[k].ray.tfar = INFINITY;
                one[k].ray.mask = 0xFFFFFFFFu;
                one[k].hit.geomID = one[k].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                rh8.ray.org_x[k] = r8.org_x[k] = x;
                rh8.ray.org_y[k] = r8.org_y[k] = y;
                rh8.ray.org_z[k] = r8.org_z[k] = 5.0f;
                rh8.ray.dir_x[k] = r8.dir_x[k] = 0.0f;
                rh8.ray.dir_y[k] = r8.dir_y[k] = 0.0f;
                rh8.ray.dir_z[k] = r8.dir_z[k] = -1.0f;
                rh8.ray.tnear[k] = r8.tnear[k] = 0.0f;
                rh8.ray.tfar[k] = r8.tfar[k] = INFINITY;
                rh8.ray.time[k] = r8.time[k] = 0.0f;
                rh8.ray.mask[k] = r8.mask[k] = 0xFFFFFFFFu;
                rh8.ray.id[k] = r8.id[k] = 0;
                rh8.ray.flags[k] = r8.flags[k] = 0;
                rh8.hit.geomID[k] = rh8.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
            }
            rtcIntersect8(valid, scene, &ctx, &rh8);
            rtcOccluded8(valid, scene, &ctx, &r8);
            for (int k = 0; k < 8; k += 2) {
                struct RTCRay shadow = one[k].ray;
                rtcIntersect1(scene, &ctx, &one[k]);
                rtcOccluded1(scene, &ctx, &shadow);
                assert_int_equal(rh8.hit.geomID[k], one[k].hit.geomID);
                assert_true((shadow.tfar < 0.0f) == (r8.tfar[k] < 0.0f));
                blocked += shadow.tfar < 0.0f;
                if (one[k].hit.geomID == RTC_INVALID_GEOMETRY_ID)
                    continue;
                ++hits;
                if (first == RTC_INVALID_GEOMETRY_ID)
                    first = one[k].hit.geomID;
                else if (one[k].hit.geomID != first)
                    other = one[k].hit.geomID;
                assert_int_equal(rh8.hit.primID[k], one[k].hit.primID);
                assert_true(rh8.ray.tfar[k] == one[k].ray.tfar && rh8.hit.u[k] == one[k].hit.u);
            }
        }
    /* both shapes seen: the sphere (radius 0.8) and the S (area 0.39) */
    assert_true(hits > 100 && blocked == hits && other != RTC_INVALID_GEOMETRY_ID);
    render_scene_destroy(rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_coverage),
        cmocka_unit_test(test_alpha),
        cmocka_unit_test(test_shading),
        cmocka_unit_test(test_no_self_shadowing),
        cmocka_unit_test(test_hair_furnace),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_packets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
