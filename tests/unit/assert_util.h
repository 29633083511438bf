/* Tolerance assertions and a seeded random stream shared by the unit tests. */
#ifndef HAZE_TESTS_UNIT_ASSERT_UTIL_H
#define HAZE_TESTS_UNIT_ASSERT_UTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "core/rng.h"
#include "core/vec.h"

static inline void assert_near(double got, double want, double tol)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("got %.17g, want %.17g (tolerance %g)", got, want, tol);
}

static inline void assert_v3_near(vec3 got, vec3 want, double tol)
{
    assert_near(got.x, want.x, tol);
    assert_near(got.y, want.y, tol);
    assert_near(got.z, want.z, tol);
}

/* A local, seeded stream (tests must be deterministic): returns a double in
 * [0, 1) and advances *s. */
static inline double rng_next(uint64_t *s)
{
    rng r = rng_seeded(*s);
    double v = rng_uniform(&r);
    *s = r.state;
    return v;
}

#endif
