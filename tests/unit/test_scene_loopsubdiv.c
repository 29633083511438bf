/* Loop subdivision (scene/loopsubdiv.h): counts (each level adds a vertex
 * per edge and splits each triangle in four), a flat mesh stays flat with
 * its normal, the boundary rule moves boundary vertices along it, a closed
 * mesh shrinks toward its centroid but stays symmetric, and non-manifold or
 * bad input is refused. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "scene/loopsubdiv.h"

typedef struct {
    double *p, *n;
    uint32_t *idx;
    size_t nv, nt;
} mesh;

static void subdivide(const double *p, size_t nv, const uint32_t *idx, size_t nt, int levels,
                      mesh *m)
{
    hz_error err;
    if (loop_subdivide(p, nv, idx, nt, levels, &m->p, &m->n, &m->nv, &m->idx, &m->nt, &err) !=
        HZ_OK)
        fail_msg("%s", err.message);
}

static void mesh_free(mesh *m)
{
    free(m->p);
    free(m->n);
    free(m->idx);
}

static const double tetra_p[12] = {1, 1, 1, -1, -1, 1, -1, 1, -1, 1, -1, -1};
static const uint32_t tetra_i[12] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};

static void test_counts_and_symmetry(void **state)
{
    (void)state;
    /* Tetrahedron: V 4, E 6, F 4 -> V 10, E 24, F 16 -> V 34, F 64. */
    mesh m;
    subdivide(tetra_p, 4, tetra_i, 4, 1, &m);
    assert_int_equal(m.nv, 10);
    assert_int_equal(m.nt, 16);
    mesh_free(&m);
    subdivide(tetra_p, 4, tetra_i, 4, 2, &m);
    assert_int_equal(m.nv, 34);
    assert_int_equal(m.nt, 64);
    /* Every original vertex (valence 3 at every level, symmetric) ends at the
     * same distance from the centre, inside the tetrahedron's corners, and
     * its normal points outward along it. */
    double r0 = sqrt(m.p[0] * m.p[0] + m.p[1] * m.p[1] + m.p[2] * m.p[2]);
    assert_true(r0 > 0.2 && r0 < sqrt(3.0));
    for (int v = 0; v < 4; ++v) {
        const double *q = &m.p[3 * v], *n = &m.n[3 * v];
        double r = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        assert_true(fabs(r - r0) < 1e-12);
        double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        double c = (q[0] * n[0] + q[1] * n[1] + q[2] * n[2]) / (r * ln);
        assert_true(fabs(c) > 0.999999); /* along the radius (the faces wind inward) */
    }
    mesh_free(&m);
}

/* A flat grid with a boundary: every vertex stays at z = 0 with normal +z,
 * and the boundary rule moves boundary vertices along the boundary. */
static void test_flat_and_boundary(void **state)
{
    (void)state;
    const double p[27] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 0, 2, 0, 1, 2, 0, 2, 2, 0};
    const uint32_t idx[24] = {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 3, 4, 7, 3, 7, 6, 4, 5, 8, 4, 8, 7};
    mesh m;
    subdivide(p, 9, idx, 8, 3, &m);
    double cx = 0.0, cy = 0.0;
    for (size_t v = 0; v < m.nv; ++v) {
        assert_true(fabs(m.p[3 * v + 2]) < 1e-12);
        const double *n = &m.n[3 * v];
        double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        assert_true(n[2] / ln > 0.999999999);
        cx += m.p[3 * v] / (double)m.nv;
        cy += m.p[3 * v + 1] / (double)m.nv;
    }
    /* The grid's symmetry survives: its vertices centre on (1, 1). */
    assert_true(fabs(cx - 1.0) < 1e-12 && fabs(cy - 1.0) < 1e-12);
    /* The boundary rule pulls the middle of the left edge along the edge
     * only: it keeps y = 1 and moves inside by the corners' rounding. */
    assert_true(fabs(m.p[3 * 3 + 1] - 1.0) < 1e-12 && m.p[3 * 3] >= 0.0 && m.p[3 * 3] < 0.05);
    assert_int_equal(m.nt, 8 * 64);
    mesh_free(&m);
}

static void test_refusals(void **state)
{
    (void)state;
    mesh m;
    hz_error err;
    /* Three triangles on one edge. */
    const double p[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1};
    const uint32_t idx[9] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    assert_int_equal(loop_subdivide(p, 5, idx, 3, 1, &m.p, &m.n, &m.nv, &m.idx, &m.nt, &err),
                     HZ_ERROR);
    assert_non_null(strstr(err.message, "shared by 3 triangles"));
    const uint32_t bad[3] = {0, 1, 7};
    assert_int_equal(loop_subdivide(p, 5, bad, 1, 1, &m.p, &m.n, &m.nv, &m.idx, &m.nt, &err),
                     HZ_ERROR);
    assert_non_null(strstr(err.message, "out of range"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counts_and_symmetry),
        cmocka_unit_test(test_flat_and_boundary),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
