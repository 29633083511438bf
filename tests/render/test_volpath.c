/* Integrator "volpath": closed forms of multiple scattering (furnaces), the
 * selection of the integrator and its parameters. */
#include "media_test_util.h"

/* A sphere of medium (radius 1 at the origin) under a uniform sky, seen from
 * outside: with albedo 1 and no absorption anywhere, every path leaves with
 * the sky's radiance, so L = sky on every pixel, inside the sphere or not. */
static char *sky_furnace(const char *medium, const char *extra)
{
    return sfmt("LookAt 0 0 4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 35\n"
                "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                "Integrator \"volpath\" \"integer maxdepth\" 100000 %s\n"
                "WorldBegin\n"
                "LightSource \"infinite\" \"rgb L\" [0.5 1 1.5]\n"
                "MakeNamedMedium \"m\" %s\n"
                "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n"
                "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
                extra, medium);
}

/* Grey media: scattering and null-collision weights are exactly 1, so each
 * path returns the sky exactly (a zero-variance furnace). */
static void test_grey_sky_furnace_is_exact(void **state)
{
    (void)state;
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [3 3 3] "
        "\"float g\" 0.6",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [8 8 8] \"float g\" -0.3",
    };
    for (size_t k = 0; k < 2; ++k) {
        char *text = sky_furnace(media[k], "");
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 8, 8, 16);
        for (int i = 0; i < 64; ++i)
            for (int c = 0; c < 3; ++c)
                assert_float_equal(ch(px[i].mean, c), 0.5 * (c + 1), 1e-9);
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}

/* Chromatic albedo-1 media: the hero channel's tracking carries the others
 * through r_u; the mean is still the sky, within noise. */
static void test_chromatic_sky_furnace(void **state)
{
    (void)state;
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0.5 2 4] "
        "\"float g\" 0.5",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [2 6 12]",
    };
    for (size_t k = 0; k < 2; ++k) {
        char *text = sky_furnace(media[k], "");
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 8, 8, 1024);
        double sum[3] = {0, 0, 0}, var[3] = {0, 0, 0};
        for (int i = 0; i < 64; ++i)
            for (int c = 0; c < 3; ++c) {
                sum[c] += ch(px[i].mean, c);
                var[c] += ch(px[i].se, c) * ch(px[i].se, c);
            }
        for (int c = 0; c < 3; ++c) {
            double mean = sum[c] / 64, se = sqrt(var[c]) / 64, want = 0.5 * (c + 1);
            if (verbose())
                print_message("medium %zu channel %d: %.6f +- %.6f (want %g)\n", k, c, mean, se,
                              want);
            assert_true(se < 0.02 * want);
            assert_true(fabs(mean - want) < 4.0 * se + 1e-12);
        }
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}

/* A closed room whose walls emit Le and reflect with albedo rho, filled with
 * an albedo-1 medium: the radiance is Le / (1 - rho) everywhere, in every
 * direction (the medium neither adds nor removes light from a uniform
 * field). Exercises area-light MIS (light sampling against BSDF and phase
 * sampling), shadow rays by ratio tracking, and surface-medium bounces. */
static char *emitting_room(const char *medium, const char *integrator)
{
    char *box = box_mesh(v3(-2, -2, -2), v3(2, 2, 2));
    char *s = sfmt("MediumInterface \"\" \"m\"\n"
                   "LookAt 0 0 -1.5  0 0.3 1  0 1 0\nCamera \"perspective\" \"float fov\" 70\n"
                   "Film \"rgb\" \"integer xresolution\" 6 \"integer yresolution\" 6\n"
                   "Sampler \"independent\" \"integer pixelsamples\" 16\n"
                   "%s\nWorldBegin\n"
                   "MakeNamedMedium \"m\" %s\nMediumInterface \"\" \"\"\n"
                   "Material \"diffuse\" \"rgb reflectance\" [0.5 0.25 0.75]\n"
                   "AreaLightSource \"diffuse\" \"rgb L\" [1 2 0.5] \"bool twosided\" true\n%s",
                   integrator, medium, box);
    free(box);
    return s;
}

static void test_emitting_room_furnace(void **state)
{
    (void)state;
    const char *media[] = {
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0.3 0.6 0.9] "
        "\"float g\" 0.4",
        "\"string type\" \"nanovdb\" \"string filename\" \"" VOLUMES "/fog_sphere.vdb\" "
        "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [3 1 2] \"float g\" -0.2",
    };
    const char *integ[] = {"Integrator \"volpath\" \"integer maxdepth\" 400",
                           "Integrator \"volpath\" \"integer maxdepth\" 400 "
                           "\"string lightsampler\" \"uniform\""};
    const double want[3] = {1.0 / 0.5, 2.0 / 0.75, 0.5 / 0.25};
    for (size_t k = 0; k < 2; ++k) {
        char *text = emitting_room(media[k], integ[k]);
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 6, 6, 1024);
        double sum[3] = {0, 0, 0}, var[3] = {0, 0, 0};
        for (int i = 0; i < 36; ++i)
            for (int c = 0; c < 3; ++c) {
                sum[c] += ch(px[i].mean, c);
                var[c] += ch(px[i].se, c) * ch(px[i].se, c);
            }
        for (int c = 0; c < 3; ++c) {
            double mean = sum[c] / 36, se = sqrt(var[c]) / 36;
            if (verbose())
                print_message("room %zu channel %d: %.5f +- %.5f (want %g)\n", k, c, mean, se,
                              want[c]);
            assert_true(se < 0.02 * want[c]);
            assert_true(fabs(mean - want[c]) < 4.0 * se);
        }
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grey_sky_furnace_is_exact),
        cmocka_unit_test(test_chromatic_sky_furnace),
        cmocka_unit_test(test_emitting_room_furnace),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
