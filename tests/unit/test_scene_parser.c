#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <zlib.h>

#include "core/digest_cache.h"
#include "core/hash.h"
#include "scene/scene_desc.h"

static void parse_ok(const char *src, scene_desc *sd)
{
    hz_error err;
    if (scene_parse_string(src, "t.pbrt", sd, &err) != HZ_OK)
        fail_msg("unexpected error: %s", err.message);
}

static void parse_err(const char *src, const char *want)
{
    scene_desc sd;
    hz_error err;
    if (scene_parse_string(src, "t.pbrt", &sd, &err) == HZ_OK) {
        scene_desc_free(&sd);
        fail_msg("expected error \"%s\"", want);
    }
    if (!strstr(err.message, want))
        fail_msg("got \"%s\", want \"%s\"", err.message, want);
    assert_int_equal(sd.shape_count, 0);
    assert_null(sd.strings);
}

/* pbrt-v4 reads the first of two parameters of one name and type (the
 * other is shadowed, pbrt-v4-scenes' villa has such a roughness) and
 * pbrt-v3's TransformBegin/End as AttributeBegin/End: both accepted with a
 * warning recorded for the build to print. */
static void test_pbrt_v4_leniencies(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("Camera \"perspective\" \"float fov\" 30\n   \"float fov\" 40\nWorldBegin\n"
             "TransformBegin\nTranslate 1 2 3\nMaterial \"conductor\"\nTransformEnd\n"
             "TransformBegin\nTransformEnd\nShape \"sphere\"\n",
             &sd);
    param_list *pl = &sd.camera.entity.params;
    assert_true(params_float(pl, "fov", 0) == 30.0);
    hz_error err;
    assert_int_equal(params_finish(pl, "Camera", &err), HZ_OK); /* the second is not "unused" */
    assert_int_equal(sd.warning_count, 2);
    assert_non_null(strstr(sd.warnings[0], "t.pbrt:2:4: warning: parameter \"float fov\" given "
                                           "again: the first (line 1) is used"));
    assert_non_null(strstr(sd.warnings[1], "t.pbrt:4:1: warning: TransformBegin/End"));
    /* The state came back: no transform, the default material. */
    assert_int_equal(sd.shape_count, 1);
    assert_int_equal(sd.shapes[0].material, -1);
    scene_desc_free(&sd);
    parse_err("WorldBegin\nTransformEnd", "t.pbrt:2:1: AttributeEnd without a matching");
}

static void assert_mat(const mat4 *m, const double want[4][4])
{
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (fabs(m->m[r][c] - want[r][c]) > 1e-12)
                fail_msg("m[%d][%d] = %g, want %g", r, c, m->m[r][c], want[r][c]);
}

static void assert_point(const transform *t, vec3 p, vec3 want)
{
    vec3 q = transform_point(t, p);
    if (v3_length(v3_sub(q, want)) > 1e-12)
        fail_msg("got (%g %g %g), want (%g %g %g)", q.x, q.y, q.z, want.x, want.y, want.z);
}

static void test_defaults(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin", &sd);
    assert_string_equal(sd.camera.entity.type, "perspective");
    assert_string_equal(sd.film.type, "rgb");
    assert_string_equal(sd.sampler.type, "zsobol");
    assert_string_equal(sd.filter.type, "gaussian");
    assert_string_equal(sd.integrator.type, "volpath");
    assert_true(transform_is_identity(sd.camera.camera_from_world));
    assert_string_equal(sd.camera.medium, "");
    assert_string_equal(sd.film.loc.file, "t.pbrt");
    assert_int_equal(sd.film.loc.line, 1);
    assert_int_equal(sd.camera.entity.params.count, 0);
    assert_true(sd.transform_start_time == 0.0 && sd.transform_end_time == 1.0);
    scene_desc_free(&sd);
}

static void test_look_at(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("LookAt 2 0 0  3 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\nWorldBegin", &sd);
    /* dir = +x, right = up x dir = (0,0,-1), up' = dir x right = (0,1,0);
     * camera_from_world rows are right, up', dir; translation -R eye. */
    const double want[4][4] = {{0, 0, -1, 0}, {0, 1, 0, 0}, {1, 0, 0, -2}, {0, 0, 0, 1}};
    assert_mat(&sd.camera.camera_from_world.m, want);
    assert_point(&sd.camera.camera_from_world, v3(3, 0, 0), v3(0, 0, 1));
    assert_int_equal(sd.camera.entity.loc.line, 2);
    assert_int_equal(sd.camera.entity.loc.column, 1);
    assert_int_equal(sd.camera.entity.params.count, 1);
    assert_true(params_float(&sd.camera.entity.params, "fov", 90) == 45.0);
    scene_desc_free(&sd);
}

static void test_transform_is_transposed(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("Transform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\nCamera \"orthographic\"\n"
             "WorldBegin\nConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 1 0 0 1]\nShape \"sphere\"",
             &sd);
    const double want[4][4] = {{1, 0, 0, 5}, {0, 1, 0, 6}, {0, 0, 1, 7}, {0, 0, 0, 1}};
    assert_mat(&sd.camera.camera_from_world.m, want);
    assert_int_equal(sd.shape_count, 1);
    assert_point(&sd.shapes[0].world_from_object, v3(1, 1, 1), v3(3, 2, 2));
    scene_desc_free(&sd);
}

static void test_composition_order(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin\n"
             "AttributeBegin Translate 1 0 0 Scale 2 2 2 Shape \"sphere\" AttributeEnd\n"
             "AttributeBegin Rotate 90 0 0 1 Translate 1 0 0 Shape \"sphere\" AttributeEnd\n"
             "Shape \"sphere\"\n",
             &sd);
    assert_int_equal(sd.shape_count, 3);
    /* ctm = T * S: the scale applies first. */
    assert_point(&sd.shapes[0].world_from_object, v3(1, 0, 0), v3(3, 0, 0));
    /* ctm = R * T: translate, then rotate about z. */
    assert_point(&sd.shapes[1].world_from_object, v3(0, 0, 0), v3(0, 1, 0));
    assert_true(transform_is_identity(sd.shapes[2].world_from_object));
    scene_desc_free(&sd);
}

static void test_attribute_restore(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin\nMaterial \"diffuse\"\n"
             "AttributeBegin\n  Translate 0 0 1\n  ReverseOrientation\n  Material \"interface\"\n"
             "  MediumInterface \"fog\" \"\"\n  AreaLightSource \"diffuse\" \"rgb L\" [1 2 3]\n"
             "  Shape \"sphere\"\nAttributeEnd\nShape \"sphere\"\n",
             &sd);
    assert_int_equal(sd.shape_count, 2);
    assert_int_equal(sd.material_count, 2);
    const shape_entity *a = &sd.shapes[0], *b = &sd.shapes[1];
    assert_true(a->reverse_orientation);
    assert_int_equal(a->material, 1);
    assert_string_equal(sd.materials[1].entity.type, "interface");
    assert_string_equal(a->inside_medium, "fog");
    assert_string_equal(a->outside_medium, "");
    assert_true(a->has_area_light);
    assert_string_equal(a->area_light.type, "diffuse");
    rgb L = params_rgb((param_list *)&a->area_light.params, "L", rgb_grey(0));
    assert_true(L.r == 1 && L.g == 2 && L.b == 3);
    assert_point(&a->world_from_object, v3(0, 0, 0), v3(0, 0, 1));
    assert_false(b->reverse_orientation);
    assert_int_equal(b->material, 0);
    assert_false(b->has_area_light);
    assert_string_equal(b->inside_medium, "");
    assert_true(transform_is_identity(b->world_from_object));
    scene_desc_free(&sd);
}

static void test_default_material(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin Shape \"sphere\"", &sd);
    assert_int_equal(sd.shapes[0].material, -1);
    scene_desc_free(&sd);
}

static void test_coordsys(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("Translate 0 0 5\nCoordinateSystem \"five\"\nIdentity\nCamera \"perspective\"\n"
             "WorldBegin\nCoordSysTransform \"five\"\nShape \"sphere\"\n"
             "CoordSysTransform \"camera\"\nShape \"sphere\"\n"
             "CoordSysTransform \"world\"\nShape \"sphere\"\n",
             &sd);
    assert_point(&sd.shapes[0].world_from_object, v3(0, 0, 0), v3(0, 0, 5));
    assert_true(transform_is_identity(sd.shapes[1].world_from_object));
    assert_true(transform_is_identity(sd.shapes[2].world_from_object));
    scene_desc_free(&sd);

    parse_ok("LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
             "CoordSysTransform \"camera\"\nShape \"sphere\"",
             &sd);
    /* "camera" is world_from_camera: the camera's origin lands at the eye. */
    assert_point(&sd.shapes[0].world_from_object, v3(0, 0, 0), v3(0, 0, -3));
    assert_point(&sd.shapes[0].world_from_object, v3(0, 0, 1), v3(0, 0, -2));
    scene_desc_free(&sd);
    parse_err("WorldBegin\nCoordSysTransform \"nope\"",
              "t.pbrt:2:1: CoordSysTransform: no coordinate system named \"nope\"");
}

static void test_active_transform(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("TransformTimes 0 2\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n"
             "Camera \"perspective\"\nWorldBegin",
             &sd);
    assert_true(transform_is_identity(sd.camera.camera_from_world));
    assert_point(&sd.camera.camera_from_world_end, v3(0, 0, 0), v3(1, 0, 0));
    assert_true(sd.transform_end_time == 2.0);
    scene_desc_free(&sd);
    parse_err("ActiveTransform Sometimes WorldBegin", "t.pbrt:1:17: ActiveTransform expects");
}

/* pbrt-v4's two current transforms, in detail: transform directives change
 * the active ones only (Transform and Identity too); AttributeBegin/End and
 * ObjectBegin/End save and restore both and the active set; CoordinateSystem
 * and CoordSysTransform save and restore both whatever is active; WorldBegin
 * resets both and makes both active; shapes, lights, instances and the camera
 * record both. */
static void test_active_transform_pbrt_rules(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("TransformTimes 1 3\n"
             "ActiveTransform EndTime\nTranslate 0 0 1\nActiveTransform All\n"
             "Camera \"perspective\"\n"
             "ActiveTransform EndTime\n" /* still active at WorldBegin: reset to All */
             "WorldBegin\n"
             "Translate 1 0 0\n"
             "Shape \"sphere\"\n"                                           /* 0 */
             "AttributeBegin\nActiveTransform StartTime\nTranslate 0 1 0\n"
             "Shape \"sphere\"\n"                                           /* 1 */
             "AttributeEnd\n"
             "Shape \"sphere\"\n"                                           /* 2 */
             "AttributeBegin\nActiveTransform EndTime\nIdentity\nShape \"sphere\"\n" /* 3 */
             "ActiveTransform StartTime\nTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 5 1]\n"
             "Shape \"sphere\"\n"                                           /* 4 */
             "ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 2 0 1]\n"
             "CoordinateSystem \"c\"\n"
             "ActiveTransform All\nIdentity\nActiveTransform EndTime\n"
             "CoordSysTransform \"c\"\nShape \"sphere\"\n"                  /* 5 */
             "LightSource \"point\"\n"
             "AttributeEnd\n"
             "AttributeBegin\nCoordSysTransform \"camera\"\nShape \"sphere\"\n" /* 6 */
             "AttributeEnd\n"
             "ObjectBegin \"o\"\nActiveTransform EndTime\nTranslate 0 0 7\nObjectEnd\n"
             "Translate 0 3 0\n" /* All again after ObjectEnd */
             "ObjectInstance \"o\"\n",
             &sd);
    assert_true(sd.transform_start_time == 1.0 && sd.transform_end_time == 3.0);
    assert_true(sd.camera.transform_start_time == 1.0 && sd.camera.transform_end_time == 3.0);
    assert_int_equal(sd.shape_count, 7);
    const shape_entity *sh = sd.shapes;
    vec3 o = v3(0, 0, 0);
    assert_point(&sh[0].world_from_object, o, v3(1, 0, 0));
    assert_point(&sh[0].world_from_object_end, o, v3(1, 0, 0));
    assert_point(&sh[1].world_from_object, o, v3(1, 1, 0));
    assert_point(&sh[1].world_from_object_end, o, v3(1, 0, 0));
    assert_point(&sh[2].world_from_object, o, v3(1, 0, 0)); /* restored, All active */
    assert_point(&sh[2].world_from_object_end, o, v3(1, 0, 0));
    assert_point(&sh[3].world_from_object, o, v3(1, 0, 0));
    assert_point(&sh[3].world_from_object_end, o, v3(0, 0, 0));
    assert_point(&sh[4].world_from_object, o, v3(0, 0, 5));
    assert_point(&sh[4].world_from_object_end, o, v3(0, 0, 0));
    /* "c" saved (0 2 5) / (0 0 0); Identity reset both; CoordSysTransform
     * restores both with only EndTime active */
    assert_point(&sh[5].world_from_object, o, v3(0, 2, 5));
    assert_point(&sh[5].world_from_object_end, o, v3(0, 0, 0));
    assert_int_equal(sd.light_count, 1);
    assert_point(&sd.lights[0].world_from_light, o, v3(0, 2, 5));
    assert_point(&sd.lights[0].world_from_light_end, o, v3(0, 0, 0));
    /* "camera" is world_from_camera at both times */
    assert_point(&sh[6].world_from_object, o, v3(0, 0, 0));
    assert_point(&sh[6].world_from_object_end, o, v3(0, 0, -1));
    assert_int_equal(sd.instance_count, 1);
    assert_point(&sd.instances[0].world_from_instance, o, v3(1, 3, 0));
    assert_point(&sd.instances[0].world_from_instance_end, o, v3(1, 3, 0));
    scene_desc_free(&sd);
    parse_err("WorldBegin\nTransformTimes 0 1", "t.pbrt:2:1:");
    parse_err("TransformTimes 2 1\nWorldBegin", "t.pbrt:1:1: TransformTimes 2 1");
}

static void test_named_material(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin\nMakeNamedMaterial \"grey\" \"string type\" \"diffuse\" "
             "\"rgb reflectance\" [.5 .5 .5]\nMaterial \"interface\"\nShape \"sphere\"\n"
             "NamedMaterial \"grey\"\nShape \"sphere\"\n",
             &sd);
    assert_int_equal(sd.material_count, 2);
    assert_string_equal(sd.materials[0].name, "grey");
    assert_string_equal(sd.materials[0].entity.type, "diffuse");
    assert_false(params_has(&sd.materials[0].entity.params, "type"));
    assert_true(params_has(&sd.materials[0].entity.params, "reflectance"));
    assert_null(sd.materials[1].name);
    assert_int_equal(sd.shapes[0].material, 1);
    assert_int_equal(sd.shapes[1].material, 0);
    scene_desc_free(&sd);
    /* Used before its definition (pbrt-v4 resolves names after the file, and
     * pbrt-v4-scenes' contemporary-bathroom relies on it): the definition
     * fills the place the use made, with the definition's type, parameters
     * and location. */
    parse_ok("WorldBegin\nNamedMaterial \"later\"\nShape \"sphere\"\n"
             "MakeNamedMaterial \"later\" \"string type\" \"conductor\" \"float roughness\" 0.2\n"
             "NamedMaterial \"later\"\nShape \"sphere\"\n",
             &sd);
    assert_int_equal(sd.material_count, 1);
    assert_string_equal(sd.materials[0].entity.type, "conductor");
    assert_false(sd.materials[0].pending);
    assert_true(params_has(&sd.materials[0].entity.params, "roughness"));
    assert_int_equal(sd.materials[0].entity.loc.line, 4);
    assert_int_equal(sd.shapes[0].material, 0);
    assert_int_equal(sd.shapes[1].material, 0);
    scene_desc_free(&sd);
    parse_err("WorldBegin\n  NamedMaterial \"nope\"",
              "t.pbrt:2:3: NamedMaterial \"nope\": no MakeNamedMaterial defines it");
    parse_err("WorldBegin\nNamedMaterial \"a\"\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n"
              "MakeNamedMaterial \"a\" \"string type\" \"diffuse\"",
              "t.pbrt:4:1: named material \"a\" redefined (first at t.pbrt:3:1)");
    parse_err("WorldBegin\nMakeNamedMaterial \"a\" \"float x\" 1",
              "t.pbrt:2:1: MakeNamedMaterial \"a\" has no \"string type\" parameter");
    parse_err("WorldBegin\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n"
              "MakeNamedMaterial \"a\" \"string type\" \"diffuse\"",
              "t.pbrt:3:1: named material \"a\" redefined (first at t.pbrt:2:1)");
}

static void test_media(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("Translate 1 0 0\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\" "
             "\"rgb sigma_s\" [1 1 1]\nIdentity\nMediumInterface \"fog\"\nCamera \"perspective\"\n"
             "WorldBegin\nMediumInterface \"\" \"fog\"\nLightSource \"point\" \"rgb I\" [1 1 1]\n",
             &sd);
    assert_int_equal(sd.medium_count, 1);
    assert_string_equal(sd.media[0].name, "fog");
    assert_string_equal(sd.media[0].entity.type, "homogeneous");
    assert_point(&sd.media[0].world_from_medium, v3(0, 0, 0), v3(1, 0, 0));
    assert_string_equal(sd.camera.medium, "fog");
    assert_int_equal(sd.light_count, 1);
    assert_string_equal(sd.lights[0].medium, "fog");
    assert_string_equal(sd.lights[0].entity.type, "point");
    scene_desc_free(&sd);
    parse_err("MakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n"
              "MakeNamedMedium \"a\" \"string type\" \"homogeneous\"\nWorldBegin",
              "t.pbrt:2:1: named medium \"a\" redefined");
}

static void test_objects(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin\nObjectBegin \"two\"\n Translate 1 0 0\n Shape \"sphere\"\n"
             " Shape \"disk\"\nObjectEnd\nShape \"sphere\"\nTranslate 0 5 0\n"
             "ObjectInstance \"two\"\n",
             &sd);
    assert_int_equal(sd.object_count, 1);
    assert_string_equal(sd.objects[0].name, "two");
    assert_int_equal(sd.objects[0].first_shape, 0);
    assert_int_equal(sd.objects[0].shape_count, 2);
    assert_int_equal(sd.object_shape_count, 2);
    assert_string_equal(sd.object_shapes[1].entity.type, "disk");
    assert_point(&sd.object_shapes[0].world_from_object, v3(0, 0, 0), v3(1, 0, 0));
    assert_int_equal(sd.shape_count, 1);
    /* ObjectEnd restored the CTM: the top-level shape is untransformed. */
    assert_true(transform_is_identity(sd.shapes[0].world_from_object));
    assert_int_equal(sd.instance_count, 1);
    assert_int_equal(sd.instances[0].object, 0);
    assert_int_equal(sd.instances[0].loc.line, 9);
    assert_point(&sd.instances[0].world_from_instance, v3(0, 0, 0), v3(0, 5, 0));
    scene_desc_free(&sd);

    parse_err("WorldBegin\nObjectInstance \"x\"", "t.pbrt:2:1: ObjectInstance: no object named \"x\"");
    parse_err("WorldBegin\nObjectBegin \"a\"\nObjectBegin \"b\"",
              "t.pbrt:3:1: ObjectBegin inside the definition of \"a\"");
    parse_err("WorldBegin\nObjectBegin \"a\"\nObjectInstance \"a\"",
              "t.pbrt:3:1: ObjectInstance inside the definition of object \"a\"");
    parse_err("WorldBegin\nAreaLightSource \"diffuse\"\nObjectBegin \"a\"\nShape \"sphere\"",
              "t.pbrt:4:1: area lights are not supported inside ObjectBegin");
    parse_err("WorldBegin\nObjectEnd", "t.pbrt:2:1: ObjectEnd without a matching ObjectBegin");
    parse_err("WorldBegin\nObjectBegin \"a\"\nAttributeBegin\nObjectEnd",
              "t.pbrt:4:1: ObjectEnd inside the AttributeBegin at t.pbrt:3:1");
    parse_err("WorldBegin\n  ObjectBegin \"a\"\n", "t.pbrt:2:3: ObjectBegin is never closed");
}

static void test_attribute_defaults(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin\nAttributeBegin\nAttribute \"shape\" \"float radius\" 2\n"
             "Shape \"sphere\"\nShape \"sphere\" \"float radius\" 3\nAttributeEnd\nShape \"sphere\"",
             &sd);
    assert_true(params_float(&sd.shapes[0].entity.params, "radius", 1) == 2.0);
    assert_true(params_float(&sd.shapes[1].entity.params, "radius", 1) == 3.0);
    assert_false(params_has(&sd.shapes[2].entity.params, "radius"));
    scene_desc_free(&sd);
    /* A default nobody reads is not an error (pbrt-v4's mayBeUnused); a
     * parameter given on the Shape itself is. */
    parse_ok("WorldBegin\nAttribute \"shape\" \"float zz\" 2\nShape \"sphere\"\n"
             "Shape \"sphere\" \"float yy\" 1",
             &sd);
    hz_error err;
    assert_int_equal(params_finish(&sd.shapes[0].entity.params, "Shape", &err), HZ_OK);
    assert_int_equal(params_finish(&sd.shapes[1].entity.params, "Shape \"sphere\"", &err),
                     HZ_ERROR);
    assert_string_equal(err.message, "t.pbrt:4:16: unused parameter \"float yy\" for Shape \"sphere\"");
    scene_desc_free(&sd);
    parse_err("Attribute \"camera\" \"float x\" 1",
              "t.pbrt:1:1: Attribute target \"camera\" is not supported");
}

static void test_options_and_colorspace(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("Option \"bool disablepixeljitter\" true\nOption \"integer seed\" 7\n"
             "ColorSpace \"srgb\"\nWorldBegin",
             &sd);
    assert_true(params_bool(&sd.options, "disablepixeljitter", false));
    assert_int_equal(params_int(&sd.options, "seed", 0), 7);
    scene_desc_free(&sd);
    parse_err("Option \"bool nosuch\" true", "t.pbrt:1:8: unknown option \"nosuch\"");
    parse_err("Option \"float seed\" 1", "t.pbrt:1:8: option \"seed\" takes one integer value");
    parse_err("ColorSpace \"adobergb\"", "t.pbrt:1:1: unknown ColorSpace \"adobergb\"");
}

static void test_structure_errors(void **state)
{
    (void)state;
    scene_desc sd;
    parse_err("WorldBegin\n  Frobnicate 1", "t.pbrt:2:3: unknown directive 'Frobnicate'; supported: LookAt");
    parse_err("WorldBegin\nWorldEnd", "t.pbrt:2:1: WorldEnd does not exist in pbrt-v4");
    parse_err("WorldBegin\nCamera \"perspective\"", "t.pbrt:2:1: Camera must come before WorldBegin");
    /* pbrt-v4 takes the last of two option directives: so does haze, with a
     * warning. */
    parse_ok("Film \"rgb\" \"integer xresolution\" 8\n Film \"rgb\" \"integer xresolution\" 4\n"
             "WorldBegin\n", &sd);
    assert_true(params_int(&sd.film.params, "xresolution", 0) == 4);
    assert_int_equal(sd.warning_count, 1);
    assert_non_null(strstr(sd.warnings[0], "t.pbrt:2:2: warning: Film given again: this one "
                                           "replaces the one at t.pbrt:1:1"));
    scene_desc_free(&sd);
    parse_err("Shape \"sphere\"", "t.pbrt:1:1: Shape is only allowed after WorldBegin");
    parse_err("Material \"diffuse\"", "t.pbrt:1:1: Material is only allowed after WorldBegin");
    parse_err("LightSource \"point\"", "t.pbrt:1:1: LightSource is only allowed after WorldBegin");
    parse_err("WorldBegin\nAttributeEnd", "t.pbrt:2:1: AttributeEnd without a matching AttributeBegin");
    parse_err("WorldBegin\nAttributeBegin\n  AttributeBegin\nAttributeEnd\n",
              "t.pbrt:2:1: AttributeBegin is never closed");
    parse_err("Camera \"perspective\"\n", "t.pbrt:2:1: end of input before WorldBegin");
    parse_err("", "t.pbrt:1:1: end of input before WorldBegin");
    parse_err("WorldBegin WorldBegin", "t.pbrt:1:12: WorldBegin must come before WorldBegin");
    parse_err("\"Shape\"", "t.pbrt:1:1: expected a directive, found \"Shape\"");
    parse_err("Translate 1 2", "t.pbrt:1:14: Translate expects 3 numbers, found end of file after 2");
}

static void test_transform_errors(void **state)
{
    (void)state;
    parse_err("Transform [1 0 0 0 0 1 0 0 0 0 0 0 0 0 0 1]", "t.pbrt:1:1: Transform matrix is singular");
    parse_err("Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0]\nWorldBegin",
              "t.pbrt:1:41: Transform expects 16 numbers, found ']' after 15");
    parse_err("Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 1]",
              "t.pbrt:1:11: Transform: '[' is not closed after 16 numbers");
    parse_err("Translate 1 \"2\" 3", "t.pbrt:1:13: Translate expects 3 numbers, found \"2\" after 1");
    parse_err("Scale 1 0 1", "t.pbrt:1:1: Scale by zero");
    parse_err("Rotate 30 0 0 0", "t.pbrt:1:1: Rotate axis is zero");
    parse_err("LookAt 0 0 0  0 0 0  0 1 0", "t.pbrt:1:1: LookAt is degenerate");
    parse_err("LookAt 0 0 0  0 1 0  0 1 0", "t.pbrt:1:1: LookAt is degenerate");
}

static void test_param_errors(void **state)
{
    (void)state;
    parse_err("Camera \"perspective\" \"float fov\" \"abc\"",
              "t.pbrt:1:34: parameter \"float fov\" expects numbers, got string \"abc\"");
    parse_err("WorldBegin\nLightSource \"point\" \"rgb I\" [1 1]",
              "t.pbrt:2:21: parameter \"rgb I\" needs a multiple of 3 values, got 2");
    parse_err("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1]",
              "t.pbrt:2:22: parameter \"point3 P\" needs a multiple of 3 values, got 4");
    /* Given again with another type: ambiguous, refused. */
    parse_err("Camera \"perspective\" \"float fov\" 30\n   \"integer fov\" 40",
              "t.pbrt:2:4: parameter \"fov\" given twice (first at line 1)");
    parse_err("Camera \"perspective\" \"quaternion q\" 1",
              "t.pbrt:1:22: unknown parameter type \"quaternion\"");
    parse_err("Camera \"perspective\" \"fov\" 1",
              "t.pbrt:1:22: parameter declaration \"fov\" must be \"type name\"");
    parse_err("Camera \"perspective\" \"float fov\" [ 1 2\nWorldBegin",
              "t.pbrt:1:34: '[' is not closed (found 'WorldBegin' at line 2, column 1)");
    parse_err("Camera \"perspective\" \"float fov\" [ 1 2", "t.pbrt:1:34: '[' is not closed (found end of file");
    parse_err("Camera \"perspective\" \"float fov\"\nWorldBegin",
              "t.pbrt:1:22: parameter \"float fov\" has no value (found 'WorldBegin')");
    parse_err("Camera \"perspective\" \"integer n\" 1.5", "t.pbrt:1:34: parameter \"integer n\" expects integers");
    /* Found by fuzz_scene: integers far outside long long's range (and beyond
     * int's) are rejected without an undefined double-to-integer conversion. */
    parse_err("Camera \"perspective\" \"integer n\" [0 -6222222222222222222222222222]",
              "t.pbrt:1:37: parameter \"integer n\" expects integers, got -6222222222222222222222222222");
    parse_err("Camera \"perspective\" \"integer n\" 1e300", "t.pbrt:1:34: parameter \"integer n\" expects integers");
    parse_err("Camera \"perspective\" \"integer n\" 2147483648", "t.pbrt:1:34: parameter \"integer n\" expects integers");
    parse_err("Camera \"perspective\" \"bool b\" 1", "t.pbrt:1:31: parameter \"bool b\" expects true or false");
    parse_err("Camera \"perspective\" \"float f\" []", "t.pbrt:1:22: parameter \"float f\" has no values");
    parse_err("WorldBegin\nMaterial \"diffuse\" \"spectrum reflectance\" \"my.spd\"",
              "t.pbrt:2:43: parameter \"spectrum reflectance\": no named spectrum \"my.spd\"");
    parse_err("WorldBegin\nMaterial \"conductor\" \"spectrum eta\" [\"metal-Cu-eta\" \"x\"]",
              "takes one spectrum name, got 2 values");
    parse_err("WorldBegin\nMaterial \"diffuse\" \"spectrum r\" [400 1 500]",
              "needs (wavelength, value) pairs, got 3 values");
    parse_err("WorldBegin\nMaterial \"diffuse\" \"spectrum r\" [500 1 400 1]",
              "t.pbrt:2:40: parameter \"spectrum r\": wavelengths must increase");
    parse_err("WorldBegin\nLightSource \"point\" \"blackbody I\" [0]", "temperature must be > 0");
    parse_err("WorldBegin\nLightSource \"point\" \"blackbody I\" [5000 1]",
              "t.pbrt:2:21: parameter \"blackbody I\" takes 1 value (kelvin), got 2");
    parse_err("WorldBegin\nMaterial \"diffuse\" \"texture reflectance\" 0.5",
              "t.pbrt:2:42: parameter \"texture reflectance\" expects strings");
    parse_err("WorldBegin\nTexture \"t\" \"color\" \"constant\"",
              "t.pbrt:2:1: Texture \"t\": type \"color\" must be \"float\" or \"spectrum\"");
    parse_err("WorldBegin\nTexture \"t\" \"float\" \"constant\"\n"
              "Texture \"t\" \"float\" \"constant\"",
              "t.pbrt:3:1: Texture \"t\" redefined (first at t.pbrt:2:1)");
}

static void test_param_values(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("Camera \"perspective\" \"bool a\" true \"bool b\" \"false\" \"point p\" [1 2 3]\n"
             "\"color c\" [.1 .2 .3] \"normal n\" [0 0 1] \"string s\" \"x\\\"y\" \"vector2 v\" [1 2]\n"
             "WorldBegin",
             &sd);
    param_list *pl = &sd.camera.entity.params;
    assert_true(params_bool(pl, "a", false));
    assert_false(params_bool(pl, "b", true));
    vec3 p = params_point3(pl, "p", v3(0, 0, 0));
    assert_true(p.x == 1 && p.y == 2 && p.z == 3);
    rgb c = params_rgb(pl, "c", rgb_grey(0));
    assert_true(c.r == 0.1 && c.b == 0.3);
    size_t n;
    assert_non_null(params_normals(pl, "n", &n));
    assert_int_equal(n, 1);
    assert_string_equal(params_string(pl, "s", ""), "x\"y");
    assert_int_equal(pl->items[6].type, PARAM_VECTOR2);
    assert_int_equal(pl->items[0].loc.column, 22);
    hz_error err;
    pl->items[6].used = true;
    assert_int_equal(params_finish(pl, "Camera \"perspective\"", &err), HZ_OK);
    scene_desc_free(&sd);
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* The folder HAZE_TMP/name in dir[size], made. */
static void test_dir(char *dir, size_t size, const char *name)
{
    snprintf(dir, size, "%s/%s", HAZE_TMP, name);
    mkdir(dir, 0755);
}

static void test_include(void **state)
{
    (void)state;
    char dir[512], sub[600], path[700];
    test_dir(dir, sizeof dir, "scene_include");
    snprintf(sub, sizeof sub, "%s/sub", dir);
    mkdir(sub, 0755);
    snprintf(path, sizeof path, "%s/main.pbrt", dir);
    write_file(path, "WorldBegin\nInclude \"sub/a.pbrt\"\nShape \"disk\"\n");
    snprintf(path, sizeof path, "%s/sub/a.pbrt", dir);
    /* Names resolve from the top-level scene file's directory, as pbrt-v4. */
    write_file(path, "# a\nImport \"sub/b.pbrt\"\n");
    snprintf(path, sizeof path, "%s/sub/b.pbrt", dir);
    write_file(path, "\n  Shape \"sphere\"\n");
    snprintf(path, sizeof path, "%s/main.pbrt", dir);
    scene_desc sd;
    hz_error err;
    if (scene_parse_file(path, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(sd.shape_count, 2);
    assert_non_null(strstr(sd.shapes[0].entity.loc.file, "sub/b.pbrt"));
    assert_int_equal(sd.shapes[0].entity.loc.line, 2);
    assert_int_equal(sd.shapes[0].entity.loc.column, 3);
    assert_string_equal(sd.shapes[1].entity.loc.file, path);
    /* Every file read, in the order opened: the scene, then its includes. */
    assert_int_equal(sd.file_count, 3);
    assert_string_equal(sd.files[0], path);
    assert_string_equal(sd.files[1], strcat(strcpy((char[800]){0}, dir), "/sub/a.pbrt"));
    assert_string_equal(sd.files[2], strcat(strcpy((char[800]){0}, dir), "/sub/b.pbrt"));
    scene_desc_free(&sd);

    /* A cycle through two files, reported at the Include that closes it. */
    snprintf(path, sizeof path, "%s/sub/b.pbrt", dir);
    write_file(path, "Include \"sub/a.pbrt\"\n");
    snprintf(path, sizeof path, "%s/main.pbrt", dir);
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "sub/b.pbrt:1:1: Include cycle: a.pbrt -> b.pbrt -> a.pbrt"));

    /* Missing file: the error names the Include. */
    write_file(path, "WorldBegin\n\n   Include \"nothere.pbrt\"\n");
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "main.pbrt:3:4: Include: cannot open"));
    assert_non_null(strstr(err.message, "nothere.pbrt"));

    /* Self-include. */
    write_file(path, "Include \"main.pbrt\"\n");
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "main.pbrt:1:1: Include cycle: main.pbrt -> main.pbrt"));

    assert_int_equal(scene_parse_file("/nonexistent/x.pbrt", &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "/nonexistent/x.pbrt: cannot read scene"));
}

/* Every error of a scene in one run, in file order (the scene, then its
 * includes in the order opened; line, column), at most HZ_ERRORS_MAX. */
static void test_all_errors_in_one_run(void **state)
{
    (void)state;
    char dir[512], path[700];
    test_dir(dir, sizeof dir, "scene_errors");
    snprintf(path, sizeof path, "%s/inc.pbrt", dir);
    write_file(path, "Shape \"sphere\" \"float radius\" true\n");
    snprintf(path, sizeof path, "%s/main.pbrt", dir);
    write_file(path, "Frobnicate 1 2 [ 3 ] \"x\" true\nWorldBegin\nInclude \"inc.pbrt\"\n"
                     "AttributeEnd\nShape \"sphere\" \"float\" 1\nShape \"disk\"\n");
    scene_desc sd;
    hz_error err;
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    char want[2048];
    snprintf(want, sizeof want,
             "%s/main.pbrt:1:1: unknown directive 'Frobnicate'; supported: ", dir);
    assert_memory_equal(err.message, want, strlen(want));
    const char *l2 = strchr(err.message, '\n');
    assert_non_null(l2);
    snprintf(want, sizeof want,
             "\n%s/main.pbrt:4:1: AttributeEnd without a matching AttributeBegin\n"
             "%s/main.pbrt:5:16: parameter declaration \"float\" must be \"type name\"\n"
             "%s/inc.pbrt:1:31: parameter \"float radius\" expects numbers, got bool 'true'",
             dir, dir, dir);
    assert_string_equal(l2, want);

    /* 30 errors: the first 20 (in order) and a count of the rest. */
    char text[2048] = "WorldBegin\n";
    for (int i = 0; i < 30; ++i)
        strcat(text, "AttributeEnd\n");
    assert_int_equal(scene_parse_string(text, "t.pbrt", &sd, &err), HZ_ERROR);
    int lines = 1;
    for (const char *c = err.message; *c; ++c)
        lines += *c == '\n';
    assert_int_equal(lines, 21);
    assert_non_null(strstr(err.message, "t.pbrt:21:1: AttributeEnd"));
    assert_null(strstr(err.message, "t.pbrt:22:1"));
    assert_non_null(strstr(err.message, "\n... and 10 more errors"));

    /* Errors too long to fit the report together: whole lines, then the
     * count of the rest (nothing cut mid-line). */
    strcpy(text, "WorldBegin\n");
    for (int i = 0; i < 12; ++i)
        strcat(text, "Frobnicate\n");
    assert_int_equal(scene_parse_string(text, "t.pbrt", &sd, &err), HZ_ERROR);
    const char *tail = strstr(err.message, "\n... and ");
    assert_non_null(tail);
    int kept = 0, more = 0;
    for (const char *c = err.message; c < tail; ++c)
        kept += *c == '\n';
    kept += 1;
    assert_int_equal(sscanf(tail, "\n... and %d more errors", &more), 1);
    assert_int_equal(kept + more, 12);
    assert_true(kept >= 2);
    for (const char *c = err.message; c && c < tail; c = strchr(c + 1, '\n'))
        assert_non_null(strstr(c, "supported: "));
    assert_memory_equal(tail - 10, "ColorSpace", 10);
}

/* pbrt-v4 reads one token stream: the end of an included file continues the
 * includer's, so a directive that ends an included file takes the parameters
 * (even the rest of a bracket) after the Include. */
static void test_include_continues_stream(void **state)
{
    (void)state;
    char dir[512], path[700];
    test_dir(dir, sizeof dir, "scene_include_stream");
    snprintf(path, sizeof path, "%s/mat.pbrt", dir);
    write_file(path, "Material \"diffuse\"\n");
    snprintf(path, sizeof path, "%s/shape.pbrt", dir);
    write_file(path, "Shape \"sphere\" \"float radius\" [\n");
    snprintf(path, sizeof path, "%s/main.pbrt", dir);
    write_file(path, "WorldBegin\nInclude \"mat.pbrt\"\n  \"rgb reflectance\" [0.1 0.2 0.3]\n"
                     "Include \"shape.pbrt\" 2.5 ]\nShape \"disk\"\n");
    scene_desc sd;
    hz_error err;
    if (scene_parse_file(path, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(sd.material_count, 1);
    param_list *pl = &sd.materials[0].entity.params;
    assert_true(params_has(pl, "reflectance"));
    assert_int_equal(sd.shape_count, 2);
    assert_true(params_float(&sd.shapes[0].entity.params, "radius", 0.0) == 2.5);
    assert_non_null(strstr(sd.shapes[0].entity.loc.file, "shape.pbrt"));
    assert_string_equal(sd.shapes[1].entity.loc.file, path);
    scene_desc_free(&sd);

    /* Includes one after another do not nest: 100 of them (deeper than the
     * nesting limit) in a row are fine. */
    char *text = malloc(100 * 32 + 64);
    assert_non_null(text);
    strcpy(text, "WorldBegin\n");
    for (int i = 0; i < 100; ++i)
        strcat(text, "Include \"mat.pbrt\"\n");
    write_file(path, text);
    free(text);
    if (scene_parse_file(path, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(sd.material_count, 100);
    scene_desc_free(&sd);
}

static void write_bytes(const char *path, const char *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, n, f), n);
    fclose(f);
}

/* What haze reads as scene input: regular files only (never blocking on a
 * FIFO or growing without bound on a device), gzip-compressed files, a UTF-8
 * byte order mark; a NUL inside a string is refused. */
static void test_input_files(void **state)
{
    (void)state;
    char dir[512], path[700], fifo[700];
    test_dir(dir, sizeof dir, "scene_input_files");
    scene_desc sd;
    hz_error err;

    /* Devices and FIFOs, as the scene and as an Include. */
    assert_int_equal(scene_parse_file("/dev/zero", &sd, &err), HZ_ERROR);
    assert_string_equal(err.message,
                        "/dev/zero: cannot read scene: is a device; haze reads only regular files");
    snprintf(path, sizeof path, "%s/main.pbrt", dir);
    write_file(path, "WorldBegin\nInclude \"/dev/urandom\"\n");
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "main.pbrt:2:1: Include: cannot read \"/dev/urandom\": is "
                                        "a device; haze reads only regular files"));
    snprintf(fifo, sizeof fifo, "%s/pipe", dir);
    unlink(fifo);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    write_file(path, "WorldBegin\nInclude \"pipe\"\n");
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "is a FIFO; haze reads only regular files"));
    snprintf(path, sizeof path, "%s", dir);
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "is a directory"));

    /* gzip: the scene itself and an Include. */
    const char *text = "WorldBegin\nShape \"sphere\" \"float radius\" 2\n";
    snprintf(path, sizeof path, "%s/sub.pbrt.gz", dir);
    gzFile gz = gzopen(path, "wb");
    assert_non_null(gz);
    assert_int_equal(gzwrite(gz, text, (unsigned)strlen(text)), (int)strlen(text));
    gzclose(gz);
    if (scene_parse_file(path, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(sd.shape_count, 1);
    assert_int_equal(sd.shapes[0].entity.loc.line, 2);
    scene_desc_free(&sd);
    snprintf(path, sizeof path, "%s/main.pbrt", dir);
    write_file(path, "Include \"sub.pbrt.gz\"\nShape \"disk\"\n");
    if (scene_parse_file(path, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(sd.shape_count, 2);
    scene_desc_free(&sd);
    snprintf(path, sizeof path, "%s/bad.pbrt.gz", dir);
    write_bytes(path, "\x1f\x8b\x08\x00garbage-garbage", 19);
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "bad.pbrt.gz: cannot read scene: "));

    /* A UTF-8 byte order mark is skipped; places count from after it. */
    snprintf(path, sizeof path, "%s/bom.pbrt", dir);
    write_bytes(path, "\xEF\xBB\xBFWorldBegin\nShape \"sphere\"\n", 29);
    if (scene_parse_file(path, &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    assert_int_equal(sd.shapes[0].entity.loc.line, 2);
    scene_desc_free(&sd);

    /* A NUL inside a string would cut the name short: refused at its place. */
    snprintf(path, sizeof path, "%s/nul.pbrt", dir);
    write_bytes(path, "WorldBegin\nShape \"sph\0ere\"\n", 27);
    assert_int_equal(scene_parse_file(path, &sd, &err), HZ_ERROR);
    assert_non_null(strstr(err.message, "nul.pbrt:2:11: NUL byte inside a string"));
}

/* HAZE_CACHE_DIR set to `dir` ("": no cache; NULL: unset); gives back what
 * it was (free it). */
static char *swap_cache_dir(const char *dir)
{
    const char *was = getenv("HAZE_CACHE_DIR");
    char *old = was ? strdup(was) : NULL;
    if (dir)
        setenv("HAZE_CACHE_DIR", dir, 1);
    else
        unsetenv("HAZE_CACHE_DIR");
    return old;
}

/* The cache folder `parent`/cache for a test; gives back what it was. */
static char *cache_in(const char *parent)
{
    char cache[600];
    snprintf(cache, sizeof cache, "%s/cache", parent);
    return swap_cache_dir(cache);
}

/* Waits until the file at `path`, written now, has settled for the digest
 * cache. Times that fall on a whole second read as a file system of whole
 * seconds, which the cache waits longer for: the rare file stamped so gets
 * its times again. */
static void settle(const char *path)
{
    struct stat st;
    for (int tries = 0; stat(path, &st) == 0 && st.st_ctim.tv_nsec == 0 &&
                        st.st_mtim.tv_nsec == 0 && tries < 10;
         ++tries) {
        struct timespec t = {0, 5000000L};
        nanosleep(&t, NULL);
        assert_int_equal(utimensat(AT_FDCWD, path, NULL, 0), 0); /* now, both times */
    }
    struct timespec t = {0, 2 * DIGEST_CACHE_SETTLE_MS * 1000000L};
    nanosleep(&t, NULL);
}

/* scene_inputs_hash: the scene and the files it names. Up to 16 MiB a file
 * counts byte by byte (FNV-1a: the render ids of every scene before large
 * volumes did not change); a larger one by its digest: the hash_block of
 * each 4 MiB window (seeded with its number), folded in order with FNV-1a.
 * Either way every byte counts. A large file's digest is kept in the digest
 * cache once the file has settled, and read back while it is unchanged. */
static void test_inputs_hash(void **state)
{
    (void)state;
    char dir[512], scene[700], vol[700];
    test_dir(dir, sizeof dir, "scene_inputs_hash");
    char *was = cache_in(dir);
    snprintf(scene, sizeof scene, "%s/s.pbrt", dir);
    snprintf(vol, sizeof vol, "%s/v.nvdb", dir);
    const char *text = "WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"nanovdb\" "
                       "\"string filename\" \"v.nvdb\"\n";
    write_file(scene, text);
    for (int large = 0; large < 2; ++large) {
        const size_t n = large ? ((size_t)16 << 20) + 4097 : (size_t)3 << 20;
        char *bytes = malloc(n);
        assert_non_null(bytes);
        for (size_t i = 0; i < n; ++i)
            bytes[i] = (char)(i * 2654435761u >> 13);
        write_bytes(vol, bytes, n);
        scene_desc sd;
        hz_error err;
        uint64_t h0, h1, h2;
        if (scene_parse_file(scene, &sd, &err) != HZ_OK)
            fail_msg("%s", err.message);
        assert_int_equal(scene_inputs_hash(&sd, &h0, &err), HZ_OK);
        { /* FNV-1a of the count, then of each file's size and its 1 MiB blocks'
           * (small: hash and length) or 4 MiB windows' (large: digest) values */
            uint64_t want = HZ_FNV_OFFSET;
            size_t count = 2;
            off_t scene_size = (off_t)strlen(text), vol_size = (off_t)n;
            HASH_FIELD(want, count);
            HASH_FIELD(want, scene_size);
            uint64_t tv = hash_block(0, text, strlen(text));
            ssize_t tn = (ssize_t)strlen(text);
            HASH_FIELD(want, tv);
            HASH_FIELD(want, tn);
            HASH_FIELD(want, vol_size);
            const size_t window = (size_t)4 << 20;
            uint64_t digest = HZ_FNV_OFFSET;
            for (size_t w = 0; large && w * window < n; ++w) { /* 4 whole, 4097 bytes */
                uint64_t v = hash_block(w, bytes + w * window, n - w * window < window ? n - w * window : window);
                HASH_FIELD(digest, v);
            }
            const size_t block = (size_t)1 << 20;
            for (size_t b = 0; !large && b * block < n; ++b) { /* 3 whole blocks */
                ssize_t bn = (ssize_t)(n - b * block < block ? n - b * block : block);
                uint64_t v = hash_block(b, bytes + b * block, (size_t)bn);
                HASH_FIELD(want, v);
                HASH_FIELD(want, bn);
            }
            if (large)
                HASH_FIELD(want, digest);
            assert_true(h0 == want);
        }
        bytes[n - 1] ^= 1; /* the last byte, past the last whole block */
        write_bytes(vol, bytes, n);
        assert_int_equal(scene_inputs_hash(&sd, &h1, &err), HZ_OK);
        bytes[n - 1] ^= 1;
        bytes[n / 2] ^= 0x40;
        write_bytes(vol, bytes, n);
        assert_int_equal(scene_inputs_hash(&sd, &h2, &err), HZ_OK);
        assert_true(h1 != h0 && h2 != h0 && h2 != h1);
        bytes[n / 2] ^= 0x40;
        write_bytes(vol, bytes, n);
        assert_int_equal(scene_inputs_hash(&sd, &h1, &err), HZ_OK);
        assert_true(h1 == h0);
        if (large) { /* settled: kept, then read back; a rewrite misses it */
            settle(vol);
            assert_int_equal(scene_inputs_hash(&sd, &h1, &err), HZ_OK);
            assert_true(h1 == h0);
            int fd = open(vol, O_RDONLY);
            file_identity id;
            file_digest d;
            assert_true(fd >= 0 && file_identity_of(fd, &id));
            close(fd);
            assert_true(digest_cache_get("inputs-xxh3-4m", &id, &d));
            d.v[0] ^= 1; /* a kept digest is what the hash takes (h0 must differ) */
            digest_cache_put("inputs-xxh3-4m", &id, &d);
            assert_int_equal(scene_inputs_hash(&sd, &h1, &err), HZ_OK);
            assert_true(h1 != h0);
            bytes[n / 2] ^= 0x40; /* rewritten: its times move, the entry no longer counts */
            write_bytes(vol, bytes, n);
            assert_int_equal(scene_inputs_hash(&sd, &h1, &err), HZ_OK);
            assert_true(h1 == h2);
            bytes[n / 2] ^= 0x40;
        }
        scene_desc_free(&sd);
        free(bytes);
    }
    free(swap_cache_dir(was));
    free(was);
    remove(vol);
    remove(scene);
}

/* The digest cache (core/digest_cache.h): an entry counts for its kind and
 * while the file's identity (device, inode, size, times) is unchanged; a
 * file changed just before its reading is not kept; no folder, no cache. */
static void test_digest_cache(void **state)
{
    (void)state;
    char dir[512], file[700];
    test_dir(dir, sizeof dir, "digest_cache");
    snprintf(file, sizeof file, "%s/f.bin", dir);
    char *was = cache_in(dir);
    write_bytes(file, "0123456789", 10);
    file_identity fresh, settled, id;
    int fd = open(file, O_RDONLY);
    assert_true(fd >= 0 && file_identity_of(fd, &fresh));
    const file_digest d = {{0x1234, 0xabcd}};
    file_digest got;
    digest_cache_put("k1", &fresh, &d); /* just written: not kept */
    assert_false(digest_cache_get("k1", &fresh, &got));
    settle(file);
    assert_true(file_identity_of(fd, &settled));
    close(fd);
    digest_cache_put("k1", &settled, &d);
    assert_true(digest_cache_get("k1", &settled, &got));
    assert_true(got.v[0] == 0x1234 && got.v[1] == 0xabcd);
    assert_false(digest_cache_get("k2", &settled, &got)); /* another kind */
    assert_false(digest_cache_get("K/..", &settled, &got)); /* not a kind */
    id = settled;
    id.size++;
    assert_false(digest_cache_get("k1", &id, &got));
    id = settled;
    id.ctime_ns ^= 1;
    assert_false(digest_cache_get("k1", &id, &got));
    write_bytes(file, "9876543210", 10); /* same size, new times */
    fd = open(file, O_RDONLY);
    assert_true(fd >= 0 && file_identity_of(fd, &id));
    close(fd);
    assert_false(digest_cache_get("k1", &id, &got));
    free(swap_cache_dir("")); /* empty: no cache */
    assert_false(digest_cache_get("k1", &settled, &got));
    free(swap_cache_dir(was));
    free(was);
    remove(file);
}

/* Garbage must give an error or a scene, never a crash, hang or leak (run
 * under ASan): random bytes, and random mutations of a valid scene. */
static void test_garbage(void **state)
{
    (void)state;
    const char *valid =
        "LookAt 0 0 -5 0 0 0 0 1 0\nCamera \"perspective\" \"float fov\" [45]\n"
        "MakeNamedMedium \"f\" \"string type\" \"homogeneous\"\nWorldBegin\n"
        "AttributeBegin\nMaterial \"diffuse\" \"spectrum reflectance\" [400 .5 700 .5]\n"
        "AreaLightSource \"diffuse\" \"blackbody L\" 5500\nShape \"trianglemesh\" "
        "\"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nAttributeEnd\n"
        "ObjectBegin \"o\" Shape \"sphere\" ObjectEnd ObjectInstance \"o\"\n";
    size_t n = strlen(valid);
    char buf[1024];
    uint32_t rng = 12345;
    const char alphabet[] = "[]\"#\\ \n0123456789.-eAWSLMOabc";
    for (int iter = 0; iter < 3000; ++iter) {
        memcpy(buf, valid, n + 1);
        int edits = 1 + iter % 8;
        for (int e = 0; e < edits; ++e) {
            rng = rng * 1664525u + 1013904223u;
            size_t at = (rng >> 8) % n;
            rng = rng * 1664525u + 1013904223u;
            if (iter % 3 == 0)
                buf[at] = (char)(1 + (rng >> 8) % 255);
            else if (iter % 3 == 1)
                buf[at] = alphabet[(rng >> 8) % (sizeof alphabet - 1)];
            else
                buf[at] = '\0'; /* truncation */
        }
        scene_desc sd;
        hz_error err;
        if (scene_parse_string(buf, "g.pbrt", &sd, &err) == HZ_OK)
            scene_desc_free(&sd);
        else
            assert_true(strlen(err.message) > 0);
    }
}

/* pbrt-v4's named spectra come back as their RGB reductions: an illuminant
 * at luminance 1 (stdillum-A, warm), a metal's index, a glass's index. */
static void named_spectra(void **state)
{
    (void)state;
    scene_desc sd;
    parse_ok("WorldBegin\nLightSource \"point\" \"spectrum I\" \"stdillum-A\"\n"
             "Material \"conductor\" \"spectrum eta\" \"metal-Ag-eta\" \"spectrum k\" "
             "\"metal-Ag-k\"\n"
             "Material \"dielectric\" \"spectrum eta\" \"glass-F11\"\n",
             &sd);
    rgb a = params_illuminant(&sd.lights[0].entity.params, "I", rgb_grey(0.0));
    assert_true(fabs(a.r - 1.84470) < 1e-5 && fabs(a.g - 0.82622) < 1e-5 &&
                fabs(a.b - 0.23290) < 1e-5);
    assert_true(fabs(rgb_luminance(a) - 1.0) < 2e-3);
    rgb k = params_rgb(&sd.materials[0].entity.params, "k", rgb_grey(0.0));
    assert_true(fabs(k.g - 3.36834) < 1e-5);
    rgb g = params_rgb(&sd.materials[1].entity.params, "eta", rgb_grey(0.0));
    assert_true(g.r == g.g && g.g == g.b && fabs(g.g - 1.79112) < 1e-5);
    scene_desc_free(&sd);
    /* A dispersive index is taken at 550 nm, linear between samples. */
    parse_ok("WorldBegin\nMaterial \"dielectric\" \"spectrum eta\" [400 1.6 500 1.55 700 1.45]\n",
             &sd);
    assert_true(fabs(params_float_or_550(&sd.materials[0].entity.params, "eta", 0.0) - 1.525) <
                1e-12);
    scene_desc_free(&sd);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(named_spectra),
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_input_files),
        cmocka_unit_test(test_inputs_hash),
        cmocka_unit_test(test_digest_cache),
        cmocka_unit_test(test_look_at),
        cmocka_unit_test(test_transform_is_transposed),
        cmocka_unit_test(test_composition_order),
        cmocka_unit_test(test_attribute_restore),
        cmocka_unit_test(test_default_material),
        cmocka_unit_test(test_coordsys),
        cmocka_unit_test(test_active_transform),
        cmocka_unit_test(test_active_transform_pbrt_rules),
        cmocka_unit_test(test_named_material),
        cmocka_unit_test(test_pbrt_v4_leniencies),
        cmocka_unit_test(test_media),
        cmocka_unit_test(test_objects),
        cmocka_unit_test(test_attribute_defaults),
        cmocka_unit_test(test_options_and_colorspace),
        cmocka_unit_test(test_structure_errors),
        cmocka_unit_test(test_transform_errors),
        cmocka_unit_test(test_param_errors),
        cmocka_unit_test(test_param_values),
        cmocka_unit_test(test_include),
        cmocka_unit_test(test_include_continues_stream),
        cmocka_unit_test(test_all_errors_in_one_run),
        cmocka_unit_test(test_garbage),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
