/* The film: pixel bounds, per-pixel filter-weighted accumulation (pbrt-v4's
 * RGBFilm: each sample lands in its own pixel with weight f/pdf), and output. */
#ifndef HAZE_FILM_FILM_H
#define HAZE_FILM_FILM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/color_space.h"
#include "core/error.h"
#include "core/transform.h"
#include "core/vec.h"
#include "film/exr.h" /* tmp_file_note */
#include "film/sensor.h"
#include "scene/scene_desc.h"

typedef struct {
    int x0, y0, x1, y1; /* half-open: [x0, x1) x [y0, y1) */
} pixel_bounds;

typedef struct {
    int xres, yres;            /* full resolution (display window) */
    pixel_bounds bounds;       /* pixels rendered (data window), from cropwindow/pixelbounds */
    char filename[4096];       /* "pbrt.exr" by default, or a .png; -o overrides */
    bool savefp16;
    double iso;                /* 100 by default; imaging ratio = exposure time * iso / 100 */
    double scale;              /* "scale" (1): pbrt-v4's before 2020, multiplying the image
                                  written (not the clamp), kept for scenes that give it */
    bool write_z;              /* haze extension: "bool writedepth" adds a Z channel */
    bool write_variance;       /* haze: "bool writevariance" adds Variance.R/G/B */
    bool write_sample_count;   /* haze: "bool writesamplecount" adds SampleCount.Y */
    double max_component_value; /* pbrt-v4 "maxcomponentvalue": INFINITY = no clamp */
    double diagonal;           /* pbrt-v4 "diagonal" (mm, default 35), for physical cameras */
    film_sensor sensor;        /* pbrt-v4 "sensor" and "whitebalance"; inactive by default */
    color_space color_space;   /* of the image (ColorSpace at Film); sRGB by default */
    /* Film "gbuffer": pbrt-v4's GBufferFilm channels beside the image (the
     * visible surface's albedo, position, normals, uv, depth slopes, and
     * the per-sample variance); "coordinatesystem" "world" (gbuffer_world)
     * or "camera" (the default) for positions and normals. */
    bool gbuffer, gbuffer_world;
} film_params;

/* What a camera ray saw first (pbrt-v4's VisibleSurface), for a gbuffer
 * film: the first surface with a material (not an interface) met before any
 * scattering, in render space. */
typedef struct {
    bool hit;
    vec3 p, n, ns;    /* point, geometric and shading normals (unit) */
    vec3 dpdx, dpdy;  /* the point's change per pixel (0: no differentials) */
    double u, v;
    rgb albedo;       /* the BSDF's directional albedo toward the camera */
} film_surface;

/* Fills pbrt-v4's defaults (1280x720, full bounds, "pbrt.exr", iso 100, float32). */
void film_params_default(film_params *p);

/* A region given on the command line (haze render --pixelbounds /
 * --cropwindow), which replaces the Film's own cropwindow/pixelbounds. */
typedef enum { FILM_REGION_NONE = 0, FILM_REGION_PIXELS, FILM_REGION_CROP } film_region_kind;

typedef struct {
    film_region_kind kind;
    double v[4]; /* x0 x1 y0 y1: integer pixels (half-open) or crop fractions in [0, 1] */
} film_region;

/* Sets p->bounds from `r` for p's resolution (a no-op for FILM_REGION_NONE):
 * pixels as given, crop fractions by pbrt-v4's ceil(res * crop). Fails with a
 * one-line message (no option name) when the region is malformed, empty or
 * not inside the image. */
hz_status film_params_set_region(film_params *p, const film_region *r, hz_error *err);
/* The image's colour space: output RGB becomes that space's (folded into the
 * sensor's output matrix, so maxcomponentvalue still clamps the sensor's RGB);
 * the EXR says so in its chromaticities, the PNG preview stays sRGB. */
void film_params_set_color_space(film_params *p, color_space cs);

/* Reads Film "rgb" (xresolution yresolution filename (.exr or .png) cropwindow pixelbounds
 * savefp16 iso maxcomponentvalue diagonal sensor whitebalance, and haze's
 * writedepth, writevariance and
 * writesamplecount); other types are errors. Bounds
 * follow pbrt-v4: ceil(res * crop); "pixelbounds" [x0 x1 y0 y1] overrides
 * "cropwindow" and must be a non-empty part of the image. Films needing more
 * than 64 GiB are refused. */
hz_status film_params_from_entity(scene_entity *e, film_params *out, hz_error *err);
/* The same with the Film's bounds replaced by `r` (NULL or FILM_REGION_NONE:
 * kept) before the memory limit is checked, so a region of a frame too large
 * to render whole can be rendered. When it fails because of `r`, sets
 * *bad_region (may be NULL) to true, else to false. */
hz_status film_params_from_entity_region(scene_entity *e, const film_region *r, film_params *out,
                                         bool *bad_region, hz_error *err);

/* The image goes to a PNG (filename ends in .png), not an EXR. */
bool film_params_writes_png(const film_params *p);
/* For a Film (`e`, read into `p`) whose image goes to a PNG, refuses at
 * `e`'s parameter what a PNG cannot hold: a gbuffer film, writedepth,
 * writevariance, writesamplecount. */
hz_status film_params_check_format(const scene_entity *e, const film_params *p, hz_error *err);

typedef struct film film;

film *film_create(const film_params *p, hz_error *err);
void film_destroy(film *f);
/* Bytes the film holds for its bounds (accumulators, AOVs and output rows). */
double film_memory_bytes(const film *f);
const film_params *film_get_params(const film *f);
/* (px, py) absolute raster pixel inside bounds. Not thread-safe for the same
 * pixel; tiles own disjoint pixels. `depth` is the first-hit distance (or INFINITY).
 * A sample whose L or weight is not finite is counted and dropped. As pbrt-v4,
 * L * imaging ratio is scaled down so its largest component is at most
 * max_component_value (see film_set_imaging_ratio). Z is the mean of the
 * finite depths weighted by |weight|, +INFINITY where no sample hit. */
void film_add_sample(film *f, int px, int py, rgb L, double weight, double depth);
/* film_add_sample(f, px, py, black, weight, INFINITY): the same sums. */
void film_add_black(film *f, int px, int py, double weight);
/* A gbuffer film (params.gbuffer) wants each sample's visible surface. */
bool film_wants_surface(const film *f);
/* Adds a sample's visible surface to pixel (px, py), with the weight its
 * film_add_sample had: positions, normals, uv and depth slopes are the mean
 * over the samples that hit, the albedo the mean over all (misses count 0),
 * as pbrt-v4's GBufferFilm. Only on a gbuffer film (asserted). */
void film_add_surface(film *f, int px, int py, double weight, const film_surface *s);
/* The transform from render space to the gbuffer's output space (camera or
 * world space; the identity until set). */
void film_set_output_from_render(film *f, transform output_from_render);
/* The imaging ratio that maxcomponentvalue clamping assumes (default 1); pass
 * the same ratio to the output functions. */
void film_set_imaging_ratio(film *f, double imaging_ratio);
/* From now on samples arrive as the camera sensor's RGB, which spectral
 * rendering computes from each sample's wavelengths (sensor_response):
 * film_add_sample skips sensor_from_render. Only for a film whose sensor
 * has curves. */
void film_take_sensor_rgb(film *f);
/* Final pixel value = imaging_ratio * sum(w L) / sum(w) (0 when sum(w) == 0). */
rgb film_get_pixel(const film *f, int px, int py, double imaging_ratio);
/* Estimated variance of film_get_pixel's value (the weighted mean), per
 * component, imaging_ratio applied squared. Online weighted Welford/West over
 * the same (clamped) L as the mean, with weights |w|: W = sum |w|, W2 = sum
 * w^2, M2 = sum |w| (L - mean)^2, n_eff = W^2 / W2, variance = (M2 / W) /
 * (n_eff - 1), exactly s^2/n for equal weights (pbrt-v4's filter sampling
 * with a positive filter); an approximation for filters with negative lobes
 * (whose weights differ in sign). 0 when n_eff <= 1 (one sample, or none).
 * Only on a film created with write_variance (asserted). */
rgb film_get_variance(const film *f, int px, int py, double imaging_ratio);
/* Number of finite samples that reached the pixel (dropped non-finite ones
 * are not counted). Only on a film created with write_sample_count (asserted). */
long film_get_sample_count(const film *f, int px, int py);
/* Whether the film keeps the variance moments and the sample counts
 * (write_variance and write_sample_count). */
bool film_keeps_statistics(const film *f);
/* Number of non-finite sample values that were dropped (counted, never stored). */
long film_nonfinite_count(const film *f);
/* Writes R G B A (+ Z, Variance.R/G/B, SampleCount.Y when requested) float32,
 * or half with savefp16 (Z and the statistics AOVs stay float), A = 1 where
 * any weight was accumulated, data
 * window = bounds, display window = full resolution; written to a temporary
 * file in the same directory, then renamed over `path`. */
hz_status film_write_exr(const film *f, const char *path, double imaging_ratio, hz_error *err);
/* Tonemapped (clamp, sRGB transfer) 8-bit PNG of the pixel bounds; atomic too. */
hz_status film_write_png(const film *f, const char *path, double imaging_ratio, hz_error *err);

/* The film's raw accumulators, for combining films that rendered disjoint
 * pixels (one image across MPI ranks, src/mpi): per pixel the sums of w*L and
 * w, the depth sums, the weighted Welford states and the sample counts. Each
 * is exactly +0 (never -0) where no sample landed, and is touched only by the
 * samples of its own pixel, so adding another film's arrays element by element
 * (x + 0 = x) yields bit for bit the film that rendered both pixel sets.
 * Arrays that the film does not keep are NULL with count 0. */
enum { FILM_DOUBLE_ARRAYS = 4 };
typedef struct {
    /* pixel sums, depth sums (write_z), moments (write_variance), visible
     * surface sums (gbuffer) */
    double *doubles[FILM_DOUBLE_ARRAYS];
    size_t double_count[FILM_DOUBLE_ARRAYS];
    uint32_t *counts;        /* sample counts (write_sample_count) */
    size_t count_count;
} film_accumulators;

void film_get_accumulators(film *f, film_accumulators *out);
/* Adds n to film_nonfinite_count (the dropped samples of a combined film). */
void film_add_nonfinite(film *f, long n);

/* A copy of a film's accumulators: to undo samples (progressive passes cut
 * short) and to see a pixel's value at the time of the copy. */
typedef struct film_snapshot film_snapshot;
film_snapshot *film_snapshot_create(film *f, hz_error *err);
/* The copy's memory only: its pixels are undefined until a save covers
 * them (a progressive render's first pass is never undone). */
film_snapshot *film_snapshot_alloc(film *f, hz_error *err);
void film_snapshot_destroy(film_snapshot *s);
void film_snapshot_save(film_snapshot *s, film *f);
void film_snapshot_restore(const film_snapshot *s, film *f);
/* The same for the pixels whose `mask` byte (row-major over the film's
 * bounds) is non-zero, every pixel for a NULL mask. The copy holds the last
 * save only, packed: a save of k pixels writes k pixels' worth of the copy.
 * A pass that adds samples only to those pixels is undone by restoring the
 * same mask as the last save. */
void film_snapshot_save_pixels(film_snapshot *s, film *f, const unsigned char *mask);
void film_snapshot_restore_pixels(const film_snapshot *s, film *f, const unsigned char *mask);
/* film_get_pixel as of the last save, which covered the pixel. */
rgb film_snapshot_pixel(const film_snapshot *s, const film *f, int px, int py,
                        double imaging_ratio);

/* Extras for an output: EXR header string attributes (names < 64 bytes,
 * values < EXR_ATTRIBUTE_VALUE_SIZE; ignored by the PNG writer) and where to
 * publish the temporary file's name while it exists (NULL: nowhere). */
typedef struct {
    const char *name, *value;
} film_attribute;

typedef struct {
    const film_attribute *attributes;
    int attribute_count;
    tmp_file_note *note;
    int threads; /* compressing the EXR's chunks (0: one) */
} film_output;

/* film_write_exr / film_write_png with extras (`out` may be NULL). */
hz_status film_write_exr_with(const film *f, const char *path, double imaging_ratio,
                              const film_output *out, hz_error *err);
hz_status film_write_png_with(const film *f, const char *path, double imaging_ratio,
                              const film_output *out, hz_error *err);

#endif
