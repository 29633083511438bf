/* Out of memory while reading a scene: each allocation of a parse (and of the
 * shape factories) is made to fail in turn. The GNU linker's --wrap (see
 * tests/CMakeLists.txt) sends malloc, calloc and realloc of everything linked
 * into this test, the static haze_scene and haze_core included, to the
 * wrappers below; the library itself has no test hook. Every failure must end
 * in HZ_ERROR and "file:line:column: out of memory", with everything freed
 * (the sanitizer build checks leaks) and the process still running: the
 * scene code used to print a line and exit(). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_desc.h"
#include "scene/shape.h"

/* ---- the failing allocator ---------------------------------------------- */

static long fail_at;     /* the allocation that fails, counted from 1; 0: off */
static bool fail_after;  /* and every one after it (memory does not come back) */
static long alloc_calls; /* allocations since arm() */

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t n);

static bool fails_now(void)
{
    if (fail_at == 0)
        return false;
    ++alloc_calls;
    return alloc_calls == fail_at || (fail_after && alloc_calls > fail_at);
}

void *__wrap_malloc(size_t n) { return fails_now() ? NULL : __real_malloc(n); }
void *__wrap_calloc(size_t n, size_t size) { return fails_now() ? NULL : __real_calloc(n, size); }
void *__wrap_realloc(void *p, size_t n) { return fails_now() ? NULL : __real_realloc(p, n); }

static void arm(long n, bool persistent)
{
    alloc_calls = 0;
    fail_after = persistent;
    fail_at = n;
}

static void disarm(void) { fail_at = 0; }

/* ---- scenes ------------------------------------------------------------- */

/* Something of every kind that allocates: options entities, spectrum and
 * blackbody values, Attribute defaults, AttributeBegin copies of the state
 * (with an area light), named media and materials, objects and instances,
 * coordinate systems, and arrays long enough to grow several times. */
static const char scene[] =
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" 40\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
    "  \"string filename\" \"out.exr\"\n"
    "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
    "Integrator \"volpath\" \"integer maxdepth\" 5\n"
    "Option \"bool disablepixeljitter\" true\n"
    "CoordinateSystem \"start\"\n"
    "WorldBegin\n"
    "Attribute \"shape\" \"float radius\" 2\n"
    "LightSource \"infinite\" \"spectrum L\" [400 1 500 2 600 3 700 2]\n"
    "LightSource \"point\" \"blackbody I\" 5500 \"point3 from\" [0 4 0]\n"
    "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
    "  \"rgb sigma_a\" [0.1 0.1 0.1] \"rgb sigma_s\" [0.5 0.5 0.5] \"float scale\" 2\n"
    "MakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.8 0.1 0.1]\n"
    "Material \"dielectric\" \"float eta\" 1.5 \"string names\" [\"a\" \"b\"]\n"
    "  \"bool flags\" [true false true]\n"
    "AttributeBegin\n"
    "  AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
    "  NamedMaterial \"red\"\n"
    "  MediumInterface \"fog\" \"\"\n"
    "  Translate 0 1 0\n"
    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2  0 2 3  0 3 4  0 4 5  0 5 6]\n"
    "    \"point3 P\" [0 0 0  1 0 0  1 1 0  0 1 0  -1 1 0  -1 0 0  -1 -1 0]\n"
    "    \"normal N\" [0 0 1  0 0 1  0 0 1  0 0 1  0 0 1  0 0 1  0 0 1]\n"
    "    \"point2 uv\" [0 0  1 0  1 1  0 1  0 1  0 0  0 0]\n"
    "AttributeEnd\n"
    "ObjectBegin \"pair\"\n"
    "  Shape \"sphere\"\n"
    "  Shape \"disk\" \"float radius\" 1 \"float innerradius\" 0.5\n"
    "ObjectEnd\n"
    "AttributeBegin\n"
    "  Rotate 30 0 1 0\n"
    "  ObjectInstance \"pair\"\n"
    "AttributeEnd\n"
    "ObjectInstance \"pair\"\n"
    "CoordSysTransform \"start\"\n"
    "Shape \"bilinearmesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  1 1 0]\n";

static void check_error(const hz_error *err, const char *what, long n)
{
    /* One error with the scene's place: out of memory ended the parse. */
    if (strncmp(err->message, "oom.pbrt:", 9) != 0 || !strstr(err->message, ": out of memory") ||
        strchr(err->message, '\n'))
        fail_msg("%s, allocation %ld failing: got \"%s\", want \"oom.pbrt:L:C: out of memory\"",
                 what, n, err->message);
}

/* Allocations a successful parse of `text` makes. */
static long count_parse_allocations(const char *text)
{
    scene_desc sd;
    hz_error err;
    arm(LONG_MAX, false);
    hz_status st = scene_parse_string(text, "oom.pbrt", &sd, &err);
    long n = alloc_calls;
    disarm();
    if (st != HZ_OK)
        fail_msg("the scene does not parse: %s", err.message);
    scene_desc_free(&sd);
    return n;
}

static void parse_failing(const char *text, bool persistent)
{
    long total = count_parse_allocations(text);
    /* --wrap in effect (else this test would prove nothing). */
    assert_true(total > 100);
    print_message("failing each of %ld allocations%s\n", total, persistent ? " and all after" : "");
    for (long n = 1; n <= total; ++n) {
        scene_desc sd;
        hz_error err;
        arm(n, persistent);
        hz_status st = scene_parse_string(text, "oom.pbrt", &sd, &err);
        long after = alloc_calls - n;
        disarm();
        if (st == HZ_OK)
            fail_msg("allocation %ld of %ld failed, yet the parse succeeded", n, total);
        check_error(&err, "parse", n);
        /* The rest of the scene was not read: only the error list and the
         * sibling allocations of the failing directive may follow. */
        if (after > 4)
            fail_msg("allocation %ld failed, yet the parse went on (%ld more allocations)", n,
                     after);
        /* Emptied (and freed: the sanitizer build checks leaks). */
        assert_null(sd.strings);
        assert_null(sd.shapes);
        assert_int_equal(sd.file_count, 0);
    }
    /* With every allocation served, the same parse succeeds. */
    scene_desc sd;
    hz_error err;
    arm(total + 1, persistent);
    hz_status st = scene_parse_string(text, "oom.pbrt", &sd, &err);
    disarm();
    if (st != HZ_OK)
        fail_msg("failing allocation %ld (none made) broke the parse: %s", total + 1, err.message);
    scene_desc_free(&sd);
}

/* Only the Nth allocation fails: each failure path on its own. */
static void test_parse_one_failure(void **state)
{
    (void)state;
    parse_failing(scene, false);
}

/* The Nth and every later one fail, as when memory is really exhausted: the
 * error list cannot be allocated either and the error is still reported. */
static void test_parse_memory_exhausted(void **state)
{
    (void)state;
    parse_failing(scene, true);
}

/* ---- shape factories ---------------------------------------------------- */

static const char ply_quad[] = "ply\nformat ascii 1.0\n"
                               "element vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nproperty float u\nproperty float v\n"
                               "element face 2\nproperty list uchar int vertex_indices\n"
                               "end_header\n"
                               "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n"
                               "4 0 1 2 3\n3 0 2 3\n";

static void create_failing(shape_entity *se, const char *file)
{
    shape_geometry g;
    hz_error err;
    arm(LONG_MAX, false);
    hz_status st = shape_geometry_create(se, &g, &err);
    long total = alloc_calls;
    disarm();
    if (st != HZ_OK)
        fail_msg("Shape \"%s\" fails: %s", se->entity.type, err.message);
    shape_geometry_free(&g);
    assert_true(total > 0);
    print_message("Shape \"%s\": failing each of %ld allocations\n", se->entity.type, total);
    for (long n = 1; n <= total; ++n) {
        arm(n, false);
        st = shape_geometry_create(se, &g, &err);
        disarm();
        if (st == HZ_OK)
            fail_msg("Shape \"%s\": allocation %ld of %ld failed, yet it succeeded",
                     se->entity.type, n, total);
        if (strncmp(err.message, file, strlen(file)) != 0 || !strstr(err.message, "out of memory"))
            fail_msg("Shape \"%s\", allocation %ld failing: got \"%s\"", se->entity.type, n,
                     err.message);
        assert_null(g.p); /* freed */
        assert_null(g.indices);
    }
}

static void test_shapes(void **state)
{
    (void)state;
    char dir_scene[512], ply_path[512], text[sizeof scene + 100];
    snprintf(dir_scene, sizeof dir_scene, "%s/oom.pbrt", HAZE_TMP);
    snprintf(ply_path, sizeof ply_path, "%s/oom_quad.ply", HAZE_TMP);
    FILE *f = fopen(ply_path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(ply_quad, 1, sizeof ply_quad - 1, f), sizeof ply_quad - 1);
    assert_int_equal(fclose(f), 0);
    snprintf(text, sizeof text, "%sShape \"plymesh\" \"string filename\" \"oom_quad.ply\"\n",
             scene);
    scene_desc sd;
    hz_error err;
    if (scene_parse_string(text, dir_scene, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    size_t meshes = 0;
    for (size_t i = 0; i < sd.shape_count; ++i)
        if (strcmp(sd.shapes[i].entity.type, "sphere") != 0) { /* spheres allocate nothing */
            create_failing(&sd.shapes[i], dir_scene);
            ++meshes;
        }
    for (size_t i = 0; i < sd.object_shape_count; ++i)
        if (strcmp(sd.object_shapes[i].entity.type, "sphere") != 0) {
            create_failing(&sd.object_shapes[i], dir_scene);
            ++meshes;
        }
    assert_int_equal(meshes, 4); /* trianglemesh, bilinearmesh, plymesh, disk */
    scene_desc_free(&sd);
    remove(ply_path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_one_failure),
        cmocka_unit_test(test_parse_memory_exhausted),
        cmocka_unit_test(test_shapes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
