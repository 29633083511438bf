/* Lights in render space: a closed set dispatched with a switch. Radiometry
 * follows pbrt-v4 for RGB values: `rgb I [1 1 1]` is radiant intensity 1 per
 * channel, `rgb L [1 1 1]` radiance 1 (pbrt-v4's photometric normalisation of
 * an RGB illuminant divides by the colour space illuminant only, which is
 * exactly what turns its spectra back into these RGB values). */
#ifndef HAZE_LIGHTS_LIGHTS_H
#define HAZE_LIGHTS_LIGHTS_H

#include <stdbool.h>
#include <stdio.h>

#include "color/spectral.h"
#include "core/error.h"
#include "core/sampling.h"
#include "core/transform.h"
#include "geometry/geometry.h"
#include "lights/envmap.h"
#include "scene/scene_desc.h"
#include "scene/spectrum_value.h"

typedef enum { LIGHT_POINT, LIGHT_SPOT, LIGHT_DISTANT, LIGHT_INFINITE, LIGHT_AREA } light_kind;

typedef struct {
    light_kind kind;
    rgb emit; /* I (point, spot) or L (distant, infinite, area), scale and power applied */
    /* The "I" or "L" spectrum as given (an RGB, a blackbody, sampled
     * values), as an illuminant: emit = spectrum_factor * spectrum.rgb.
     * Spectral rendering emits spectrum_factor times this spectrum. */
    spectrum_value spectrum;
    double spectrum_factor;
    /* Spectral rendering: emit's RGB spectrum looked up once
     * (light_prepare_spectral; an RGB spectrum's). */
    spectral_color emit_prepared;
    union {
        struct {
            vec3 p;
            /* NULL: isotropic. Otherwise, with wl = light_from_render w
             * toward w: goniometric, intensity emit * value(image(wl));
             * projection, emit * image(screen point of wl) inside the
             * screen window, 0 outside. */
            light_image *image;
            transform light_from_render;
            bool projection;
            double inv_tan;   /* projection: 1 / tan(fov / 2) */
            double screen[4]; /* projection: x0, x1, y0, y1 of the window */
        } point;
        struct {
            vec3 p;
            transform light_from_render; /* +z is the spot axis */
            double cos_falloff_start, cos_falloff_end;
        } spot;
        struct {
            vec3 w; /* unit direction toward the light */
        } distant;
        struct {
            /* NULL: a constant sky of radiance emit. Otherwise radiance
             * emit * image(light_from_render w) arrives from direction w. */
            light_image *image;
            transform light_from_render, render_from_light; /* rotations */
            /* pbrt-v4's "portal" (always with an image): light arrives only
             * along rays through this rectangle, render space: corner p0,
             * unit edges ex (toward the 4th corner) and ey (toward the 2nd)
             * of lengths len_x, len_y, and ez = ex x ey, the way it lets
             * light in. */
            bool portal;
            vec3 portal_p0, portal_ex, portal_ey, portal_ez;
            double portal_len_x, portal_len_y;
        } infinite;
        struct {
            /* top-level; in render space, or in object space when it moves
             * (shape->motion): then it is sampled in object space and moved
             * to render space with the transform at the sample's time */
            const geom_shape *shape;
            bool two_sided;
            /* A shape of constant alpha 0: pbrt-v4's invisible emitter, never
             * hit by a ray, emitting fully toward its light samples (which
             * then take no MIS weight, as a delta light's). */
            bool invisible;
            /* "filename": radiance emit times the image, bilinear at the
             * surface's (u, 1 - v) as pbrt-v4 (NULL: emit alone). */
            light_image *image;
            double area;             /* in the shape's space */
            double *cdf;             /* triangles: cumulative areas / area (triangle_count) */
            /* Spheres whose space_from_object is a uniform scale (times a
             * rotation, reflection and translation) are sampled by solid
             * angle from outside points (pbrt-v4's cone sampling); others,
             * and points inside, by area. Set by light_area_from_entity for
             * static spheres; a moving one decides at each sample's time. */
            bool sphere_cone;
            vec3 sphere_center;      /* render space */
            double sphere_radius;    /* render space */
        } area;
    };
} light;

/* LightSource "point", "spot", "goniometric" and "projection" (point lights
 * with an image), "distant", "infinite" (constant "L" or an image
 * "filename"). Warnings (an image with negative texels) go to `warn` (NULL:
 * none). */
hz_status light_from_entity(light_entity *e, transform render_from_world, light *out,
                            FILE *warn, hz_error *err);
/* AreaLightSource "diffuse" on a top-level shape (in render space, or in
 * object space with its motion); warnings as light_from_entity. */
hz_status light_area_from_entity(scene_entity *e, const geom_shape *shape, light *out,
                                 FILE *warn, hz_error *err);
void light_free(light *l);

/* Relative tolerance of light_uniform_scale, on the entries of the Gram matrix
 * AᵀA of the linear part A (i.e. squared axis scales and cosines between axes):
 * loose enough for matrices written with float precision, tight enough that
 * treating the ellipsoid as a sphere is far below any sampling noise. */
#define LIGHT_UNIFORM_SCALE_TOL 1e-6
/* s > 0 when `t` is affine with a linear part s·Q, Q orthogonal (rotation or
 * reflection: no shear, equal axis scales) within LIGHT_UNIFORM_SCALE_TOL;
 * 0 otherwise. */
double light_uniform_scale(const transform *t);

/* Incident radiance sample at reference point `p`. `wi` is unit; `pdf` is
 * per solid angle (1 for delta lights). The shadow ray must test the segment
 * from the offset origin to `p_light` (or to infinity when `infinite`). */
typedef struct {
    rgb L;
    vec3 wi;
    double pdf;
    vec3 p_light, n_light; /* area lights: point and normal on the emitter */
    double dist;           /* distance to the light point (INFINITY for distant/infinite) */
    bool infinite;
} light_sample;

/* `n` is the unit normal of the surface at `p` on the side radiance is wanted
 * (used for cosine sampling of the infinite light). Returns false when the
 * sample carries no light. `time` is the ray's scene time (area lights move
 * with their shapes). `u` in [0,1)^2 (ignored by delta lights). */
bool light_sample_li(const light *l, vec3 p, vec3 n, double time, vec2 u, light_sample *out);

/* Radiance leaving an area light's surface point with unit normal `n` and
 * surface parameters `uv` (an image light and an alpha texture read them) at
 * point `p` toward `w`; 0 where the shape's alpha masks it (pbrt-v4's
 * AlphaMasked). */
rgb light_area_le(const light *l, vec3 n, vec3 w, vec2 uv, vec3 p);

bool light_is_delta(const light *l);
/* Delta lights and invisible area lights: no ray can hit them, so their light
 * samples are the only strategy (MIS weight 1). */
bool light_only_sampled(const light *l);

/* The intensity factor of point light `l` toward unit direction w (from the
 * light): 1 for an isotropic one, the image's for goniometric and
 * projection lights. */
rgb light_point_factor(const light *l, vec3 w);

/* Radiance of infinite light `l` arriving along -w, i.e. seen by a ray from
 * o with unit direction w that leaves the scene. */
rgb light_infinite_le(const light *l, vec3 o, vec3 w);
/* Whether a ray from o along w can see infinite light l: always, unless l
 * has a portal the ray does not pass through. */
bool light_portal_passes(const light *l, vec3 o, vec3 w);
/* The solid-angle density with which light_sample_li samples direction w of
 * an image infinite light (0 for a constant one, which it samples around the
 * normal instead). */
double light_infinite_pdf(const light *l, vec3 w);
static inline bool light_is_image(const light *l)
{
    return l->kind == LIGHT_INFINITE && l->infinite.image;
}

/* The solid-angle density with which light_sample_li(l, p, .., time, ..)
 * picks the point `pl` (unit geometric normal `nl`) of area light `l`, seen
 * from `p` (for MIS against BSDF and phase sampling: a path that hits the
 * light there). 0 for lights other than area lights (delta lights cannot be
 * hit; the infinite light is not sampled by volpath) and degenerate points. */
double light_pdf_li(const light *l, vec3 p, double time, vec3 pl, vec3 nl);

/* Spectral rendering: the lanes (color/spectral.h) of radiance or intensity
 * `L` that one of l's functions above returned in RGB. Every such value is
 * l's emission times a scalar, unless l has an image: then it becomes an
 * illuminant spectrum of its own (pbrt-v4's image lights' RGBIlluminantSpectrum).
 * L itself when sp is NULL. */
rgb light_spectral(const light *l, rgb L, const spectral_ctx *sp);
/* Looks up the spectrum of l's RGB emission once (l->emit_prepared). */
void light_prepare_spectral(light *l, const rgb2spec_table *t);
/* The lanes of l's emission (`emit`) as an illuminant spectrum. */
rgb light_emit_spectral(const light *l, const spectral_ctx *sp);

/* Emitted power as pbrt-v4's Light::Phi in RGB terms (per channel), for
 * PowerLightSampler: point 4π I, spot 2π I (1 - (cos_start + cos_end) / 2),
 * area π A L (twice for two-sided), distant π r² L and infinite 4π² r² L with
 * r the radius of the scene's bounding sphere `scene_radius`. Area lights on
 * moving shapes take their area at the start of the shutter. */
rgb light_phi(const light *l, double scene_radius);

#endif
