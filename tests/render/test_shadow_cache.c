/* The shadow cache (Integrator "singlescatter" "float shadowcache"):
 * closed-form transmittance through a uniform box under a tilted distant
 * light, a surface's shadow, convergence against exact shadow rays, and the
 * scenes it refuses. */
#include "media_test_util.h"

#include "integrator/shadow_cache.h"

/* Density 1 over [-2, 2]^3 (4^3 voxels of 1), sigma_t (0.75, 1, 1.5) or,
 * `grey`, 1, seen through an interface box
 * [-1, 1]^3; a distant light along w ~ (0.1, 1, 0.1); an opaque quad at
 * y = 1.5 over x >= 0.3 shades part of the box. */
static char *box_scene(double spacing, bool occluder, bool grey)
{
    char *box = box_mesh(v3(-1, -1, -1), v3(1, 1, 1));
    char *s = sfmt(
        "LookAt 0 0 -6  0 0 0  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 30\n"
        "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
        "Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" \"float shadowcache\" %g\n"
        "WorldBegin\n"
        "LightSource \"distant\" \"point3 from\" [0.1 1 0.1] \"point3 to\" [0 0 0] \"rgb L\" [1 1 1]\n"
        "MakeNamedMedium \"m\" \"string type\" \"uniformgrid\" \"integer nx\" 4 \"integer ny\" 4\n"
        "  \"integer nz\" 4 \"point3 p0\" [-2 -2 -2] \"point3 p1\" [2 2 2]\n"
        "  \"float density\" [1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1\n"
        "                     1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1]\n"
        "  \"rgb sigma_a\" %s \"rgb sigma_s\" [0.5 0.5 0.5]\n"
        "AttributeBegin\n  Material \"interface\"\n  MediumInterface \"m\" \"\"\n  %s\nAttributeEnd\n"
        "%s",
        spacing, grey ? "[0.5 0.5 0.5]" : "[0.25 0.5 1]", box,
        occluder ? "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
                   "  \"point3 P\" [0.3 1.5 -3  3 1.5 -3  3 1.5 3  0.3 1.5 3]\n"
                 : "");
    free(box);
    return s;
}

static vec3 render_point(const render_scene *rs, vec3 world)
{
    transform render_from_world = transform_inverse(render_scene_camera(rs)->world_from_render);
    return transform_point(&render_from_world, world);
}

/* Inside the box, where every node a lookup reads lies on a column that
 * leaves through the top face, the optical depth is linear across the
 * light and along it, which the interpolation reproduces: the cache gives
 * exp(-sigma_t (1 - y) / w_y) to float precision. Under the quad it is 0. */
static void check_closed_form(bool grey)
{
    char *text = box_scene(0.125, true, grey);
    render_scene *rs = build_scene_or_fail(text, NULL);
    free(text);
    const shadow_cache *c = shadow_caches_get(render_scene_shadow_caches(rs), 0, 0);
    assert_non_null(c);
    vec3 w = v3_normalize(v3(0.1, 1.0, 0.1));
    rgb sigma_t = grey ? rgb_grey(1.0) : rgb_make(0.75, 1.0, 1.5);
    rng r = rng_seeded(7);
    double worst = 0.0;
    for (int k = 0; k < 200; ++k) {
        vec3 p = v3(-0.5 + 0.2 * rng_uniform(&r), -0.5 + rng_uniform(&r),
                    -0.2 + 0.4 * rng_uniform(&r));
        rgb T = shadow_cache_transmittance(c, render_point(rs, p), NULL);
        double d = (1.0 - p.y) / w.y;
        for (int ch = 0; ch < 3; ++ch) {
            double want = exp(-rgb_ch(sigma_t, ch) * d);
            worst = fmax(worst, fabs(rgb_ch(T, ch) / want - 1.0));
        }
        vec3 q = v3(0.6 + 0.1 * rng_uniform(&r), p.y, p.z);
        rgb T0 = shadow_cache_transmittance(c, render_point(rs, q), NULL);
        assert_true(T0.r == 0.0 && T0.g == 0.0 && T0.b == 0.0);
    }
    print_message("closed form: worst relative error %.3g\n", worst);
    assert_true(worst < 1e-5);
    render_memory mem = render_scene_memory(rs);
    assert_true(mem.shadow_caches > 0.0);
    render_scene_destroy(rs);
}

static void test_closed_form(void **state)
{
    (void)state;
    check_closed_form(false);
    check_closed_form(true);
}

/* The fog sphere marched at step 1 voxel, with shadow rays (a quarter voxel)
 * or a cache. */
static char *sphere_scene(double cache) { return fog_sphere_scene("raymarch", 1.0, 0.25, cache); }

/* Against exact shadow rays (marched at a quarter voxel), the whole image's
 * relMSE falls as the spacing shrinks, and is small at half a voxel. */
static void test_converges_to_shadow_rays(void **state)
{
    (void)state;
    char *text = sphere_scene(0.0);
    render_scene *exact = build_scene_or_fail(text, NULL);
    free(text);
    assert_null(render_scene_shadow_caches(exact));
    double prev = INFINITY, mean = 0.0;
    const double spacings[3] = {2.0, 1.0, 0.5};
    for (int k = 0; k < 3; ++k) {
        text = sphere_scene(spacings[k]);
        render_scene *rs = build_scene_or_fail(text, NULL);
        free(text);
        double e = centre_rel_mse(rs, exact, 32, 32, 1, &mean);
        print_message("spacing %g voxels: relMSE %.3g against shadow rays (image mean %.4g)\n",
                      spacings[k], e, mean);
        assert_true(e < prev);
        prev = e;
        render_scene_destroy(rs);
    }
    assert_true(mean > 0.01); /* the image is not black */
    assert_true(prev < 1e-5);
    render_scene_destroy(exact);
}

static void expect_refused(const char *text, const char *what)
{
    char msg[1024];
    build_scene_expect_error(text, msg, sizeof msg);
    print_message("%s\n", msg);
    assert_non_null(strstr(msg, "test.pbrt:"));
    assert_non_null(strstr(msg, "shadowcache"));
    assert_non_null(strstr(msg, what));
}

/* Refused where it would change nothing, or could not hold. */
static void test_refusals(void **state)
{
    (void)state;
    char *text = box_scene(-1.0, false, false);
    expect_refused(text, ">= 0");
    free(text);
    text = box_scene(1.0, false, false);
    char *p = strstr(text, "LightSource \"distant\""), *end = p ? strchr(p, '\n') : NULL;
    assert_non_null(end);
    char *point = sfmt("%.*sLightSource \"point\" \"point3 from\" [0 3 0] \"rgb I\" [1 1 1]%s",
                       (int)(p - text), text, end);
    expect_refused(point, "no distant light");
    free(point);
    char *moving = sfmt("%.*sActiveTransform EndTime\nTranslate 0.5 0 0\nActiveTransform All\n%s",
                        (int)(strstr(text, "MakeNamedMedium") - text), text,
                        strstr(text, "MakeNamedMedium"));
    expect_refused(moving, "static scene");
    free(moving);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_form),
        cmocka_unit_test(test_converges_to_shadow_rays),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
