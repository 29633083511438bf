/* Private to src/geometry: what every Embree scene build asks of the device
 * (embree_device.c): a new scene with haze's flags and build quality, and
 * the device's errors as haze's. For the top-level scene (embree_scene.c)
 * and the prototypes' and moving shapes' own scenes (instances.c). */
#ifndef HAZE_GEOMETRY_EMBREE_DEVICE_H
#define HAZE_GEOMETRY_EMBREE_DEVICE_H

#include <embree3/rtcore.h>

#include "core/error.h"

/* A scene with haze's flags and build quality, or NULL. */
RTCScene geom_new_scene(RTCDevice device);
/* rtcNewScene failed: the device's error, or a generic message. */
hz_status geom_new_scene_failed(RTCDevice device, hz_error *err);
/* HZ_OK unless Embree reported an error (out of memory named as such). */
hz_status geom_check_device(RTCDevice device, hz_error *err);

#endif
