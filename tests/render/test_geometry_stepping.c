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

/* pbrt-v4's partial sphere: a ray down the axis of a sphere cut at zmax 0.5
 * passes the opening and meets the inside at z = -1; one cut at phimax 90
 * is hit only where 0 <= phi <= 90 degrees; every hit lies on the part. */
static void test_partial_sphere(void **state)
{
    (void)state;
    render_scene *rs = build("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                             "Shape \"sphere\" \"float zmax\" 0.5\n"
                             "Translate 20 0 0\n"
                             "Shape \"sphere\" \"float phimax\" 90\n");
    const geometry *g = render_scene_geometry(rs);
    geom_hit h;
    assert_true(geometry_intersect(g, v3(0, 0, 5), v3(0, 0, -1), 0.0, INFINITY, 0.0, &h));
    assert_true(fabs(h.p.z + 1.0) < 1e-9);
    assert_true(geometry_intersect(g, v3(0, 0, -5), v3(0, 0, 1), 0.0, INFINITY, 0.0, &h));
    assert_true(fabs(h.p.z + 1.0) < 1e-9); /* from below: the bottom is there */
    rng r = rng_seeded(11);
    int hits = 0;
    for (int i = 0; i < 20000; ++i) {
        vec3 dir = sample_uniform_sphere(v2(rng_uniform(&r), rng_uniform(&r)));
        vec3 o = v3_add(v3(20, 0, 0), v3_scale(dir, 4.0));
        vec3 target = v3(20.0 + rng_uniform(&r) - 0.5, rng_uniform(&r) - 0.5,
                         rng_uniform(&r) - 0.5);
        if (!geometry_intersect(g, o, v3_normalize(v3_sub(target, o)), 0.0, 10.0, 0.0, &h))
            continue;
        vec3 q = v3_sub(h.p, v3(20, 0, 0));
        if (!(fabs(v3_length(q) - 1.0) < 1e-9) || !(q.x >= -1e-9 && q.y >= -1e-9))
            fail_msg("hit at %g %g %g (r %.12g)", q.x, q.y, q.z, v3_length(q));
        assert_true(q.x >= -1e-9 && q.y >= -1e-9); /* phi in [0, 90] degrees */
        ++hits;
    }
    assert_true(hits > 1000);
    render_scene_destroy(rs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_far_rays_cross_each_face_once),
        cmocka_unit_test(test_partial_sphere),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
