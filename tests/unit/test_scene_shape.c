#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/shape.h"

/* Parses "WorldBegin <shape>" and builds the first shape's geometry. */
static hz_status build(const char *shape, const char *name, shape_geometry *g, hz_error *err)
{
    char src[1024];
    snprintf(src, sizeof src, "WorldBegin\n%s", shape);
    scene_desc sd;
    if (scene_parse_string(src, name, &sd, err) != HZ_OK)
        fail_msg("parse: %s", err->message);
    hz_status st = shape_geometry_create(&sd.shapes[0], g, err);
    scene_desc_free(&sd);
    return st;
}

static void expect_error(const char *shape, const char *want)
{
    shape_geometry g;
    hz_error err;
    assert_int_equal(build(shape, "s.pbrt", &g, &err), HZ_ERROR);
    if (!strstr(err.message, want))
        fail_msg("got \"%s\", want \"%s\"", err.message, want);
    assert_null(g.p);
}

static void test_trianglemesh(void **state)
{
    (void)state;
    shape_geometry g;
    hz_error err;
    assert_int_equal(build("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 1 1 0 0 1 0]\n"
                           "\"integer indices\" [0 1 2 0 2 3] \"normal N\" [0 0 1 0 0 1 0 0 1 0 0 1]\n"
                           "\"point2 uv\" [0 0 1 0 1 1 0 1]",
                           "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.vertex_count, 4);
    assert_int_equal(g.triangle_count, 2);
    assert_int_equal(g.indices[5], 3);
    assert_true(g.p[3 * 2 + 1] == 1.0);
    assert_true(g.n[3 * 3 + 2] == 1.0);
    assert_true(g.uv[2 * 2] == 1.0);
    shape_geometry_free(&g);

    /* Indices may be omitted for a single triangle. */
    assert_int_equal(build("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]", "s.pbrt", &g,
                           &err),
                     HZ_OK);
    assert_int_equal(g.triangle_count, 1);
    assert_null(g.n);
    shape_geometry_free(&g);
}

static void test_trianglemesh_errors(void **state)
{
    (void)state;
    expect_error("Shape \"trianglemesh\" \"integer indices\" [0 1 2]",
                 "s.pbrt:2:1: trianglemesh needs \"point3 P\"");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1]",
                 "s.pbrt:2:1: trianglemesh without \"integer indices\" must have exactly 3 vertices, has 4");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n \"integer indices\" [0 1]",
                 "s.pbrt:3:2: trianglemesh \"indices\" must be a multiple of 3, got 2 values");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n \"integer indices\" [0 1 3]",
                 "s.pbrt:3:2: trianglemesh index 3 (value 2) is out of range [0, 3)");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n \"integer indices\" [0 -1 2]",
                 "out of range");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n \"normal N\" [0 0 1]",
                 "s.pbrt:3:2: trianglemesh has 1 normals for 3 vertices");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n \"point2 uv\" [0 0 1 1]",
                 "s.pbrt:3:2: trianglemesh has 2 uvs for 3 vertices");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n \"float Pp\" 1",
                 "s.pbrt:3:2: unused parameter \"float Pp\" for Shape \"trianglemesh\"");
    expect_error("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"float indices\" [0 1 2]",
                 "parameter \"indices\" must be integer, not float");
    expect_error("Shape \"cone\"", "s.pbrt:2:1: unknown shape \"cone\"; supported:");
}

static void test_sphere_disk_bilinear(void **state)
{
    (void)state;
    shape_geometry g;
    hz_error err;
    assert_int_equal(build("Shape \"sphere\" \"float radius\" 2 \"float zmax\" 2", "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.kind, GEOMETRY_SPHERE);
    assert_true(g.radius == 2.0);
    shape_geometry_free(&g);
    assert_int_equal(build("Shape \"sphere\" \"float zmax\" -3 \"float zmin\" 0.5 "
                           "\"float phimax\" 90",
                           "s.pbrt", &g, &err),
                     HZ_OK);
    assert_true(g.zmin == -1.0 && g.zmax == 0.5); /* swapped and clamped, as pbrt-v4 */
    assert_float_equal(g.phimax, HZ_PI / 2.0, 1e-15);
    shape_geometry_free(&g);
    expect_error("Shape \"sphere\" \"float zmin\" 2 \"float zmax\" 3",
                 "sphere \"zmin\" and \"zmax\" leave nothing of it");
    expect_error("Shape \"sphere\" \"float radius\" 0", "s.pbrt:2:16: sphere \"radius\" must be > 0");

    assert_int_equal(build("Shape \"disk\" \"float height\" 1 \"float radius\" 2", "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.triangle_count, 256);
    double area = 0;
    for (size_t t = 0; t < g.triangle_count; ++t) {
        const double *a = &g.p[3 * g.indices[3 * t]], *b = &g.p[3 * g.indices[3 * t + 1]],
                     *c = &g.p[3 * g.indices[3 * t + 2]];
        double cz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert_true(cz > 0); /* counter-clockwise seen from +z */
        assert_true(a[2] == 1.0);
        area += 0.5 * cz;
    }
    assert_float_equal(area, HZ_PI * 4.0, 1e-3 * HZ_PI * 4.0);
    shape_geometry_free(&g);
    assert_int_equal(build("Shape \"disk\" \"float innerradius\" 0.5", "s.pbrt", &g, &err), HZ_OK);
    assert_int_equal(g.triangle_count, 512);
    shape_geometry_free(&g);
    expect_error("Shape \"disk\" \"float innerradius\" 2", "s.pbrt:2:14: disk \"innerradius\" must be in [0, radius)");

    assert_int_equal(build("Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]", "s.pbrt",
                           &g, &err),
                     HZ_OK);
    assert_int_equal(g.triangle_count, 2);
    /* pbrt's vertex order p00 p10 p01 p11: the quad's diagonal is 0-3. */
    const uint32_t want[6] = {0, 1, 3, 0, 3, 2};
    assert_memory_equal(g.indices, want, sizeof want);
    shape_geometry_free(&g);
}

static void test_plymesh_relative_path(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/shape_tri.ply", HAZE_TMP);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
          "0 0 0 1 0 0 0 1 0\n3 0 1 2\n",
          f);
    fclose(f);
    char scene[512];
    snprintf(scene, sizeof scene, "%s/some.pbrt", HAZE_TMP);
    shape_geometry g;
    hz_error err;
    if (build("Shape \"plymesh\" \"string filename\" \"shape_tri.ply\"", scene, &g, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(g.triangle_count, 1);
    shape_geometry_free(&g);
    assert_int_equal(build("Shape \"plymesh\" \"string filename\" \"missing.ply\"", scene, &g, &err),
                     HZ_ERROR);
    assert_non_null(strstr(err.message, "some.pbrt:2:17: plymesh: "));
    assert_non_null(strstr(err.message, "missing.ply: cannot open"));
    assert_int_equal(build("Shape \"plymesh\" \"string filename\" \"shape_tri.ply\" \"float "
                           "displacement\" 1",
                           scene, &g, &err),
                     HZ_ERROR);
    assert_non_null(strstr(err.message, "plymesh \"displacement\" is not supported"));
    /* Every shape takes "alpha": read, never left unused. */
    if (build("Shape \"plymesh\" \"string filename\" \"shape_tri.ply\" \"float alpha\" 0.5",
              scene, &g, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_float_equal(g.alpha, 0.5, 0.0);
    assert_null(g.alpha_texture);
    shape_geometry_free(&g);
}

/* pbrt-v4's cylinder (radius, zmin, zmax, phimax) as 256 segments per turn:
 * every vertex on the surface, every triangle facing outward with the
 * outward shading normal at its vertices, the area 2 pi r h (phimax h r for
 * a part) within the chords' 1e-4; disks take phimax too. */
static void test_cylinder(void **state)
{
    (void)state;
    shape_geometry g;
    hz_error err;
    const double phis[2] = {360.0, 90.0};
    for (int k = 0; k < 2; ++k) {
        char src[128];
        snprintf(src, sizeof src,
                 "Shape \"cylinder\" \"float radius\" 2 \"float zmin\" -0.5 "
                 "\"float zmax\" 1 \"float phimax\" %g",
                 phis[k]);
        assert_int_equal(build(src, "s.pbrt", &g, &err), HZ_OK);
        assert_int_equal(g.kind, GEOMETRY_TRIANGLES);
        double area = 0.0;
        for (size_t v = 0; v < g.vertex_count; ++v) {
            const double *p = &g.p[3 * v], *n = &g.n[3 * v];
            assert_float_equal(hypot(p[0], p[1]), 2.0, 1e-6);
            assert_true(p[2] == -0.5 || p[2] == 1.0);
            assert_float_equal(n[0] * p[0] + n[1] * p[1], 2.0, 1e-6); /* outward, unit */
        }
        for (size_t t = 0; t < g.triangle_count; ++t) {
            const double *a = &g.p[3 * g.indices[3 * t]], *b = &g.p[3 * g.indices[3 * t + 1]],
                         *c = &g.p[3 * g.indices[3 * t + 2]];
            double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2],
                   nz = e1[0] * e2[1] - e1[1] * e2[0];
            double mx = (a[0] + b[0] + c[0]) / 3.0, my = (a[1] + b[1] + c[1]) / 3.0;
            assert_true(nx * mx + ny * my > 0.0); /* outward */
            area += 0.5 * sqrt(nx * nx + ny * ny + nz * nz);
        }
        double want = hz_radians(phis[k]) * 2.0 * 1.5;
        assert_float_equal(area, want, 1e-4 * want);
        shape_geometry_free(&g);
    }
    expect_error("Shape \"cylinder\" \"float zmin\" 1 \"float zmax\" 1",
                 "cylinder \"zmin\" and \"zmax\" must be finite and differ");
    expect_error("Shape \"cylinder\" \"float phimax\" 400", "\"phimax\" must be in (0, 360]");
    assert_int_equal(build("Shape \"disk\" \"float phimax\" 180", "s.pbrt", &g, &err), HZ_OK);
    assert_int_equal(g.triangle_count, 128);
    shape_geometry_free(&g);
}

/* pbrt-v4's curve: Bezier segments sharing end points, quadratics raised to
 * cubic, uniform b-splines converted (the same curve: continuous, starting
 * at the b-spline's first knot point), widths linear over the whole curve. */
static void test_curve(void **state)
{
    (void)state;
    shape_geometry g;
    hz_error err;
    assert_int_equal(build("Shape \"curve\" \"point3 P\" [0 0 0 1 1 0 2 1 0 3 0 0 4 -1 0 5 -1 0 "
                           "6 0 0] \"float width0\" 1 \"float width1\" 3 \"integer splitdepth\" 2",
                           "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.kind, GEOMETRY_CURVES);
    assert_int_equal(g.curve, CURVE_FLAT);
    assert_int_equal(g.segment_count, 2);
    assert_int_equal(g.split, 2);
    assert_true(g.cp[12 + 0] == 3.0 && g.cp[12 + 9] == 6.0); /* segment 1: P3 .. P6 */
    assert_true(g.width[0] == 1.0 && g.width[1] == 2.0 && g.width[2] == 2.0 && g.width[3] == 3.0);
    assert_null(g.normals);
    shape_geometry_free(&g);

    /* Quadratic Bezier: (p0, p0 + 2/3 (p1 - p0), p2 + 2/3 (p1 - p2), p2). */
    assert_int_equal(build("Shape \"curve\" \"point3 P\" [0 0 0 3 3 0 6 0 0] \"integer degree\" 2",
                           "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.segment_count, 1);
    const double q[12] = {0, 0, 0, 2, 2, 0, 4, 2, 0, 6, 0, 0};
    for (int i = 0; i < 12; ++i)
        assert_true(fabs(g.cp[i] - q[i]) < 1e-12);
    shape_geometry_free(&g);

    /* Cubic b-spline: 5 points, 2 segments, joined; it starts at
     * (P0 + 4 P1 + P2) / 6. */
    assert_int_equal(build("Shape \"curve\" \"point3 P\" [0 0 0 1 2 0 2 0 1 3 3 0 4 0 0] "
                           "\"string basis\" \"bspline\" \"string type\" \"cylinder\"",
                           "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.segment_count, 2);
    assert_int_equal(g.curve, CURVE_CYLINDER);
    const double start[3] = {(0 + 4 * 1 + 2) / 6.0, (0 + 4 * 2 + 0) / 6.0, (0 + 0 + 1) / 6.0};
    for (int k = 0; k < 3; ++k) {
        assert_true(fabs(g.cp[k] - start[k]) < 1e-12);
        assert_true(fabs(g.cp[9 + k] - g.cp[12 + k]) < 1e-12);
    }
    shape_geometry_free(&g);

    /* Quadratic b-spline: starts at the midpoint of P0 P1. */
    assert_int_equal(build("Shape \"curve\" \"point3 P\" [0 0 0 2 2 0 4 0 0 6 2 0] "
                           "\"string basis\" \"bspline\" \"integer degree\" 2",
                           "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.segment_count, 2);
    assert_true(g.cp[0] == 1.0 && g.cp[1] == 1.0);
    assert_true(fabs(g.cp[9] - g.cp[12]) < 1e-12 && fabs(g.cp[10] - g.cp[13]) < 1e-12);
    shape_geometry_free(&g);

    /* A ribbon's normals, normalised, at each segment's ends. */
    assert_int_equal(build("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] "
                           "\"string type\" \"ribbon\" \"normal N\" [0 0 2 0 3 0]",
                           "s.pbrt", &g, &err),
                     HZ_OK);
    assert_int_equal(g.curve, CURVE_RIBBON);
    assert_true(g.normals[2] == 1.0 && g.normals[4] == 1.0);
    shape_geometry_free(&g);

    expect_error("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"normal N\" [0 0 1]",
                 "s.pbrt:2:52: curve \"N\" is used by \"ribbon\" curves only");
    expect_error("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0 5 0 0 6 0 0] "
                 "\"string type\" \"ribbon\" \"normal N\" [0 0 1 0 0 1]",
                 "2 segments need 3 normals");
    expect_error("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0] \"string basis\" \"bspline\"",
                 "b-spline needs at least 4 control points");
    expect_error("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"string type\" \"tube\"",
                 "curve \"type\" must be");
    expect_error("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"integer splitdepth\" 9",
                 "\"splitdepth\" must be in [0, 8]");
    expect_error("Shape \"curve\" \"float width\" 1", "curve needs \"point3 P\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trianglemesh),
        cmocka_unit_test(test_trianglemesh_errors),
        cmocka_unit_test(test_sphere_disk_bilinear),
        cmocka_unit_test(test_cylinder),
        cmocka_unit_test(test_curve),
        cmocka_unit_test(test_plymesh_relative_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
