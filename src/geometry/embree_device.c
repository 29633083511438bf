/* New Embree scenes with haze's flags and build quality, and the device's
 * errors as haze's: for every scene the geometry builds. */
#include "geometry/embree_device.h"

hz_status geom_check_device(RTCDevice device, hz_error *err)
{
    enum RTCError e = rtcGetDeviceError(device);
    switch (e) {
    case RTC_ERROR_NONE:
        return HZ_OK;
    case RTC_ERROR_OUT_OF_MEMORY:
        return hz_fail(err, "out of memory building the Embree scene (acceleration structure)");
    default:
        return hz_fail(err, "Embree error %d while building the scene", (int)e);
    }
}

hz_status geom_new_scene_failed(RTCDevice device, hz_error *err)
{
    if (geom_check_device(device, err) != HZ_OK)
        return HZ_ERROR;
    return hz_fail(err, "cannot create an Embree scene");
}

RTCScene geom_new_scene(RTCDevice device)
{
    RTCScene s = rtcNewScene(device);
    if (!s)
        return NULL;
    /* Robust mode makes the triangle test watertight against edges and
     * vertices; the cost is small and leaks between triangles are worse. */
    rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
    return s;
}
