/* media/medium: MakeNamedMedium entities become media (parameters, defaults,
 * errors, file resolution, grid placement), medium_clip bounds rays to a
 * grid's support box, and moving grids (animated transforms, velocity grids)
 * place each ray at its time. Scenes are parsed from strings; the grids are the
 * generated volumes (volumes/generate.cpp). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "media/grid_medium.h"
#include "media/medium.h"
#include "media/presets.h"
#include "scene/scene_desc.h"
#include "unit/assert_util.h"

#define VOLUMES HAZE_SCENES "/../volumes/"

/* Parses `src` (named `name`), which must declare exactly one medium, and builds
 * it with render_from_world. Returns the status; on success the caller frees
 * both *m and *sd. On failure *sd is already freed and err holds the message. */
static hz_status build_named(const char *src, const char *name, transform render_from_world,
                             scene_desc *sd, medium *m, hz_error *err)
{
    hz_error perr;
    if (scene_parse_string(src, name, sd, &perr) != HZ_OK)
        fail_msg("parse error: %s", perr.message);
    assert_int_equal(sd->medium_count, 1);
    medium_times times = {sd->transform_start_time, sd->transform_end_time,
                          sd->transform_start_time, sd->transform_end_time};
    hz_status st = medium_create(&sd->media[0], render_from_world, &times, NULL, m, err);
    if (st != HZ_OK) {
        /* A failed build leaves a medium that medium_destroy accepts. */
        medium_destroy(m);
        scene_desc_free(sd);
    }
    return st;
}

/* The density at o + t d of a grid ray made by grid_medium_ray_make. */
static double density_at(const medium *m, medium_ray *r, double t, uint64_t *lookups)
{
    r->m = m;
    grid_medium_accessors_init(m, r);
    return grid_medium_density(r, t, lookups);
}

static void build_ok_at(const char *src, const char *name, transform render_from_world,
                        scene_desc *sd, medium *m)
{
    hz_error err;
    if (build_named(src, name, render_from_world, sd, m, &err) != HZ_OK)
        fail_msg("unexpected error: %s", err.message);
}

static void build_ok(const char *src, scene_desc *sd, medium *m)
{
    build_ok_at(src, "t.pbrt", transform_identity(), sd, m);
}

static void build_err_at(const char *src, const char *name, const char *want1, const char *want2)
{
    scene_desc sd;
    medium m;
    hz_error err;
    if (build_named(src, name, transform_identity(), &sd, &m, &err) == HZ_OK) {
        medium_destroy(&m);
        scene_desc_free(&sd);
        fail_msg("expected an error containing \"%s\"", want1);
    }
    if (!strstr(err.message, want1) || (want2 && !strstr(err.message, want2)))
        fail_msg("got \"%s\", want \"%s\"%s%s", err.message, want1, want2 ? " and " : "",
                 want2 ? want2 : "");
    if (strchr(err.message, '\n'))
        fail_msg("message spans lines: \"%s\"", err.message);
}

static void build_err(const char *src, const char *want1, const char *want2)
{
    build_err_at(src, "t.pbrt", want1, want2);
}

static void free_all(scene_desc *sd, medium *m)
{
    medium_destroy(m);
    scene_desc_free(sd);
}

static void assert_rgb_near(rgb got, rgb want, double tol)
{
    assert_near(got.r, want.r, tol);
    assert_near(got.g, want.g, tol);
    assert_near(got.b, want.b, tol);
}

/* A one-medium scene with the given medium parameters, after WorldBegin. */
static const char *homog(const char *params)
{
    static char buf[1024];
    snprintf(buf, sizeof buf,
             "WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\" %s\n", params);
    return buf;
}

/* ---- homogeneous ---- */

static void homogeneous_defaults(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(homog(""), &sd, &m);
    assert_true(medium_is_homogeneous(&m));
    assert_ptr_equal(m.name, sd.media[0].name);
    assert_string_equal(m.name, "fog");
    assert_rgb_near(m.sigma_a, rgb_grey(1.0), 0);
    assert_rgb_near(m.sigma_s, rgb_grey(1.0), 0);
    assert_rgb_near(medium_sigma_t(&m), rgb_grey(2.0), 0);
    assert_near(m.g, 0.0, 0);
    free_all(&sd, &m);
}

static void homogeneous_parameters(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(homog("\"rgb sigma_a\" [0.1 0.2 0.3] \"rgb sigma_s\" [1 2 3] \"float scale\" 2 "
                   "\"float g\" -0.5"),
             &sd, &m);
    assert_rgb_near(m.sigma_a, rgb_make(0.2, 0.4, 0.6), 1e-15);
    assert_rgb_near(m.sigma_s, rgb_make(2, 4, 6), 1e-15);
    assert_rgb_near(medium_sigma_t(&m), rgb_make(2.2, 4.4, 6.6), 1e-14);
    assert_near(m.g, -0.5, 0);
    free_all(&sd, &m);

    /* Spectra: a constant spectrum is that grey; zero coefficients and scale are fine. */
    build_ok(homog("\"spectrum sigma_s\" 0.7 \"rgb sigma_a\" [0 0 0] \"float scale\" 3"), &sd,
             &m);
    assert_rgb_near(m.sigma_s, rgb_grey(2.1), 1e-12);
    assert_rgb_near(m.sigma_a, rgb_grey(0.0), 0);
    free_all(&sd, &m);
    build_ok(homog("\"float scale\" 0 \"float g\" 0.999"), &sd, &m);
    assert_rgb_near(medium_sigma_t(&m), rgb_grey(0.0), 0);
    assert_near(m.g, 0.999, 0);
    free_all(&sd, &m);

    /* Zero emission is accepted, as is a scale on it. */
    build_ok(homog("\"rgb Le\" [0 0 0] \"float Lescale\" 4"), &sd, &m);
    free_all(&sd, &m);
    build_ok(homog("\"float Lescale\" 4"), &sd, &m);
    free_all(&sd, &m);
}

/* The transform does not matter to a homogeneous medium. */
static void homogeneous_under_transform(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok("WorldBegin\nScale 2 3 4\nTranslate 1 2 3\nMakeNamedMedium \"a\" \"string type\" "
             "\"homogeneous\"\n",
             &sd, &m);
    double t0 = 0.5, t1 = 7.0;
    assert_true(medium_clip(&m, v3(0, 0, 0), v3(1, 0, 0), 0.0, &t0, &t1));
    assert_near(t0, 0.5, 0);
    assert_near(t1, 7.0, 0);
    free_all(&sd, &m);
}

static void homogeneous_errors(void **state)
{
    (void)state;
    build_err("WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"fluffy\"\n", "t.pbrt:2:1:",
              "\"fluffy\" is not supported (supported: \"homogeneous\", \"nanovdb\", "
              "\"uniformgrid\", \"cloud\", \"rgbgrid\")");
    build_err(homog("\"rgb sigma_a\" [0.5 -1 0]"), "t.pbrt:2:", "\"sigma_a\" must be");
    build_err(homog("\"spectrum sigma_s\" -0.5"), "t.pbrt:2:", "\"sigma_s\" must be");
    build_err(homog("\"float g\" 1"), "t.pbrt:2:", "\"g\" must lie in (-1, 1)");
    build_err(homog("\"float g\" -1"), "t.pbrt:2:", "\"g\"");
    build_err(homog("\"float g\" 1.5"), "t.pbrt:2:", "\"g\"");
    build_err(homog("\"float scale\" -1"), "t.pbrt:2:", "\"scale\" must be");
    build_err(homog("\"float scale\" 1e308 \"rgb sigma_s\" [1e10 1 1]"), "t.pbrt:2:", "\"scale\"");
    build_err(homog("\"float fog\" 1"), "t.pbrt:2:",
              "unused parameter \"float fog\" for MakeNamedMedium \"fog\"");
    build_err(homog("\"rgb Le\" [0 -0.1 0]"), "t.pbrt:2:", "\"Le\" times \"Lescale\" must be");
    build_err(homog("\"spectrum Le\" 2 \"float Lescale\" -0.5"), "t.pbrt:2:",
              "\"Lescale\" must be finite and non-negative");
    build_err(homog("\"float sigma_a\" 1"), "t.pbrt:2:", "sigma_a");
    /* Grid-only parameters are unknown to homogeneous media. */
    build_err(homog("\"string filename\" \"box.vdb\""), "t.pbrt:2:",
              "unused parameter \"string filename\"");
    build_err(homog("\"float temperaturescale\" 2"), "t.pbrt:2:", "unused parameter");
}

/* pbrt-v4's named measured media: the coefficients of the published tables
 * (Jensen et al. 2001: Skin1 sigma_s' = (0.74, 0.88, 1.01), sigma_a =
 * (0.032, 0.17, 0.48) per mm; Narasimhan et al. 2006: Espresso), times
 * "scale"; names match exactly; the preset gives both coefficients. */
static void homogeneous_presets(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(homog("\"string preset\" \"Skin1\""), &sd, &m);
    assert_rgb_near(m.sigma_s, rgb_make(0.74, 0.88, 1.01), 1e-7);
    assert_rgb_near(m.sigma_a, rgb_make(0.032, 0.17, 0.48), 1e-7);
    free_all(&sd, &m);
    build_ok(homog("\"string preset\" \"Espresso\" \"float scale\" 10 \"float g\" 0.3"), &sd, &m);
    assert_rgb_near(m.sigma_s, rgb_make(7.2378, 8.4557, 10.247), 1e-5);
    assert_rgb_near(m.sigma_a, rgb_make(47.984, 65.751, 88.493), 1e-4);
    assert_near(m.g, 0.3, 0);
    free_all(&sd, &m);
    size_t n = medium_preset_count();
    assert_int_equal(n, 47);
    for (size_t i = 0; i < n; ++i) { /* every name resolves to finite, non-negative values */
        rgb a, b;
        assert_true(medium_preset(medium_preset_name(i), &a, &b));
        assert_true(a.r >= 0 && a.g >= 0 && a.b >= 0 && b.r > 0 && isfinite(a.r + a.g + a.b));
    }
    build_err(homog("\"string preset\" \"skin1\""), "t.pbrt:2:", "no preset \"skin1\"");
    build_err(homog("\"string preset\" \"Skin1\" \"rgb sigma_a\" [1 1 1]"), "t.pbrt:2:",
              "\"sigma_a\" beside \"preset\" \"Skin1\"");
    build_err("WorldBegin\nMakeNamedMedium \"c\" \"string type\" \"cloud\" \"string preset\" "
              "\"Skin1\"\n",
              "t.pbrt:2:", "for \"homogeneous\" only");
}

/* ---- nanovdb ---- */

static const char *nanovdb_at(const char *prefix, const char *filename, const char *params)
{
    static char buf[2048];
    snprintf(buf, sizeof buf,
             "WorldBegin\n%sMakeNamedMedium \"smoke\" \"string type\" \"nanovdb\" "
             "\"string filename\" \"%s\" %s\n",
             prefix, filename, params);
    return buf;
}

static const char *nanovdb(const char *filename, const char *params)
{
    return nanovdb_at("", filename, params);
}

static void check_box(const medium *m)
{
    assert_true(medium_is_density_grid(m));
    assert_non_null(grid_medium_of(m)->grid);
    assert_near(grid_medium_of(m)->density_max, 1.0, 0);
    assert_near(grid_medium_of(m)->background, 0.0, 0);
    assert_v3_near(grid_medium_of(m)->support_lo, v3(-1, -1, -1), 0);
    assert_v3_near(grid_medium_of(m)->support_hi, v3(32, 32, 32), 0);
}

static void nanovdb_absolute_path(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb(VOLUMES "box.vdb", "\"rgb sigma_a\" [1 2 3] \"float scale\" 0.5 "
                                        "\"float g\" 0.8"),
             &sd, &m);
    check_box(&m);
    assert_string_equal(m.name, "smoke");
    /* Per unit density. */
    assert_rgb_near(m.sigma_a, rgb_make(0.5, 1, 1.5), 0);
    assert_rgb_near(m.sigma_s, rgb_grey(0.5), 0);
    assert_near(m.g, 0.8, 0);
    /* Voxel size 1/32, no offset. */
    assert_v3_near(transform_point(&grid_medium_of(&m)->index_from_render, v3(0.5, 0.25, 1)), v3(16, 8, 32),
                   1e-12);
    grid_accessor a;
    grid_accessor_init(grid_medium_of(&m)->grid, &a);
    vec3 p = transform_point(&grid_medium_of(&m)->index_from_render, v3(0.5, 0.5, 0.5));
    assert_near(grid_density_index(grid_medium_of(&m)->grid, &a, p), 1.0, 0);
    free_all(&sd, &m);

    /* The same volume as NanoVDB, and the grid named explicitly. */
    build_ok(nanovdb(VOLUMES "box.nvdb", "\"string gridname\" \"density\""), &sd, &m);
    check_box(&m);
    assert_rgb_near(m.sigma_a, rgb_grey(1), 0);
    free_all(&sd, &m);

    /* fog_sphere: index bounds [9, 55], index 32 at the world origin. */
    build_ok(nanovdb(VOLUMES "fog_sphere.vdb", ""), &sd, &m);
    assert_near(grid_medium_of(&m)->density_max, 1.0, 0);
    assert_v3_near(grid_medium_of(&m)->support_lo, v3(8, 8, 8), 0);
    assert_v3_near(grid_medium_of(&m)->support_hi, v3(56, 56, 56), 0);
    double t0 = 0, t1 = INFINITY;
    assert_true(medium_clip(&m, v3(-5, 0, 0), v3(1, 0, 0), 0.0, &t0, &t1));
    assert_near(t0, 4.25, 1e-12);
    assert_near(t1, 5.75, 1e-12);
    free_all(&sd, &m);
}

/* Without a temperature grid in the file there is no emission (as pbrt-v4),
 * and what would shape it is refused rather than ignored; both names of the
 * offset at once are refused. */
static void nanovdb_temperature_params(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb(VOLUMES "box.vdb", ""), &sd, &m);
    assert_null(grid_medium_of(&m)->temperature);
    assert_false(m.emissive);
    check_box(&m);
    free_all(&sd, &m);
    build_err(nanovdb(VOLUMES "box.vdb", "\"float temperaturescale\" 100"), "t.pbrt:2:",
              "\"temperaturescale\" needs a temperature grid");
    build_err(nanovdb(VOLUMES "box.vdb", "\"float Lescale\" 5"), "t.pbrt:2:",
              "\"Lescale\" needs a temperature grid");
    build_err(nanovdb(VOLUMES "box.vdb", "\"float temperaturecutoff\" 1 \"float temperatureoffset\" 2"),
              "t.pbrt:2:", "give one of \"temperatureoffset\" and \"temperaturecutoff\"");
    build_err(nanovdb(VOLUMES "box.vdb", "\"string temperaturename\" \"heat\""), "t.pbrt:2:",
              "temperature grid:");
}

static void nanovdb_relative_path(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    /* Relative to the directory of the declaring file. */
    build_ok_at(nanovdb("box.vdb", ""), VOLUMES "x.pbrt", transform_identity(), &sd, &m);
    check_box(&m);
    free_all(&sd, &m);
    build_ok_at(nanovdb("../volumes/fog_sphere.vdb", ""), VOLUMES "x.pbrt", transform_identity(),
                &sd, &m);
    assert_v3_near(grid_medium_of(&m)->support_lo, v3(8, 8, 8), 0);
    free_all(&sd, &m);
    /* Absolute names ignore the scene's directory. */
    build_ok_at(nanovdb(VOLUMES "box.vdb", ""), "/nonexistent/dir/x.pbrt", transform_identity(),
                &sd, &m);
    check_box(&m);
    free_all(&sd, &m);
    /* Not relative to the working directory. */
    build_err_at(nanovdb("box.vdb", ""), "/nonexistent/dir/x.pbrt", "/nonexistent/dir/x.pbrt:2:1:",
                 "/nonexistent/dir/box.vdb");
}

static void nanovdb_errors(void **state)
{
    (void)state;
    build_err(nanovdb(VOLUMES "missing.vdb", ""), "t.pbrt:2:1:", "missing.vdb");
    build_err(nanovdb(VOLUMES "box.vdb", "\"string gridname\" \"nope\""), "t.pbrt:2:1:", "nope");
    build_err(nanovdb(VOLUMES "smoke.vdb", "\"string gridname\" \"v\""), "t.pbrt:2:1:", "\"v\"");
    build_err(nanovdb(VOLUMES "generate.cpp", ""), "t.pbrt:2:1:", "generate.cpp");
    build_err("WorldBegin\nMakeNamedMedium \"smoke\" \"string type\" \"nanovdb\"\n", "t.pbrt:2:1:",
              "needs \"string filename\"");
    build_err(nanovdb("", ""), "t.pbrt:2:1:", "needs \"string filename\"");
    build_err(nanovdb(VOLUMES "box.vdb", "\"float g\" -1"), "t.pbrt:2:", "\"g\"");
    build_err(nanovdb(VOLUMES "box.vdb", "\"rgb Le\" [1 1 1]"), "t.pbrt:2:",
              "unused parameter \"rgb Le\"");
    build_err(nanovdb(VOLUMES "box.vdb", "\"float density\" 1"), "t.pbrt:2:",
              "unused parameter \"float density\"");
    build_err(nanovdb(VOLUMES "box.vdb", "\"rgb sigma_s\" [1 -1 1]"), "t.pbrt:2:", "sigma_s");
}

/* ---- clipping ---- */

static void clip_expect(const medium *m, vec3 o, vec3 d, double t0, double t1, double want0,
                        double want1)
{
    if (!medium_clip(m, o, d, 0.0, &t0, &t1))
        fail_msg("ray (%g %g %g) + t (%g %g %g) missed", o.x, o.y, o.z, d.x, d.y, d.z);
    if (!((t0 == want0 || fabs(t0 - want0) <= 1e-12 * fmax(1, fabs(want0))) &&
          (t1 == want1 || fabs(t1 - want1) <= 1e-12 * fmax(1, fabs(want1)))))
        fail_msg("ray (%g %g %g) + t (%g %g %g): [%.17g, %.17g], want [%.17g, %.17g]", o.x, o.y,
                 o.z, d.x, d.y, d.z, t0, t1, want0, want1);
}

static void clip_expect_miss(const medium *m, vec3 o, vec3 d, double t0, double t1)
{
    if (medium_clip(m, o, d, 0.0, &t0, &t1))
        fail_msg("ray (%g %g %g) + t (%g %g %g) hit [%g, %g]", o.x, o.y, o.z, d.x, d.y, d.z, t0,
                 t1);
}

/* box.vdb's support is index [-1, 32]^3, world [-1/32, 1]^3. */
static void clip_box(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb(VOLUMES "box.vdb", ""), &sd, &m);
    const double lo = -1.0 / 32, hi = 1.0;
    /* Along +x through the centre: the y and z components of d are zero, inside the slabs. */
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 0, INFINITY, 5 - 1.0 / 32, 6);
    /* A non-unit direction: t scales. */
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(2, 0, 0), 0, INFINITY, (5 + lo) / 2, 3);
    /* The given interval trims the result, and the support trims the interval. */
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 5.5, 5.75, 5.5, 5.75);
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 5.5, 100, 5.5, 6);
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), -INFINITY, INFINITY, 5 + lo, 6);
    /* From inside, backwards along -z. */
    clip_expect(&m, v3(0.5, 0.5, 0.5), v3(0, 0, -1), 0, INFINITY, 0, 0.5 - lo);
    /* Diagonal through the corners. */
    clip_expect(&m, v3(-1, -1, -1), v3(1, 1, 1), 0, INFINITY, 1 + lo, 2);
    /* On the boundary plane y = 1 (index 32): the closed box still holds it. */
    clip_expect(&m, v3(-5, hi, 0.5), v3(1, 0, 0), 0, INFINITY, 5 + lo, 6);
    /* A direction component too small to matter: no NaN. */
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(1, 1e-300, 0), 0, INFINITY, 5 + lo, 6);
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(1, 0x1.0p-1070, 0), 0, INFINITY, 5 + lo, 6);
    /* On the boundary plane, a denormal component decides: inward keeps the ray,
     * outward leaves the box at t = 0 (exactly what the slabs say). */
    clip_expect(&m, v3(-5, hi, 0.5), v3(1, -0x1.0p-1070, 0), 0, INFINITY, 5 + lo, 6);
    clip_expect_miss(&m, v3(-5, hi, 0.5), v3(1, 0x1.0p-1070, 0), 0, INFINITY);

    /* Misses: beside the box (zero component outside its slab), behind the
     * origin, beyond t1, before t0, a diagonal that passes a corner. */
    clip_expect_miss(&m, v3(-5, 1.5, 0.5), v3(1, 0, 0), 0, INFINITY);
    clip_expect_miss(&m, v3(-5, 0.5, -0.5), v3(1, 0, 0), 0, INFINITY);
    clip_expect_miss(&m, v3(-5, 0.5, 0.5), v3(-1, 0, 0), 0, INFINITY);
    clip_expect_miss(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 0, 4.9);
    clip_expect_miss(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 6.1, 10);
    clip_expect_miss(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 5.6, 5.5);
    clip_expect_miss(&m, v3(-2, 0, 0), v3(1, -1, 0), 0, INFINITY);
    clip_expect_miss(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), NAN, 10);
    clip_expect_miss(&m, v3(NAN, 0.5, 0.5), v3(1, 0, 0), 0, 10);
    clip_expect_miss(&m, v3(-5, 0.5, 0.5), v3(0, 0, 0), 0, 10);
    clip_expect(&m, v3(0.5, 0.5, 0.5), v3(0, 0, 0), 0, 10, 0, 10);
    free_all(&sd, &m);
}

/* The transform current at MakeNamedMedium places the grid. */
static void clip_follows_medium_transform(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb_at("Translate 10 0 0\n", VOLUMES "box.vdb", ""), &sd, &m);
    assert_v3_near(transform_point(&grid_medium_of(&m)->index_from_render, v3(10.5, 0.5, 0.5)),
                   v3(16, 16, 16), 1e-12);
    clip_expect(&m, v3(5, 0.5, 0.5), v3(1, 0, 0), 0, INFINITY, 5 - 1.0 / 32, 6);
    clip_expect_miss(&m, v3(-5, 0.5, 0.5), v3(0, 0, 1), 0, INFINITY);
    free_all(&sd, &m);

    /* AttributeBegin/End: the transform is the one at the declaration. */
    build_ok(nanovdb_at("AttributeBegin\nScale 2 2 2\n", VOLUMES "box.vdb", "\nAttributeEnd"),
             &sd, &m);
    clip_expect(&m, v3(-5, 1, 1), v3(1, 0, 0), 0, INFINITY, 5 - 2.0 / 32, 7);
    free_all(&sd, &m);

    /* A rotation: 90° about z takes +x to +y, so the box spans world x in [-1, 1/32]. */
    build_ok(nanovdb_at("Rotate 90 0 0 1\n", VOLUMES "box.vdb", ""), &sd, &m);
    clip_expect(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 0, INFINITY, 4, 5 + 1.0 / 32);
    free_all(&sd, &m);
}

/* Render space centred on a camera at (3, 1, 0): render = world - (3, 1, 0). */
static void clip_in_camera_render_space(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    transform render_from_world = transform_translate(v3(-3, -1, 0));
    build_ok_at(nanovdb_at("Translate 10 0 0\n", VOLUMES "box.vdb", ""), "t.pbrt",
                render_from_world, &sd, &m);
    assert_v3_near(transform_point(&grid_medium_of(&m)->index_from_render, v3(10.5 - 3, 0.5 - 1, 0.5)),
                   v3(16, 16, 16), 1e-12);
    /* The world ray (5, 0.5, 0.5) + t x is (2, -0.5, 0.5) + t x in render space. */
    clip_expect(&m, v3(2, -0.5, 0.5), v3(1, 0, 0), 0, INFINITY, 5 - 1.0 / 32, 6);
    /* The untranslated world ray misses in render space. */
    clip_expect_miss(&m, v3(5, 0.5, 0.5), v3(1, 0, 0), 0, INFINITY);
    free_all(&sd, &m);
}

/* Inactive voxels that do not hold the background are made to hold it at
 * load, with a warning naming how many (box_inactive.vdb: a slab of 32 x 32
 * x 8 voxels holding 50); the box's active voxels keep their density. */
static void inactive_voxels_fold(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    hz_error perr, err;
    if (scene_parse_string(nanovdb(VOLUMES "box_inactive.vdb", ""), "t.pbrt", &sd, &perr) != HZ_OK)
        fail_msg("parse error: %s", perr.message);
    medium_times times = {0, 1, 0, 1};
    FILE *warn = tmpfile();
    assert_non_null(warn);
    assert_int_equal(medium_create(&sd.media[0], transform_identity(), &times, warn, &m, &err),
                     HZ_OK);
    char text[1024] = "";
    rewind(warn);
    size_t n = fread(text, 1, sizeof text - 1, warn);
    text[n] = 0;
    fclose(warn);
    assert_non_null(strstr(text, "t.pbrt:2:1"));
    assert_non_null(strstr(text, "8192 inactive voxels hold values other than the background"));
    const grid *g = grid_medium_of(&m)->grid;
    assert_int_equal(grid_inactive_folded(g), 32 * 32 * 8);
    grid_accessor a;
    grid_accessor_init(g, &a);
    assert_near(grid_voxel(g, &a, 5, 5, 15), 0.0, 0); /* the slab: the background */
    assert_near(grid_voxel(g, &a, 5, 5, 11), 1.0, 0);
    assert_near(grid_medium_of(&m)->density_max, 1.0, 0);
    free_all(&sd, &m);
    /* A grid whose inactive voxels hold the background says nothing. */
    build_ok(nanovdb(VOLUMES "box.vdb", ""), &sd, &m);
    assert_int_equal(grid_inactive_folded(grid_medium_of(&m)->grid), 0);
    free_all(&sd, &m);
}

/* Hand-made grid media: empty support, non-zero background. */
static void clip_special_grids(void **state)
{
    (void)state;
    medium m;
    memset(&m, 0, sizeof m);
    m.ops = medium_kind("nanovdb");
    assert_true(grid_medium_alloc(&m));
    grid_medium_of(&m)->index_from_render = transform_identity();
    grid_medium_of(&m)->support_lo = v3(1, 1, 1);
    grid_medium_of(&m)->support_hi = v3(-1, -1, -1);
    clip_expect_miss(&m, v3(-5, 0, 0), v3(1, 0, 0), 0, INFINITY);
    clip_expect_miss(&m, v3(0, 0, 0), v3(0, 0, 0), 0, INFINITY);
    /* A non-zero background fills all space: the interval is kept. */
    grid_medium_of(&m)->background = 0.25;
    clip_expect(&m, v3(-5, 0, 0), v3(1, 0, 0), 0, INFINITY, 0, INFINITY);
    clip_expect_miss(&m, v3(-5, 0, 0), v3(1, 0, 0), 2, 1);
    medium_destroy(&m); /* no grid: nothing to release */
}

static void homogeneous_clip(void **state)
{
    (void)state;
    medium m;
    memset(&m, 0, sizeof m);
    m.ops = medium_kind("homogeneous");
    clip_expect(&m, v3(1e9, -3, 2), v3(0, 1, 0), 0.25, INFINITY, 0.25, INFINITY);
    clip_expect(&m, v3(0, 0, 0), v3(1, 0, 0), 3, 3, 3, 3);
    clip_expect_miss(&m, v3(0, 0, 0), v3(1, 0, 0), 3, 2);
    medium_destroy(&m);
}

static void free_is_safe(void **state)
{
    (void)state;
    medium m;
    memset(&m, 0, sizeof m);
    medium_destroy(&m);
    medium_destroy(&m);
    medium_destroy(NULL);
    scene_desc sd;
    build_ok(nanovdb(VOLUMES "box.vdb", ""), &sd, &m);
    medium_destroy(&m);
    medium_destroy(&m); /* the grid pointer was cleared */
    scene_desc_free(&sd);
}

/* ---- moving grids ---- */

/* A ray's index-space origin at `time` (the grid ray of o + t d). */
static vec3 index_origin(const medium *m, vec3 o, double time)
{
    medium_ray r;
    assert_true(grid_medium_ray_make(m, o, v3(1, 0, 0), time, &r));
    return r.at.grid.o;
}

static void clip_expect_at(const medium *m, vec3 o, vec3 d, double time, double want0,
                           double want1)
{
    double t0 = 0, t1 = INFINITY;
    if (!medium_clip(m, o, d, time, &t0, &t1))
        fail_msg("missed at time %g", time);
    if (!(fabs(t0 - want0) <= 1e-12 * fmax(1, fabs(want0)) &&
          fabs(t1 - want1) <= 1e-12 * fmax(1, fabs(want1))))
        fail_msg("time %g: [%.17g, %.17g], want [%.17g, %.17g]", time, t0, t1, want0, want1);
}

/* A grid under an animated transform moves with it over TransformTimes. */
static void moving_translation(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb_at("ActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n",
                        VOLUMES "box.vdb", ""),
             &sd, &m);
    assert_true(grid_medium_of(&m)->moving);
    vec3 o = v3(-5, 0.5, 0.5);
    for (double t = 0; t <= 1.0; t += 0.25) {
        assert_v3_near(index_origin(&m, o, t), v3(32 * (-5 - t), 16, 16), 1e-12);
        clip_expect_at(&m, o, v3(1, 0, 0), t, 5 + t - 1.0 / 32, 6 + t);
    }
    /* Before and after the transform times: the end keyframes. */
    assert_v3_near(index_origin(&m, o, -3), v3(-160, 16, 16), 1e-12);
    assert_v3_near(index_origin(&m, o, 7), v3(-192, 16, 16), 1e-12);
    /* A ray that meets the box only late in the motion. */
    double t0 = 0, t1 = INFINITY;
    assert_false(medium_clip(&m, v3(1.5, -5, 0.5), v3(0, 1, 0), 0.25, &t0, &t1));
    assert_true(medium_clip(&m, v3(1.5, -5, 0.5), v3(0, 1, 0), 0.75, &t0, &t1));
    free_all(&sd, &m);

    /* Other TransformTimes: the motion spans them. */
    build_ok("TransformTimes 2 4\nWorldBegin\nActiveTransform EndTime\nTranslate 1 0 0\n"
             "ActiveTransform All\nMakeNamedMedium \"smoke\" \"string type\" \"nanovdb\" "
             "\"string filename\" \"" VOLUMES "box.vdb\"\n",
             &sd, &m);
    assert_v3_near(index_origin(&m, o, 3), v3(32 * -5.5, 16, 16), 1e-12);
    assert_v3_near(index_origin(&m, o, 1), v3(-160, 16, 16), 1e-12);
    free_all(&sd, &m);
}

/* Rotations are interpolated as pbrt-v4 does (slerp): half way through a 90°
 * turn about z, the grid has turned 45°. */
static void moving_rotation(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb_at("ActiveTransform EndTime\nRotate 90 0 0 1\nActiveTransform All\n",
                        VOLUMES "box.vdb", ""),
             &sd, &m);
    /* Index (16,16,16) is medium (0.5, 0.5, 0.5); turned 45° about z. */
    vec3 centre = v3(0, sqrt(0.5), 0.5);
    assert_v3_near(index_origin(&m, centre, 0.5), v3(16, 16, 16), 1e-12);
    assert_v3_near(index_origin(&m, v3(-0.5, 0.5, 0.5), 1), v3(16, 16, 16), 1e-12);
    free_all(&sd, &m);
}

/* Equal keyframes are no motion: the static placement and code path. */
static void moving_equal_keyframes_are_static(void **state)
{
    (void)state;
    scene_desc sd;
    medium m, still;
    build_ok(nanovdb_at("Translate 0.25 0 0\nActiveTransform EndTime\nTranslate 0 0 0\n"
                        "ActiveTransform All\n",
                        VOLUMES "box.vdb", ""),
             &sd, &m);
    assert_false(grid_medium_of(&m)->moving);
    scene_desc sd2;
    build_ok(nanovdb_at("Translate 0.25 0 0\n", VOLUMES "box.vdb", ""), &sd2, &still);
    assert_memory_equal(&grid_medium_of(&m)->index_from_render, &grid_medium_of(&still)->index_from_render,
                        sizeof grid_medium_of(&still)->index_from_render);
    free_all(&sd, &m);
    free_all(&sd2, &still);
    /* A homogeneous medium accepts an animated transform (its shapes place it). */
    build_ok("WorldBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n"
             "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n",
             &sd, &m);
    assert_true(medium_is_homogeneous(&m));
    free_all(&sd, &m);
}

/* box_velocity.vdb: box.vdb's density, v = (1, 0.25, 0) world units per time
 * on the same index space (voxel size 1/32). */
static void velocity_box(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb(VOLUMES "box_velocity.vdb",
                     "\"string velocityname\" \"v\" \"float velocityscale\" 0.5"),
             &sd, &m);
    check_box(&m);
    assert_non_null(grid_medium_of(&m)->velocity);
    assert_true(grid_medium_of(&m)->velocity_aligned);
    assert_false(grid_medium_of(&m)->moving);
    assert_near(grid_medium_of(&m)->velocity_scale, 0.5, 0);
    assert_near(grid_medium_of(&m)->velocity_time, 0.0, 0); /* TransformTimes start */
    /* |v| times 32 index units per world unit, on every axis. */
    double grow = 32 * sqrt(1.0625);
    assert_v3_near(grid_medium_of(&m)->dilation, v3(grow, grow, grow), 1e-5);

    /* At time 1 the density has moved by 0.5 v = 16 and 4 voxels. */
    vec3 o = v3(40.0 / 32, 18.0 / 32, 0.5); /* index (40, 18, 16) */
    medium_ray r;
    uint64_t lookups = 0;
    assert_true(grid_medium_ray_make(&m, o, v3(0, 0, 1), 1.0, &r));
    assert_near(r.at.grid.shift, 0.5, 0);
    assert_near(density_at(&m, &r, 0.0, &lookups), 1.0, 0);
    assert_int_equal(lookups, 2); /* velocity, then density */
    assert_near(density_at(&m, &r, 15.5 / 32, &lookups), 0.5, 1e-12); /* z = 31.5 */
    /* At time 0 (velocitytime): no velocity lookup, the static box. */
    assert_true(grid_medium_ray_make(&m, o, v3(0, 0, 1), 0.0, &r));
    assert_near(r.at.grid.shift, 0.0, 0);
    lookups = 0;
    assert_near(density_at(&m, &r, 0.0, &lookups), 0.0, 0);
    assert_int_equal(lookups, 1);
    /* The support grows by |shift| times the dilation, both ways. */
    assert_true(grid_medium_ray_make(&m, o, v3(0, 0, 1), 1.0, &r));
    assert_v3_near(r.at.grid.lo, v3_sub(grid_medium_of(&m)->support_lo, v3_scale(grid_medium_of(&m)->dilation, 0.5)), 1e-12);
    assert_v3_near(r.at.grid.hi, v3_add(grid_medium_of(&m)->support_hi, v3_scale(grid_medium_of(&m)->dilation, 0.5)), 1e-12);
    grow = grid_medium_of(&m)->dilation.x;
    clip_expect_at(&m, v3(-5, 0.5, 0.5), v3(1, 0, 0), 1.0, 5 + (-1 - 0.5 * grow) / 32,
                   5 + (32 + 0.5 * grow) / 32);
    free_all(&sd, &m);

    /* velocitytime: the grid shows time 0.5; at time 0 the box sits 8 and 2
     * voxels back (where the velocity grid still holds v). */
    build_ok(nanovdb(VOLUMES "box_velocity.vdb",
                     "\"string velocityname\" \"v\" \"float velocityscale\" 0.5 "
                     "\"float velocitytime\" 0.5"),
             &sd, &m);
    assert_true(grid_medium_ray_make(&m, v3(-2.0 / 32, 0.5, 0.5), v3(1, 0, 0), 0.0, &r));
    assert_near(r.at.grid.shift, -0.25, 0);
    assert_near(density_at(&m, &r, 0.0, &lookups), 1.0, 0);          /* x = -2 */
    assert_near(density_at(&m, &r, -7.0 / 32, &lookups), 0.0, 0);    /* x = -9 */
    assert_near(density_at(&m, &r, 25.5 / 32, &lookups), 0.5, 1e-12); /* x = 23.5 */
    free_all(&sd, &m);
}

/* plume.vdb's velocity has its own map (half the resolution): lookups go
 * through the grids' world space. Checked against the grid functions. */
static void velocity_unaligned_grids(void **state)
{
    (void)state;
    scene_desc sd;
    medium m;
    build_ok(nanovdb(VOLUMES "plume.vdb",
                     "\"string velocityname\" \"v\" \"float velocityscale\" 0.2 "
                     "\"float velocitytime\" 0.5"),
             &sd, &m);
    assert_false(grid_medium_of(&m)->velocity_aligned);
    const grid *d = grid_medium_of(&m)->grid, *v = grid_medium_of(&m)->velocity;
    grid_accessor va, da;
    grid_accessor_init(v, &va);
    grid_accessor_init(d, &da);
    uint64_t seed = 5, lookups = 0;
    int nonzero = 0;
    for (int n = 0; n < 300; ++n) {
        vec3 o = v3(rng_next(&seed) - 0.5, 2 * rng_next(&seed), rng_next(&seed) - 0.5);
        double time = rng_next(&seed);
        medium_ray r;
        assert_true(grid_medium_ray_make(&m, o, v3(0, 1, 0), time, &r));
        double got = density_at(&m, &r, 0.0, &lookups);
        vec3 vel = grid_vec3_index(v, &va, grid_index_from_world(v, o));
        vec3 moved = v3_sub(o, v3_scale(vel, 0.2 * (time - 0.5)));
        double want = grid_density_index(d, &da, grid_index_from_world(d, moved));
        assert_near(got, want, 1e-9);
        nonzero += want > 0.0;
    }
    assert_true(nonzero > 20);
    free_all(&sd, &m);
}

/* The column of `needle` (1-based) in the one-line-after-WorldBegin source. */
static int column_of(const char *src, const char *needle)
{
    const char *p = strstr(src, needle);
    assert_non_null(p);
    const char *line = p;
    while (line > src && line[-1] != '\n')
        --line;
    return (int)(p - line) + 1;
}

static void velocity_errors(void **state)
{
    (void)state;
    char want[64];
    const char *src = nanovdb(VOLUMES "box_velocity.vdb", "\"string velocityname\" \"nope\"");
    snprintf(want, sizeof want, "t.pbrt:2:%d:", column_of(src, "\"string velocityname\""));
    build_err(src, want, "velocity grid");
    build_err(nanovdb(VOLUMES "box_velocity.vdb", "\"string velocityname\" \"nope\""), want,
              "no grid named \"nope\" (grids: \"density\", \"v\", \"v0\")");
    build_err(nanovdb(VOLUMES "box_velocity.vdb", "\"string velocityname\" \"density\""), want,
              "grid \"density\" is float, expected vec3s");
    build_err(nanovdb(VOLUMES "box_velocity.vdb", "\"string velocityname\" \"\""), want,
              "\"velocityname\" is empty");
    src = nanovdb(VOLUMES "box_velocity.vdb",
                  "\"string velocityname\" \"v\" \"float velocityscale\" -1");
    snprintf(want, sizeof want, "t.pbrt:2:%d:", column_of(src, "\"float velocityscale\""));
    build_err(src, want, "\"velocityscale\" must be finite and non-negative, got -1");
    build_err(nanovdb(VOLUMES "box.vdb", "\"float velocityscale\" 1"), "t.pbrt:2:",
              "\"velocityscale\" needs a velocity grid (\"string velocityname\")");
    build_err(nanovdb(VOLUMES "box.vdb", "\"float velocitytime\" 1"), "t.pbrt:2:",
              "\"velocitytime\" needs a velocity grid");
    build_err(homog("\"string velocityname\" \"v\""), "t.pbrt:2:",
              "unused parameter \"string velocityname\"");
    /* The parser refuses a written NaN at its place. */
    scene_desc sd;
    hz_error err;
    src = nanovdb(VOLUMES "box_velocity.vdb",
                  "\"string velocityname\" \"v\" \"float velocityscale\" nan");
    assert_int_equal(scene_parse_string(src, "t.pbrt", &sd, &err), HZ_ERROR);
    snprintf(want, sizeof want, "t.pbrt:2:%d:", column_of(src, "velocityscale\" nan") + 15);
    assert_non_null(strstr(err.message, want));
    assert_non_null(strstr(err.message, "not a number"));

    /* A NaN that reaches the medium (set after parsing) is refused too. */
    src = nanovdb(VOLUMES "box_velocity.vdb",
                  "\"string velocityname\" \"v\" \"float velocityscale\" 1");
    if (scene_parse_string(src, "t.pbrt", &sd, &err) != HZ_OK)
        fail_msg("%s", err.message);
    param_list *pl = &sd.media[0].entity.params;
    for (size_t i = 0; i < pl->count; ++i)
        if (strcmp(pl->items[i].name, "velocityscale") == 0)
            pl->items[i].nums[0] = NAN;
    medium m;
    medium_times times = {0, 1, 0, 1};
    assert_int_equal(medium_create(&sd.media[0], transform_identity(), &times, NULL, &m, &err),
                     HZ_ERROR);
    snprintf(want, sizeof want, "t.pbrt:2:%d:", column_of(src, "\"float velocityscale\""));
    assert_non_null(strstr(err.message, want));
    assert_non_null(strstr(err.message, "\"velocityscale\" must be finite"));
    medium_destroy(&m);
    scene_desc_free(&sd);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(homogeneous_defaults),
        cmocka_unit_test(homogeneous_parameters),
        cmocka_unit_test(homogeneous_under_transform),
        cmocka_unit_test(homogeneous_errors),
        cmocka_unit_test(homogeneous_presets),
        cmocka_unit_test(nanovdb_absolute_path),
        cmocka_unit_test(inactive_voxels_fold),
        cmocka_unit_test(nanovdb_temperature_params),
        cmocka_unit_test(nanovdb_relative_path),
        cmocka_unit_test(nanovdb_errors),
        cmocka_unit_test(clip_box),
        cmocka_unit_test(clip_follows_medium_transform),
        cmocka_unit_test(clip_in_camera_render_space),
        cmocka_unit_test(clip_special_grids),
        cmocka_unit_test(homogeneous_clip),
        cmocka_unit_test(free_is_safe),
        cmocka_unit_test(moving_translation),
        cmocka_unit_test(moving_rotation),
        cmocka_unit_test(moving_equal_keyframes_are_static),
        cmocka_unit_test(velocity_box),
        cmocka_unit_test(velocity_unaligned_grids),
        cmocka_unit_test(velocity_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
