/* Stepping past surfaces far from the origin: every hit found once. A ray
 * from ~60 units away crossing an interface box hits each face once; before
 * Embree's tnear was rounded up, a step past a hit could round back onto the
 * hit's own float t and find it again and again (paths were dropped after 64
 * "crossings", 3-5 per 4M samples on scenes/moving-smoke.pbrt with volpath). */
#include "media_test_util.h"

#include "core/rng.h"
#include "core/sampling.h"

static void test_far_rays_cross_each_face_once(void **state)
{
    (void)state;
    char *box = box_mesh(v3(-0.6, -0.25, -0.6), v3(0.5, 2.2, 0.5));
    /* The camera at the world origin: render space is world space. */
    char *text = sfmt("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                      "MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
                      "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"m\" \"\"\n%s"
                      "AttributeEnd\n",
                      box);
    render_scene *rs = build(text);
    const geometry *g = render_scene_geometry(rs);
    rng r = rng_seeded(7);
    int rays = 0;
    for (int i = 0; i < 20000; ++i) {
        /* A point inside the box, and an origin 30-80 units away from it. */
        vec3 target = v3(-0.55 + 1.0 * rng_uniform(&r), -0.2 + 2.3 * rng_uniform(&r),
                         -0.55 + 1.0 * rng_uniform(&r));
        vec3 dir = sample_uniform_sphere(v2(rng_uniform(&r), rng_uniform(&r)));
        double dist = 30.0 + 50.0 * rng_uniform(&r);
        vec3 o = v3_add(target, v3_scale(dir, dist)), w = v3_neg(dir);
        double tmin = 0.0;
        int hits = 0;
        geom_hit h;
        while (hits < 10 && geometry_intersect(g, o, w, tmin, INFINITY, 0.0, &h)) {
            double next = geometry_step_past(&h, o, w);
            assert_true(next > tmin && next > h.t);
            tmin = next;
            ++hits;
        }
        /* In and out: two faces (edges may count two triangles at one t). */
        if (hits < 2 || hits > 3)
            fail_msg("ray %d from %.3f %.3f %.3f: %d hits", i, o.x, o.y, o.z, hits);
        ++rays;
    }
    assert_int_equal(rays, 20000);
    render_scene_destroy(rs);
    free(text);
    free(box);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_far_rays_cross_each_face_once),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
