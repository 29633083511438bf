/* A point's footprint on the film when its ray carries no differentials
 * (pbrt-v4's CameraBase::Approximate_dp_dxy): textures filter, and bump maps
 * take their finite differences, over what one pixel would cover if the
 * point were looked at directly. */
#ifndef HAZE_CAMERA_FOOTPRINT_H
#define HAZE_CAMERA_FOOTPRINT_H

#include "camera/camera.h"

/* pbrt-v4's footprint of a point whose ray carries no differentials (a path
 * after a diffuse bounce): the camera's smallest pixel differentials
 * (camera_find_min_differentials), turned to look at p from the camera at
 * `time`, meet the plane through p with normal n at p + dpdx and p + dpdy,
 * scaled by `scale` (the camera rays' differential scale). Zeros where a
 * differential runs parallel to the plane. */
void camera_approximate_dpdxy(const camera *c, vec3 p, vec3 n, double time, double scale,
                              vec3 *dpdx, vec3 *dpdy);
/* Sets c->min_*: over 512 film points on the diagonal, through the lens
 * centre at mid-shutter (scenes with textures: the renderer calls it). */
void camera_find_min_differentials(camera *c);

#endif
