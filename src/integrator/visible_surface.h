/* pbrt-v4's VisibleSurface for a gbuffer film: what the camera ray's first
 * surface with a material is (point, normals, uv, screen derivatives of the
 * point; normals facing the camera) and its directional albedo toward the
 * camera. */
#ifndef HAZE_INTEGRATOR_VISIBLE_SURFACE_H
#define HAZE_INTEGRATOR_VISIBLE_SURFACE_H

#include "core/ray.h"
#include "film/film.h"
#include "geometry/geometry.h"

/* Fills *vs from hit h of camera ray rd (unit direction), whose footprint
 * (geometry_hit_footprint) is already set. */
void visible_surface_at(const geom_hit *h, const ray_differential *rd, film_surface *vs);

#endif
