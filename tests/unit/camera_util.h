/* A camera built straight from a camera_config (no scene parsing) for the
 * camera unit tests; fails the test with camera_init's message otherwise. */
#ifndef HAZE_TESTS_UNIT_CAMERA_UTIL_H
#define HAZE_TESTS_UNIT_CAMERA_UTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "camera/camera.h"

static inline camera make_camera(camera_config cfg)
{
    camera c;
    hz_error err = {0};
    if (camera_init(&cfg, &c, &err) != HZ_OK)
        fail_msg("camera_init: %s", err.message);
    return c;
}

#endif
