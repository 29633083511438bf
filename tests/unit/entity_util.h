/* Builds scene entities (a type and parameters declared at test.pbrt:3) the way
 * the parser does, without parsing, for unit tests of the *_create functions. */
#ifndef HAZE_TESTS_UNIT_ENTITY_UTIL_H
#define HAZE_TESTS_UNIT_ENTITY_UTIL_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "scene/params.h"

static inline char *dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    assert_non_null(d);
    memcpy(d, s, n);
    return d;
}

static inline void entity_init(scene_entity *e, const char *type)
{
    memset(e, 0, sizeof *e);
    e->type = dup_str(type);
    e->loc = (file_loc){"test.pbrt", 3, 1, NULL};
    params_init(&e->params, e->loc);
}

static inline void entity_free(scene_entity *e)
{
    params_free(&e->params);
    free(e->type);
}

static inline void add_nums(scene_entity *e, param_type t, const char *name, const double *v,
                            size_t n)
{
    param p;
    memset(&p, 0, sizeof p);
    p.type = t;
    p.name = dup_str(name);
    p.loc = (file_loc){"test.pbrt", 3, 10, NULL};
    p.count = n;
    p.nums = malloc(n * sizeof *p.nums);
    assert_non_null(p.nums);
    memcpy(p.nums, v, n * sizeof *v);
    assert_int_equal(params_add(&e->params, p, NULL), HZ_OK);
}

static inline void add_float(scene_entity *e, const char *name, double v)
{
    add_nums(e, PARAM_FLOAT, name, &v, 1);
}

static inline void add_int(scene_entity *e, const char *name, double v)
{
    add_nums(e, PARAM_INTEGER, name, &v, 1);
}

static inline void add_string(scene_entity *e, const char *name, const char *v)
{
    param p;
    memset(&p, 0, sizeof p);
    p.type = PARAM_STRING;
    p.name = dup_str(name);
    p.loc = (file_loc){"test.pbrt", 3, 10, NULL};
    p.count = 1;
    p.strs = malloc(sizeof *p.strs);
    assert_non_null(p.strs);
    p.strs[0] = dup_str(v);
    assert_int_equal(params_add(&e->params, p, NULL), HZ_OK);
}

static inline void add_bool(scene_entity *e, const char *name, bool v)
{
    param p;
    memset(&p, 0, sizeof p);
    p.type = PARAM_BOOL;
    p.name = dup_str(name);
    p.loc = (file_loc){"test.pbrt", 3, 10, NULL};
    p.count = 1;
    p.bools = malloc(sizeof *p.bools);
    assert_non_null(p.bools);
    p.bools[0] = v;
    assert_int_equal(params_add(&e->params, p, NULL), HZ_OK);
}

#endif
