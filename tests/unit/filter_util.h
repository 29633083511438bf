/* A filter built from a bare entity of one type (its defaults), for the
 * filter unit tests; fails the test with filter_create's message otherwise. */
#ifndef HAZE_TESTS_UNIT_FILTER_UTIL_H
#define HAZE_TESTS_UNIT_FILTER_UTIL_H

#include "film/filter.h"
#include "unit/entity_util.h"

static inline filter *make_filter(const char *type)
{
    scene_entity e;
    entity_init(&e, type);
    hz_error err = {0};
    filter *f = filter_create(&e, &err);
    if (!f)
        fail_msg("%s", err.message);
    entity_free(&e);
    return f;
}

#endif
