/* transmittance "auto" (singlescatter's default, issue 43): in a grid whose
 * voxels are optically thin the marching steps grow to a fixed optical
 * depth, so the cost follows the optical depth and not the voxel count,
 * and the estimate stays the closed form where marching is exact. */
#include "media_test_util.h"

#include "integrator/singlescatter_scene.h"

/* A pure absorber of constant density 1 in the unit cube, as an n^3
 * uniformgrid, held by the interface box [0.1, 0.9]^3 (inside it the
 * density is exactly 1: a uniformgrid's lookups fall off within a voxel of
 * its faces), looked at along z through its middle, in front of a white
 * sky: each pixel is the box's transmittance, exp(-sigma 0.8 / |d.z|).
 * `integrator`: the line. */
static char *cube_scene(int n, const char *integrator)
{
    size_t cells = (size_t)n * n * n;
    char *ones = malloc(cells * 2 + 1);
    assert_non_null(ones);
    for (size_t i = 0; i < cells; ++i) {
        ones[2 * i] = '1';
        ones[2 * i + 1] = ' ';
    }
    ones[cells * 2] = '\0';
    char *encl = box_mesh(v3(0.1, 0.1, 0.1), v3(0.9, 0.9, 0.9));
    char *s = sfmt("LookAt 0.5 0.5 -3  0.5 0.5 0  0 1 0\n"
                   "Camera \"perspective\" \"float fov\" 6\n"
                   "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                   "Sampler \"independent\" \"integer pixelsamples\" 4\n%s\n"
                   "WorldBegin\n"
                   "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                   "MakeNamedMedium \"cube\" \"string type\" \"uniformgrid\" "
                   "\"integer nx\" %d \"integer ny\" %d \"integer nz\" %d \"float density\" [%s] "
                   "\"rgb sigma_a\" [0.5 1 2] \"rgb sigma_s\" [0 0 0]\n"
                   "AttributeBegin\nMediumInterface \"cube\" \"\"\nMaterial \"interface\"\n%s"
                   "AttributeEnd\n",
                   integrator, n, n, n, ones, encl);
    free(ones);
    free(encl);
    return s;
}

typedef struct {
    double lookups_per_pixel;
    double worst_rel; /* the largest |L / exp(-tau) - 1| over pixels and channels */
} cube_result;

static cube_result render_cube(int n, const char *integrator)
{
    char *text = cube_scene(n, integrator);
    render_scene *rs = build(text);
    free(text);
    const camera *cam = render_scene_camera(rs);
    sampler smp = *render_scene_sampler(rs);
    integrator_counters c = {0};
    cube_result r = {0.0, 0.0};
    const double sigma[3] = {0.5, 1.0, 2.0};
    for (int i = 0; i < 64; ++i) {
        camera_sample cs = {v2(i % 8 + 0.5, i / 8 + 0.5), v2(0.5, 0.5), 0.5, 1.0};
        ray_differential rd;
        assert_true(camera_generate_ray_differential(cam, cs, &rd));
        vec3 d = v3_normalize(rd.r.d);
        /* The world is the render space's translate: lengths are equal. */
        double length = 0.8 / fabs(d.z);
        for (int s = 0; s < smp.spp; ++s) {
            sampler_state st;
            sampler_start(&smp, i % 8, i / 8, s, &st);
            double depth;
            rgb L = render_scene_li(rs, &rd, &st, &depth, &c);
            for (int k = 0; k < 3; ++k)
                r.worst_rel = fmax(r.worst_rel,
                                   fabs(rgb_ch(L, k) / exp(-sigma[k] * length) - 1.0));
        }
    }
    r.lookups_per_pixel = (double)c.density_lookups / 64.0;
    render_scene_destroy(rs);
    return r;
}

/* At 8^3 a voxel holds 2/8 of optical depth (the largest sigma_t, 2), at
 * 128^3 1/64: "auto" keeps jittered marching at 1 voxel in the first and in
 * the second marches 6.4 voxels a step (the 16 voxels that hold 0.25,
 * capped at 1/16 of the 102-voxel chord), where "jittered" at 1 voxel
 * takes 16x the lookups of 8^3; both stay the exact Beer-Lambert value
 * (marching is exact in a constant density). */
static void test_auto_steps_follow_optical_depth(void **state)
{
    (void)state;
    const char *automatic = "Integrator \"singlescatter\"";
    const char *fixed = "Integrator \"singlescatter\" \"string transmittance\" \"jittered\"";
    cube_result a8 = render_cube(8, automatic), a128 = render_cube(128, automatic);
    cube_result j8 = render_cube(8, fixed), j128 = render_cube(128, fixed);
    print_message("lookups per pixel: auto %.1f (8^3) %.1f (128^3), jittered %.1f %.1f; "
                  "worst relative error %.2g %.2g %.2g %.2g\n",
                  a8.lookups_per_pixel, a128.lookups_per_pixel, j8.lookups_per_pixel,
                  j128.lookups_per_pixel, a8.worst_rel, a128.worst_rel, j8.worst_rel,
                  j128.worst_rel);
    assert_true(j8.lookups_per_pixel > 0.0);
    /* The fixed step's cost follows the voxels (the proof that the
     * counters see the marching)... */
    assert_true(j128.lookups_per_pixel > 12.0 * j8.lookups_per_pixel);
    /* ... "auto" is the same at 8^3, where it does not scale ... */
    assert_true(a8.lookups_per_pixel == j8.lookups_per_pixel);
    /* ... and at 128^3 takes about 1/6.4 of the fixed step's lookups. */
    assert_true(a128.lookups_per_pixel < 0.2 * j128.lookups_per_pixel);
    assert_true(a128.lookups_per_pixel < 3.0 * a8.lookups_per_pixel);
    assert_true(a8.worst_rel < 1e-6 && a128.worst_rel < 1e-6); /* float grids and hits */
    assert_true(j8.worst_rel < 1e-6 && j128.worst_rel < 1e-6);
}

/* The factor itself, as the step pilot sees it (no chord): 1 where a
 * voxel holds enough optical depth, else the steps that hold 0.25. */
static double cube_auto_scale(int n)
{
    char *text = cube_scene(n, "Integrator \"singlescatter\"");
    render_scene *rs = build(text);
    free(text);
    render_marching m;
    assert_true(render_scene_marching(rs, &m));
    assert_true(m.auto_steps);
    render_scene_destroy(rs);
    return m.auto_scale;
}

static void test_auto_step_scale(void **state)
{
    (void)state;
    /* sigma_t at most 2, density 1: a voxel holds 2/n. */
    assert_true(cube_auto_scale(4) == 1.0);  /* 0.5 a voxel */
    assert_true(fabs(cube_auto_scale(8) - 1.0) < 1e-12); /* 0.25 (within rounding) */
    assert_true(fabs(cube_auto_scale(16) - 2.0) < 1e-12);
    assert_true(fabs(cube_auto_scale(64) - 8.0) < 1e-12);
}

/* What turns "auto" off: an estimator, or a step, named in the scene; and
 * "auto" named with a shadow estimator is refused. */
static void test_auto_settings(void **state)
{
    (void)state;
    const struct {
        const char *line;
        bool automatic;
    } cases[] = {
        {"Integrator \"singlescatter\"", true},
        {"Integrator \"singlescatter\" \"string transmittance\" \"auto\"", true},
        {"Integrator \"singlescatter\" \"string transmittance\" \"auto\" \"float stepsize\" 2",
         true},
        {"Integrator \"singlescatter\" \"string transmittance\" \"jittered\"", false},
        {"Integrator \"singlescatter\" \"float stepsize\" 2", false},
        {"Integrator \"singlescatter\" \"float shadowstepsize\" 4", false},
        {"Integrator \"singlescatter\" \"string shadowtransmittance\" \"ratio\"", false},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char *text = cube_scene(4, cases[i].line);
        render_scene *rs = build(text);
        free(text);
        render_marching m;
        bool marching = render_scene_marching(rs, &m);
        assert_true(marching || !cases[i].automatic);
        assert_true((marching && m.auto_steps) == cases[i].automatic);
        render_scene_destroy(rs);
    }
    char msg[512];
    char *text = cube_scene(4, "Integrator \"singlescatter\" \"string transmittance\" \"auto\" "
                               "\"string shadowtransmittance\" \"ratio\"");
    build_scene_expect_error(text, msg, sizeof msg);
    free(text);
    assert_non_null(strstr(msg, "needs a \"transmittance\" other than \"auto\""));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_auto_step_scale),
        cmocka_unit_test(test_auto_settings),
        cmocka_unit_test(test_auto_steps_follow_optical_depth),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
