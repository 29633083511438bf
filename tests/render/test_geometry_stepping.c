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

/* Rays that skip Embree (they miss the box around every shape) lose no hit:
 * rays aimed just inside the edges and corners of a box mesh, from outside,
 * hit it, and rays aimed at the tops of two spheres hit at their tangent
 * points; an empty scene is hit by nothing. */
static void test_world_box_keeps_grazing_hits(void **state)
{
    (void)state;
    vec3 lo = v3(-0.6, 0.1, -0.3), hi = v3(0.7, 2.2, 0.9);
    char *box = box_mesh(lo, hi);
    char *text = sfmt("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n%s"
                      "Translate 3 0 0\nShape \"sphere\" \"float radius\" 0.7\n"
                      "Translate 0 -7 0\nShape \"sphere\" \"float radius\" 0.3\n",
                      box);
    render_scene *rs = build(text);
    const geometry *g = render_scene_geometry(rs);
    rng r = rng_seeded(5);
    geom_hit h;
    for (int i = 0; i < 20000; ++i) {
        /* A point on an edge of the box (two coordinates on faces), moved
         * inward by 1e-5 of the box along each face's normal. */
        double u[3] = {rng_uniform(&r), rng_uniform(&r), rng_uniform(&r)};
        int free_axis = i % 3;
        double t[3], l3[3] = {lo.x, lo.y, lo.z}, h3[3] = {hi.x, hi.y, hi.z};
        for (int a = 0; a < 3; ++a) {
            double in = 1e-5 * (h3[a] - l3[a]);
            if (a == free_axis)
                t[a] = l3[a] + u[a] * (h3[a] - l3[a]);
            else
                t[a] = u[a] < 0.5 ? l3[a] + in : h3[a] - in;
        }
        if (i % 7 == 0) /* a corner */
            t[free_axis] = u[free_axis] < 0.5 ? l3[free_axis] + 1e-5 : h3[free_axis] - 1e-5;
        vec3 target = v3(t[0], t[1], t[2]);
        /* From outside: away from the box's centre, at 5 to 50 units. */
        vec3 out = v3_sub(target, v3_scale(v3_add(lo, hi), 0.5));
        vec3 dir = sample_uniform_sphere(v2(rng_uniform(&r), rng_uniform(&r)));
        if (v3_dot(dir, out) < 0.0)
            dir = v3_neg(dir);
        vec3 o = v3_add(target, v3_scale(dir, 5.0 + 45.0 * rng_uniform(&r)));
        if (!geometry_intersect(g, o, v3_neg(dir), 0.0, INFINITY, 0.0, &h))
            fail_msg("ray %d at %.9g %.9g %.9g: no hit", i, target.x, target.y, target.z);
        assert_true(geometry_occluded(g, o, v3_neg(dir), v3_length(v3_sub(target, o)) + 1e-3, 0.0));
    }
    /* Tangent to the spheres at their tops, from far away along z. */
    assert_true(geometry_intersect(g, v3(3, 0.7 - 1e-5, -40), v3(0, 0, 1), 0.0, INFINITY, 0.0, &h));
    assert_true(fabs(h.p.z) < 1e-2);
    assert_true(geometry_intersect(g, v3(3, -6.7 - 1e-5, 30), v3(0, 0, -1), 0.0, INFINITY, 0.0,
                                   &h));
    assert_true(geometry_occluded(g, v3(3, -6.7 - 1e-5, 30), v3(0, 0, -1), 60.0, 0.0));
    assert_false(geometry_intersect(g, v3(3, -6.7 + 1e-5, 30), v3(0, 0, -1), 0.0, INFINITY, 0.0,
                                    &h)); /* above the small sphere, below the big one */
    render_scene_destroy(rs);
    free(text);
    free(box);

    rs = build("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n");
    g = render_scene_geometry(rs);
    assert_false(geometry_intersect(g, v3(0, 0, 0), v3(0, 0, 1), 0.0, INFINITY, 0.0, &h));
    assert_false(geometry_occluded(g, v3(0, 0, 0), v3(0, 0, 1), INFINITY, 0.0));
    render_scene_destroy(rs);
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

/* Two boxes in one mesh ([lo, hi] and [lo, hi] moved by `shift`): not
 * convex, so a ray leaving one box may still meet the other. */
static char *two_box_mesh(vec3 lo, vec3 hi, vec3 shift)
{
    static const int quads[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                    {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    char pts[2048] = "", ids[1024] = "";
    size_t np = 0, ni = 0;
    for (int b = 0; b < 2; ++b) {
        vec3 s = b ? shift : v3(0, 0, 0);
        for (int i = 0; i < 8; ++i)
            np += (size_t)snprintf(pts + np, sizeof pts - np, "%g %g %g ",
                                   (i & 1 ? hi.x : lo.x) + s.x, (i & 2 ? hi.y : lo.y) + s.y,
                                   (i & 4 ? hi.z : lo.z) + s.z);
        for (int f = 0; f < 6; ++f) {
            const int *q = quads[f];
            ni += (size_t)snprintf(ids + ni, sizeof ids - ni, "%d %d %d %d %d %d ", 8 * b + q[0],
                                   8 * b + q[1], 8 * b + q[2], 8 * b + q[0], 8 * b + q[2],
                                   8 * b + q[3]);
        }
    }
    return sfmt("Shape \"trianglemesh\" \"integer indices\" [%s] \"point3 P\" [%s]\n", ids, pts);
}

/* A ray that leaves a convex interface mesh for good skips Embree when it
 * misses every other shape's box (geometry_intersect_past): along walks of
 * random rays through a convex box, a sphere, a floor and a non-convex mesh
 * of two boxes, every query answers as geometry_intersect does (hit, shape
 * and t); the convex box is left for good exactly where the walk goes on
 * outside it, the non-convex mesh never. */
static void test_left_for_good_keeps_every_hit(void **state)
{
    (void)state;
    vec3 lo = v3(-1.0, -0.5, -0.8), hi = v3(0.9, 1.5, 1.1);
    char *box = box_mesh(lo, hi);
    char *pair = two_box_mesh(v3(-0.5, -0.5, 3.0), v3(0.5, 0.5, 3.6), v3(0.0, 0.0, 1.4));
    char *text = sfmt("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                      "MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
                      "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"m\" \"\"\n%s"
                      "AttributeEnd\n"
                      "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"m\" \"\"\n%s"
                      "AttributeEnd\n"
                      "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
                      "  \"point3 P\" [-20 -3 -20  20 -3 -20  20 -3 20  -20 -3 20]\n"
                      "AttributeBegin\nTranslate 3 0.5 0\nShape \"sphere\" \"float radius\" 0.7\n"
                      "AttributeEnd\n",
                      box, pair);
    render_scene *rs = build(text);
    const geometry *g = render_scene_geometry(rs);
    rng r = rng_seeded(13);
    int left_box = 0, skipped = 0, box_exits = 0, exits = 0;
    for (int i = 0; i < 20000; ++i) {
        /* Half the rays start inside the convex box, half anywhere near. */
        vec3 o = i % 2 ? v3(lo.x + (hi.x - lo.x) * rng_uniform(&r),
                            lo.y + (hi.y - lo.y) * rng_uniform(&r),
                            lo.z + (hi.z - lo.z) * rng_uniform(&r))
                       : v3(10.0 * rng_uniform(&r) - 5.0, 6.0 * rng_uniform(&r) - 2.5,
                            10.0 * rng_uniform(&r) - 4.0);
        vec3 w = sample_uniform_sphere(v2(rng_uniform(&r), rng_uniform(&r)));
        double tmin = 0.0;
        /* Every ray starts with the hint of a ray in the box's medium, those
         * outside the box too: geometry_intersect_past checks it. */
        geom_past past = {NULL, geometry_convex_around(g, 0)};
        assert_non_null(past.within);
        for (int k = 0; k < 10; ++k) {
            geom_hit ref, h;
            bool want = geometry_intersect(g, o, w, tmin, INFINITY, 0.0, &ref);
            bool got = geometry_intersect_past(g, past, o, w, tmin, INFINITY, 0.0, &h);
            /* A convex mesh's exit is found in double, where Embree's t is
             * a float (off by up to ~1e-6 on grazing rays); the point and
             * the normal are the plane's either way. */
            if (got != want ||
                (got && (h.shape != ref.shape || !(fabs(h.t - ref.t) <= 1e-5 * (1.0 + ref.t)) ||
                         !(v3_length(v3_sub(h.p, ref.p)) <= 1e-12 * (1.0 + ref.t)) ||
                         !(v3_length(v3_sub(h.ng, ref.ng)) <= 1e-12))))
                fail_msg("ray %d crossing %d: %d against %d (t %.17g against %.17g)", i, k, got,
                         want, got ? h.t : 0.0, want ? ref.t : 0.0);
            skipped += past.left && !want;
            exits += past.within && got && h.shape == past.within;
            if (!got)
                break;
            tmin = geometry_step_past(&h, o, w);
            past = geometry_past(&h, w);
            const geom_shape *left = past.left;
            /* Where the walk goes on: outside the convex box or in it, a
             * micrometre past the hit (the plane's point, in double), the
             * box's faces where its float vertices put them. A millimetre
             * took a ray that enters near an edge and leaves through the
             * next face for one leaving. */
            vec3 q = v3_add(h.p, v3_scale(w, 1e-6 / v3_length(w)));
            bool outside = q.x < (float)lo.x || q.x > (float)hi.x || q.y < (float)lo.y ||
                           q.y > (float)hi.y || q.z < (float)lo.z || q.z > (float)hi.z;
            /* (The mesh's vertices are floats.) */
            bool on_box = h.p.z < 2.9 && v3_length(v3_sub(h.p, v3(3, 0.5, 0))) > 0.71 &&
                          h.p.y > -2.9;
            if (left ? !(on_box && outside) : on_box && outside)
                fail_msg("ray %d at %g %g %g: left for good %d, on the box %d, outside %d", i,
                         h.p.x, h.p.y, h.p.z, left != NULL, on_box, outside);
            left_box += left != NULL;
            box_exits += on_box && outside;
        }
    }
    /* Every exit of the convex box is left for good, and most walks then
     * skip Embree. */
    assert_int_equal(left_box, box_exits);
    assert_true(left_box > 10000);
    assert_true(skipped > 5000);
    print_message("left for good %d, skipped %d, exits found %d\n", left_box, skipped, exits);
    assert_true(exits > 10000);
    render_scene_destroy(rs);
    free(text);
    free(pair);
    free(box);
}

/* A ray that knows nothing and misses the box of every other shape finds
 * its entry into the largest convex interface mesh from the planes
 * (geometry_intersect_past): random rays from around a convex box, half of
 * them aimed at it, with a sphere beside it, answer as geometry_intersect
 * does (hit, shape, point and t). An entry found from the planes shows in
 * its t, a double where Embree's is a float. */
static void test_entry_from_planes(void **state)
{
    (void)state;
    vec3 lo = v3(-1.0, -0.5, -0.8), hi = v3(0.9, 1.5, 1.1);
    char *box = box_mesh(lo, hi);
    char *text = sfmt("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                      "MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
                      "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"m\" \"\"\n%s"
                      "AttributeEnd\n"
                      "AttributeBegin\nTranslate 3 0.5 0\nShape \"sphere\" \"float radius\" 0.7\n"
                      "AttributeEnd\n",
                      box);
    render_scene *rs = build(text);
    const geometry *g = render_scene_geometry(rs);
    rng r = rng_seeded(29);
    const geom_shape *convex = geometry_convex_around(g, 0);
    assert_non_null(convex);
    int hits = 0, box_hits = 0, from_planes = 0, misses = 0;
    for (int i = 0; i < 40000; ++i) {
        vec3 o = v3(12.0 * rng_uniform(&r) - 6.0, 8.0 * rng_uniform(&r) - 3.5,
                    12.0 * rng_uniform(&r) - 6.0);
        vec3 w = sample_uniform_sphere(v2(rng_uniform(&r), rng_uniform(&r)));
        if (i % 2) {
            vec3 aim = v3(lo.x + (hi.x - lo.x) * rng_uniform(&r),
                          lo.y + (hi.y - lo.y) * rng_uniform(&r),
                          lo.z + (hi.z - lo.z) * rng_uniform(&r));
            w = v3_scale(v3_sub(aim, o), 0.5 + rng_uniform(&r));
        }
        double tmin = i % 3 ? 0.0 : 0.1 * rng_uniform(&r);
        geom_hit ref, h;
        bool want = geometry_intersect(g, o, w, tmin, INFINITY, 0.0, &ref);
        bool got = geometry_intersect_past(g, (geom_past){NULL, NULL}, o, w, tmin, INFINITY, 0.0,
                                           &h);
        if (got != want ||
            (got && (h.shape != ref.shape || h.prim != ref.prim ||
                     !(fabs(h.t - ref.t) <= 1e-5 * (1.0 + ref.t)) ||
                     !(v3_length(v3_sub(h.p, ref.p)) <= 1e-12 * (1.0 + ref.t)) ||
                     !(v3_length(v3_sub(h.ng, ref.ng)) <= 1e-12))))
            fail_msg("ray %d: %d against %d (t %.17g against %.17g)", i, got, want,
                     got ? h.t : 0.0, want ? ref.t : 0.0);
        hits += got;
        misses += !got;
        box_hits += got && h.shape == convex;
        from_planes += got && h.shape == convex && (double)(float)h.t != h.t;
    }
    print_message("hits %d (the box %d, from the planes %d), misses %d\n", hits, box_hits,
                  from_planes, misses);
    assert_true(box_hits > 15000);
    /* All but the rays from inside the box and those whose way passes the
     * sphere's box (95% here). */
    assert_true(from_planes > 0.9 * box_hits);
    assert_true(misses > 10000);
    render_scene_destroy(rs);
    free(text);
    free(box);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_far_rays_cross_each_face_once),
        cmocka_unit_test(test_partial_sphere),
        cmocka_unit_test(test_world_box_keeps_grazing_hits),
        cmocka_unit_test(test_left_for_good_keeps_every_hit),
        cmocka_unit_test(test_entry_from_planes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
