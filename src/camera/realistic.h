/* pbrt-v4's RealisticCamera (cameras.h/.cpp): a film behind a stack of
 * spherical glass interfaces and an aperture stop, focused by the thick-lens
 * approximation, rays sampled over precomputed exit-pupil bounds. Lengths in
 * metres. Lens space is camera space with z mirrored: the film at z = 0, the
 * elements at negative z, the scene beyond them. */
#ifndef HAZE_CAMERA_REALISTIC_H
#define HAZE_CAMERA_REALISTIC_H

#include <stdbool.h>

#include "camera/lens_file.h"
#include "core/error.h"
#include "core/vec.h"

#define REALISTIC_PUPIL_INTERVALS 64
/* Rear-element samples per film interval when bounding the exit pupil:
 * pbrt-v4 takes 1024 * 1024 (on all cores); 65536 bounds a double Gauss in
 * 0.4 s on one core. The bounds only need to hold the pupil (they are grown
 * by twice the sample spacing), so the estimate is the same in expectation. */
#define REALISTIC_PUPIL_SAMPLES 65536

/* The stop's shape: pbrt-v4's default circle, its built-in "aperture"
 * images (evaluated exactly rather than from a 256x256 raster) and an image
 * file. */
typedef enum {
    APERTURE_CIRCLE,
    APERTURE_GAUSSIAN,
    APERTURE_SQUARE,
    APERTURE_PENTAGON,
    APERTURE_STAR,
    APERTURE_IMAGE
} aperture_shape;

/* An aperture image over the stop's square [-r, r]^2: texel (x, y) covers
 * x in [-r + 2r x / width, ...] and y likewise from -r at row 0 (the file's
 * bottom row: pbrt-v4 flips the image), scaled to a mean of pi/4 as pbrt-v4
 * does, so a full disc transmits as the circle; read bilinearly, black
 * outside. Owned by the realistic_lens (realistic_lens_free). */
typedef struct {
    int width, height;
    float *values;
} aperture_image;

typedef struct {
    double radius;    /* curvature radius, 0 = aperture stop */
    double thickness; /* to the next interface toward the film */
    double eta;       /* index of refraction behind the interface (toward the film) */
    double aperture_radius;
} lens_interface;

typedef struct {
    int count;
    lens_interface e[LENS_FILE_MAX_ELEMENTS]; /* scene side first */
    aperture_shape shape;
    double shape_scale;          /* the shape's value inside: its mean over [-1,1]^2 is pi/4 */
    int poly_count;              /* pentagon, star: the outline in stop-radius units */
    vec2 poly[10];
    aperture_image image;        /* APERTURE_IMAGE */
    double film_diagonal;        /* metres */
    double film_half[2];         /* half the film's physical width and height */
    /* Exit-pupil bounds on the rear element's plane for film radii
     * [i, i + 1) * diagonal / 2 / REALISTIC_PUPIL_INTERVALS, as
     * {xmin, xmax, ymin, ymax}; empty when xmin > xmax. */
    double pupil[REALISTIC_PUPIL_INTERVALS][4];
} realistic_lens;

typedef struct {
    vec3 o, d;
} lens_ray;

/* The elements from a lens table (millimetres to metres); the stop's diameter
 * becomes aperture_diameter_mm unless that exceeds the file's (pbrt-v4 then
 * keeps the file's, with a warning: *clamped is set). No focusing, no pupil. */
void realistic_elements(const lens_table *t, double aperture_diameter_mm, aperture_shape shape,
                        double film_diagonal_mm, int xres, int yres, realistic_lens *out,
                        bool *clamped);
/* Makes the stop the image of `width` x `height` linear values, top row first
 * (as a file stores them): flipped and scaled to a mean of pi/4. Takes
 * ownership of `values` (freed on failure too). Refuses a negative or
 * non-finite value and an image whose mean is not > 0. */
hz_status realistic_set_aperture_image(realistic_lens *l, int width, int height, float *values,
                                       hz_error *err);
/* Frees what the lens owns (the aperture image) and makes the stop a circle. */
void realistic_lens_free(realistic_lens *l);
/* The z of the rear and front interfaces in camera space (both > 0). */
double realistic_rear_z(const realistic_lens *l);
double realistic_front_z(const realistic_lens *l);
/* Traces a camera-space ray from the film side through the stack: the
 * weight (the aperture shape's value, 1 for the circle), 0 when blocked. */
double realistic_trace_from_film(const realistic_lens *l, lens_ray in, lens_ray *out);
/* The same from the scene side (no aperture shape weight); false when blocked. */
bool realistic_trace_from_scene(const realistic_lens *l, lens_ray in, lens_ray *out);
/* pbrt-v4's ComputeThickLensApproximation: camera-space z of the principal
 * planes pz and focal points fz, [0] for the film side, [1] the scene side. */
hz_status realistic_thick_lens(const realistic_lens *l, double pz[2], double fz[2],
                               hz_error *err);
/* pbrt-v4's FocusThickLens: sets the rear element's thickness (the film
 * distance) so that a point focus_distance from the film is in focus. */
hz_status realistic_focus(realistic_lens *l, double focus_distance, hz_error *err);
/* Precomputes the exit-pupil table from `samples` rear-element points per
 * film interval (pbrt-v4: 1024 * 1024). */
void realistic_bound_pupil(realistic_lens *l, int samples);
/* pbrt-v4's GenerateRay in camera space for raster point p of an xres x yres
 * film and lens sample u: the weight cos^4 / (pdf * rear_z^2) times the
 * aperture's, 0 when there is no ray. */
double realistic_generate(const realistic_lens *l, vec2 p, vec2 u, int xres, int yres,
                          lens_ray *out);

#endif
