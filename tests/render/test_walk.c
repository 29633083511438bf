/* The walk through surfaces and medium interfaces (integrator/walk.h) on
 * built scenes: the segments of a ray through nested interface boxes, in
 * order, with their media; opaque hits stopped at, stepped over or gone
 * through; hits behind t_fill; and the crossing limit, exactly at it and one
 * past it. */
#include "media_test_util.h"

#include "integrator/walk.h"

/* Media "a" (index 0) and "b" (1); box A = [-2, 2]^3 holds a, box B =
 * [-1, 1]^3 inside it holds b; `extra` follows. */
static render_scene *nested_boxes(const char *extra)
{
    char *a = box_mesh(v3(-2, -2, -2), v3(2, 2, 2)), *b = box_mesh(v3(-1, -1, -1), v3(1, 1, 1));
    char *text = sfmt("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                      "MakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n"
                      "MakeNamedMedium \"b\" \"string type\" \"homogeneous\"\n"
                      "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"a\" \"\"\n%s"
                      "MediumInterface \"b\" \"a\"\n%sAttributeEnd\n%s",
                      a, b, extra);
    render_scene *rs = build(text);
    free(text);
    free(a);
    free(b);
    return rs;
}

#define MAX_SEGS 200

typedef struct {
    walk_segment seg[MAX_SEGS];
    int n;
    bool lost;
} walked;

/* Every segment of the walk, going on past every hit. */
static walked walk_all(ray_walk *w)
{
    walked out = {.n = 0};
    while (out.n < MAX_SEGS && walk_next(w, &out.seg[out.n]))
        out.n++;
    assert_true(out.n < MAX_SEGS);
    out.lost = walk_lost(w);
    return out;
}

/* Ends within `tol` relatively: exact ends lie on the surface in double,
 * Embree's t in float. */
static void expect_seg_tol(const walk_segment *s, double t0, double t1, int medium, bool hit,
                           bool opaque, double tol)
{
    if (!(fabs(s->t0 - t0) <= tol * fmax(1.0, fabs(t0)) &&
          (s->t1 == t1 || fabs(s->t1 - t1) <= tol * fmax(1.0, fabs(t1))) &&
          s->medium == medium && s->hit == hit && s->opaque == opaque))
        fail_msg("segment [%.17g, %.17g] medium %d hit %d opaque %d; want [%g, %g] %d %d %d",
                 s->t0, s->t1, s->medium, s->hit, s->opaque, t0, t1, medium, hit, opaque);
}

static void expect_seg(const walk_segment *s, double t0, double t1, int medium, bool hit,
                       bool opaque)
{
    expect_seg_tol(s, t0, t1, medium, hit, opaque, 1e-12);
}

/* From x = -5 along +x: vacuum, a, b, a, vacuum; each segment begins
 * exactly where the last ended. The same walk without exact ends yields the
 * same media and hits (the ends then Embree's float t). */
static void test_nested_interfaces(void **state)
{
    (void)state;
    render_scene *rs = nested_boxes("");
    const geometry *g = render_scene_geometry(rs);
    vec3 o = v3(-5, 0.1, 0.3), d = v3(1, 0, 0);
    for (int exact = 0; exact < 2; ++exact) {
        ray_walk w;
        walk_start(&w, g, o, d, 0.0, 0.0, INFINITY, 0.0, -1, exact ? WALK_EXACT_ENDS : 0u);
        walked r = walk_all(&w);
        assert_false(r.lost);
        assert_int_equal(r.n, 5);
        double tol = exact ? 1e-12 : 1e-6;
        expect_seg_tol(&r.seg[0], 0, 3, -1, true, false, tol);
        expect_seg_tol(&r.seg[1], 3, 4, 0, true, false, tol);
        expect_seg_tol(&r.seg[2], 4, 6, 1, true, false, tol);
        expect_seg_tol(&r.seg[3], 6, 7, 0, true, false, tol);
        expect_seg_tol(&r.seg[4], 7, INFINITY, -1, false, false, tol);
        for (int i = 1; i < r.n; ++i)
            assert_true(r.seg[i].t0 == r.seg[i - 1].t1);
        /* Over: no segment more. */
        walk_segment s;
        assert_false(walk_next(&w, &s));
        assert_false(walk_lost(&w));
    }
    /* A ray that leaves the scene in a medium ends at HZ_FAR_COORD; from the
     * centre the media are b, a, then vacuum to infinity. */
    ray_walk w;
    walk_start(&w, g, v3(6, 0.1, 0.3), d, 0.0, 0.0, INFINITY, 0.0, 0, WALK_EXACT_ENDS);
    walked r = walk_all(&w);
    assert_int_equal(r.n, 1);
    expect_seg(&r.seg[0], 0, HZ_FAR_COORD - 6, 0, false, false);
    walk_start(&w, g, v3(0, 0.1, 0.3), d, 0.0, 0.0, INFINITY, 0.0, 1,
               WALK_EXACT_ENDS | WALK_CONVEX_START);
    r = walk_all(&w);
    assert_int_equal(r.n, 3);
    expect_seg(&r.seg[0], 0, 1, 1, true, false);
    expect_seg(&r.seg[1], 1, 2, 0, true, false);
    expect_seg(&r.seg[2], 2, INFINITY, -1, false, false);
    /* tmax bounds the last segment. */
    walk_start(&w, g, v3(0, 0.1, 0.3), d, 0.0, 0.0, 1.5, 0.0, 1, WALK_EXACT_ENDS);
    r = walk_all(&w);
    assert_int_equal(r.n, 2);
    expect_seg(&r.seg[1], 1, 1.5, 0, false, false);
    render_scene_destroy(rs);
}

/* An opaque box [3, 4] x [-1, 1]^2 behind the nested boxes: its hit ends a
 * segment as an interface's would; stepping over it keeps the medium and
 * the segment's start, going on crosses it. */
static void test_opaque_hits(void **state)
{
    (void)state;
    char *box = box_mesh(v3(3, -1, -1), v3(4, 1, 1));
    render_scene *rs = nested_boxes(box);
    const geometry *g = render_scene_geometry(rs);
    vec3 o = v3(-5, 0.1, 0.3), d = v3(1, 0, 0);
    ray_walk w;
    walk_segment s;
    walk_start(&w, g, o, d, 0.0, 0.0, INFINITY, 0.0, -1, WALK_EXACT_ENDS);
    for (int i = 0; i < 5; ++i)
        assert_true(walk_next(&w, &s));
    expect_seg(&s, 7, 8, -1, true, true);
    assert_true(fabs(s.h.p.x - 3.0) < 1e-6);
    /* Stepped over: the front face and the back face, one segment from 7. */
    walk_step_over(&w);
    assert_true(walk_next(&w, &s));
    expect_seg(&s, 7, 9, -1, true, true);
    walk_step_over(&w);
    assert_true(walk_next(&w, &s));
    expect_seg(&s, 7, INFINITY, -1, false, false);
    assert_false(walk_next(&w, &s));
    /* Gone through (the shadow cache's columns): [8, 9] and on. */
    walk_start(&w, g, o, d, 0.0, 0.0, INFINITY, 0.0, -1, WALK_EXACT_ENDS);
    walked r = walk_all(&w);
    assert_int_equal(r.n, 7);
    expect_seg(&r.seg[5], 8, 9, -1, true, true);
    expect_seg(&r.seg[6], 9, INFINITY, -1, false, false);
    render_scene_destroy(rs);
    free(box);
}

/* From the centre in b, the first segment filled from t_fill = 1.5, past
 * B's face at 1: the path's rays step over that hit (into a), the shadow
 * walks yield an empty segment in b there. */
static void test_hits_behind_fill(void **state)
{
    (void)state;
    render_scene *rs = nested_boxes("");
    const geometry *g = render_scene_geometry(rs);
    vec3 o = v3(0, 0.1, 0.3), d = v3(1, 0, 0);
    ray_walk w;
    walk_start(&w, g, o, d, 0.0, 1.5, INFINITY, 0.0, 1, WALK_EXACT_ENDS | WALK_PASS_BEHIND);
    walked r = walk_all(&w);
    assert_int_equal(r.n, 2);
    expect_seg(&r.seg[0], 1.5, 2, 0, true, false);
    expect_seg(&r.seg[1], 2, INFINITY, -1, false, false);
    walk_start(&w, g, o, d, 0.0, 1.5, INFINITY, 0.0, 1, WALK_EXACT_ENDS);
    r = walk_all(&w);
    assert_int_equal(r.n, 3);
    expect_seg(&r.seg[0], 1.5, 1.5, 1, true, false);
    expect_seg(&r.seg[1], 1.5, 2, 0, true, false);
    expect_seg(&r.seg[2], 2, INFINITY, -1, false, false);
    render_scene_destroy(rs);
}

/* `boxes` interface boxes [2i, 2i + 1] x [-1, 1]^2 along x, each holding
 * medium "m". */
static render_scene *box_row(int boxes)
{
    size_t cap = 1 << 16, len = 0;
    char *shapes = malloc(cap);
    assert_non_null(shapes);
    shapes[0] = '\0';
    for (int i = 0; i < boxes; ++i) {
        char *b = box_mesh(v3(2 * i, -1, -1), v3(2 * i + 1, 1, 1));
        size_t n = strlen(b);
        if (len + n + 1 > cap) {
            cap = 2 * (len + n + 1);
            shapes = realloc(shapes, cap);
            assert_non_null(shapes);
        }
        memcpy(shapes + len, b, n + 1);
        len += n;
        free(b);
    }
    char *text = sfmt("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                      "MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
                      "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"m\" \"\"\n%s"
                      "AttributeEnd\n",
                      shapes);
    render_scene *rs = build(text);
    free(text);
    free(shapes);
    return rs;
}

/* WALK_MAX_CROSSINGS interfaces are crossed; the next one loses the ray
 * after the segment that ends at it. */
static void test_crossing_limit(void **state)
{
    (void)state;
    assert_int_equal(WALK_MAX_CROSSINGS % 2, 0);
    int boxes = WALK_MAX_CROSSINGS / 2;
    for (int extra = 0; extra < 2; ++extra) {
        render_scene *rs = box_row(boxes + extra);
        ray_walk w;
        walk_start(&w, render_scene_geometry(rs), v3(-1, 0.1, 0.3), v3(1, 0, 0), 0.0, 0.0,
                   INFINITY, 0.0, -1, WALK_EXACT_ENDS);
        walked r = walk_all(&w);
        /* A segment before each crossing, and one after the last. */
        assert_int_equal(r.n, WALK_MAX_CROSSINGS + 1);
        for (int i = 0; i < WALK_MAX_CROSSINGS; ++i)
            expect_seg(&r.seg[i], i, i + 1, i % 2 ? 0 : -1, true, false);
        if (extra) { /* the last yielded ends at the 65th face: no step past it */
            assert_true(r.lost);
            expect_seg(&r.seg[WALK_MAX_CROSSINGS], WALK_MAX_CROSSINGS,
                       WALK_MAX_CROSSINGS + 1, -1, true, false);
        } else {
            assert_false(r.lost);
            expect_seg(&r.seg[WALK_MAX_CROSSINGS], WALK_MAX_CROSSINGS, INFINITY, -1,
                       false, false);
        }
        render_scene_destroy(rs);
    }
}

/* Hits stepped over count as crossings: the ray is lost at the same one
 * (stepping over interfaces is the caller's choice too: the medium stays
 * vacuum and every segment begins at 0). */
static void test_crossing_limit_stepping_over(void **state)
{
    (void)state;
    for (int extra = 0; extra < 2; ++extra) {
        render_scene *rs = box_row(WALK_MAX_CROSSINGS / 2 + extra);
        ray_walk w;
        walk_segment s;
        walk_start(&w, render_scene_geometry(rs), v3(-1, 0.1, 0.3), v3(1, 0, 0), 0.0, 0.0,
                   INFINITY, 0.0, -1, WALK_EXACT_ENDS);
        int n = 0;
        bool left = false;
        while (walk_next(&w, &s)) {
            ++n;
            expect_seg(&s, 0, s.hit ? n : INFINITY, -1, s.hit, false);
            if (!s.hit) {
                left = true;
                break;
            }
            walk_step_over(&w);
        }
        assert_int_equal(n, WALK_MAX_CROSSINGS + 1);
        assert_int_equal(left, !extra);
        assert_int_equal(walk_lost(&w), extra);
        render_scene_destroy(rs);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nested_interfaces),
        cmocka_unit_test(test_opaque_hits),
        cmocka_unit_test(test_hits_behind_fill),
        cmocka_unit_test(test_crossing_limit),
        cmocka_unit_test(test_crossing_limit_stepping_over),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
