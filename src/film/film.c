/* The RGB film (pbrt-v4's RGBFilm without the sensor model: haze renders in
 * linear sRGB already). Per pixel, double sums of w*L and w; the pixel is
 * their ratio, so the filter needs no normalisation and negative lobes work. */
#define _POSIX_C_SOURCE 200809L

#include "film/film.h"

#include <assert.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/big_alloc.h"
#include "core/parallel.h"
#include "film/exr.h"
#include "film/png.h"
#include "scene/params.h"

/* Refuse films whose buffers would need more than this. */
#define FILM_MAX_BYTES (64.0 * 1024 * 1024 * 1024)

typedef struct {
    double r, g, b, w;
} film_pixel;

typedef struct {
    double sum, w; /* |weight|-weighted finite depths */
} film_depth;

/* A gbuffer pixel's sums: weight of the samples that hit, and weighted
 * sums of their point, normals, uv and depth slopes (render space), and of
 * every sample's albedo (divided by the pixel's w). */
typedef struct {
    double w, p[3], n[3], ns[3], uv[2], dz[2], albedo[3];
} film_gbuffer;
enum { GBUFFER_DOUBLES = 17 };

/* Weighted Welford/West state with weights |w|: W = sum |w|, W2 = sum w^2,
 * the |w|-weighted running mean and M2 = sum |w| (L - mean)^2 per component. */
typedef struct {
    double w, w2, mean[3], m2[3];
} film_moments;

struct film {
    film_params p;
    int width, height; /* of the bounds */
    film_pixel *pixels;
    film_depth *depth; /* NULL unless write_z */
    film_moments *moments; /* NULL unless write_variance */
    uint32_t *count;   /* NULL unless write_sample_count */
    film_gbuffer *gbuf; /* NULL unless gbuffer */
    transform output_from_render; /* gbuffer positions and normals */
    double clamp_ratio;
    double xyz_from_render[9]; /* the clamp's space without an active sensor */
    bool sensor_rgb_in; /* film_take_sensor_rgb */
    atomic_long nonfinite; /* tiles run in parallel; only this is shared */
};

void film_params_default(film_params *p)
{
    memset(p, 0, sizeof *p);
    p->xres = 1280;
    p->yres = 720;
    p->bounds = (pixel_bounds){0, 0, 1280, 720};
    snprintf(p->filename, sizeof p->filename, "pbrt.exr");
    p->savefp16 = false; /* haze default; pbrt-v4 writes half by default */
    p->iso = 100.0;
    p->scale = 1.0;
    p->max_component_value = INFINITY;
    p->diagonal = 35.0;
}

/* The gbuffer's own channels (Albedo.R ... v; the variances are the
 * moments' 3 plus RelativeVariance's 3). */
enum { GBUFFER_OUT = 16 };

/* Bytes per bounds pixel: accumulation, optional depth and statistics, and
 * the output image (one float per channel). */
static double film_bytes(const film_params *p)
{
    double area = (double)(p->bounds.x1 - p->bounds.x0) * (double)(p->bounds.y1 - p->bounds.y0);
    double per = sizeof(film_pixel) + 4.0 * sizeof(float) +
                 (p->write_z ? sizeof(film_depth) + sizeof(float) : 0.0) +
                 (p->write_variance ? sizeof(film_moments) + 3.0 * sizeof(float) : 0.0) +
                 (p->write_sample_count ? sizeof(uint32_t) + sizeof(float) : 0.0) +
                 (p->gbuffer ? sizeof(film_gbuffer) + (GBUFFER_OUT + 3.0) * sizeof(float)
                             : 0.0);
    return area * per;
}

double film_memory_bytes(const film *f) { return film_bytes(&f->p); }

/* `s` ends in `ext` (".exr", ".png"; any case) after at least one character. */
static bool ends_with(const char *s, const char *ext)
{
    size_t n = strlen(s), m = strlen(ext);
    return n > m && strcasecmp(s + n - m, ext) == 0;
}

bool film_params_writes_png(const film_params *p) { return ends_with(p->filename, ".png"); }

/* pbrt-v4's crop window rule: ceil(res * crop), crop = [x0 x1 y0 y1] in [0, 1]. */
static pixel_bounds crop_bounds(int xres, int yres, const double crop[4])
{
    return (pixel_bounds){(int)ceil(xres * crop[0]), (int)ceil(yres * crop[2]),
                          (int)ceil(xres * crop[1]), (int)ceil(yres * crop[3])};
}

/* Bounds from cropwindow / pixelbounds, as pbrt-v4's FilmBaseParameters. */
static void film_read_bounds(param_list *pl, film_params *p)
{
    size_t ncrop = 0, npb = 0;
    const double *crop = params_floats(pl, "cropwindow", &ncrop);
    const double *pb = params_ints(pl, "pixelbounds", &npb);
    p->bounds = (pixel_bounds){0, 0, p->xres, p->yres};
    if (pb) {
        if (npb != 4) {
            params_reject(pl, "pixelbounds", "\"integer pixelbounds\" needs 4 values [x0 x1 y0 y1], got %zu",
                          npb);
            return;
        }
        if (!(pb[0] >= 0 && pb[1] <= p->xres && pb[2] >= 0 && pb[3] <= p->yres && pb[0] < pb[1] &&
              pb[2] < pb[3])) {
            params_reject(pl, "pixelbounds",
                          "\"integer pixelbounds\" [%g %g %g %g] must be a non-empty part of the "
                          "%dx%d image (x0 < x1 <= %d, y0 < y1 <= %d)",
                          pb[0], pb[1], pb[2], pb[3], p->xres, p->yres, p->xres, p->yres);
            return;
        }
        p->bounds = (pixel_bounds){(int)pb[0], (int)pb[2], (int)pb[1], (int)pb[3]};
        return; /* overrides cropwindow (which counts as read) */
    }
    if (!crop)
        return;
    if (ncrop != 4) {
        params_reject(pl, "cropwindow", "\"float cropwindow\" needs 4 values [x0 x1 y0 y1], got %zu", ncrop);
        return;
    }
    for (int i = 0; i < 4; i++)
        if (!(crop[i] >= 0.0 && crop[i] <= 1.0)) {
            params_reject(pl, "cropwindow", "\"float cropwindow\" values must lie in [0, 1], got %g", crop[i]);
            return;
        }
    if (!(crop[0] < crop[1] && crop[2] < crop[3])) {
        params_reject(pl, "cropwindow", "\"float cropwindow\" [%g %g %g %g] needs x0 < x1 and y0 < y1",
                      crop[0], crop[1], crop[2], crop[3]);
        return;
    }
    pixel_bounds b = crop_bounds(p->xres, p->yres, crop);
    if (b.x0 >= b.x1 || b.y0 >= b.y1) {
        params_reject(pl, "cropwindow", "\"float cropwindow\" [%g %g %g %g] covers no pixel of the %dx%d image",
                      crop[0], crop[1], crop[2], crop[3], p->xres, p->yres);
        return;
    }
    p->bounds = b;
}

hz_status film_params_from_entity(scene_entity *e, film_params *out, hz_error *err)
{
    return film_params_from_entity_region(e, NULL, out, NULL, err);
}

/* A gbuffer's "coordinatesystem": "camera" (the default) or "world". */
static void film_read_gbuffer(param_list *pl, film_params *p)
{
    const char *cs = params_string(pl, "coordinatesystem", "camera");
    p->gbuffer = true;
    p->gbuffer_world = strcmp(cs, "world") == 0;
    if (!p->gbuffer_world && strcmp(cs, "camera") != 0)
        params_reject(pl, "coordinatesystem",
                      "Film \"gbuffer\" \"string coordinatesystem\" must be \"camera\" or "
                      "\"world\", got \"%s\"", cs);
}

/* The resolution, then (when it is valid) the bounds within it. */
static void film_read_resolution(param_list *pl, film_params *p)
{
    p->xres = params_int(pl, "xresolution", 1280);
    p->yres = params_int(pl, "yresolution", 720);
    bool res_ok = true;
    if (p->xres < 1 || p->xres > (1 << 24)) {
        params_reject(pl, "xresolution", "\"integer xresolution\" must be in [1, %d], got %d", 1 << 24, p->xres);
        res_ok = false;
    }
    if (p->yres < 1 || p->yres > (1 << 24)) {
        params_reject(pl, "yresolution", "\"integer yresolution\" must be in [1, %d], got %d", 1 << 24, p->yres);
        res_ok = false;
    }
    if (res_ok)
        film_read_bounds(pl, p);
}

static void film_read_filename(param_list *pl, film_params *p)
{
    const char *name = params_string(pl, "filename", "pbrt.exr");
    if (!ends_with(name, ".exr") && !ends_with(name, ".png"))
        params_reject(pl, "filename", "Film \"string filename\" \"%s\" must end in .exr or .png",
                      name);
    else if (strlen(name) >= sizeof p->filename)
        params_reject(pl, "filename", "Film \"string filename\" is too long");
    else
        snprintf(p->filename, sizeof p->filename, "%s", name);
}

/* Which channels the EXR gets besides the colour, and at what precision. */
static void film_read_channels(param_list *pl, film_params *p)
{
    p->savefp16 = params_bool(pl, "savefp16", false);
    p->write_z = params_bool(pl, "writedepth", false);
    /* A gbuffer's variance channels come from the same moments. */
    p->write_variance = params_bool(pl, "writevariance", false) || p->gbuffer;
    p->write_sample_count = params_bool(pl, "writesamplecount", false);
}

static void film_read_exposure(param_list *pl, film_params *p)
{
    p->iso = params_float(pl, "iso", 100.0);
    if (!(p->iso > 0.0 && isfinite(p->iso)))
        params_reject(pl, "iso", "\"float iso\" must be positive, got %g", p->iso);
    p->scale = params_float(pl, "scale", 1.0);
    if (!(p->scale > 0.0 && isfinite(p->scale)))
        params_reject(pl, "scale", "\"float scale\" must be positive, got %g", p->scale);
    p->max_component_value = params_float(pl, "maxcomponentvalue", INFINITY);
    if (!(p->max_component_value > 0.0)) /* INFINITY is the default and allowed */
        params_reject(pl, "maxcomponentvalue", "\"float maxcomponentvalue\" must be positive, got %g",
                      p->max_component_value);
    p->diagonal = params_float(pl, "diagonal", 35.0);
    if (!(p->diagonal > 0.0 && isfinite(p->diagonal)))
        params_reject(pl, "diagonal", "\"float diagonal\" must be positive, got %g", p->diagonal);
}

static void film_read_sensor(param_list *pl, film_params *p)
{
    const char *sensor = params_string(pl, "sensor", "cie1931");
    double wb = params_float(pl, "whitebalance", 0.0);
    if (wb != 0.0 && !(wb >= SENSOR_MIN_KELVIN && wb <= SENSOR_MAX_KELVIN))
        params_reject(pl, "whitebalance",
                      "Film \"float whitebalance\" must be 0 (none) or in [%g, %g] kelvin, got %g",
                      SENSOR_MIN_KELVIN, SENSOR_MAX_KELVIN, wb);
    else if (!sensor_lookup(sensor, wb, &p->sensor))
        params_reject(pl, "sensor", "Film \"string sensor\" \"%s\" is unknown (known: %s)", sensor,
                      sensor_names());
}

/* A film whose buffers would need more than FILM_MAX_BYTES is refused. */
static hz_status film_check_memory(const scene_entity *e, const film_params *p, hz_error *err)
{
    double bytes = film_bytes(p);
    if (bytes > FILM_MAX_BYTES)
        return hz_fail_at(err, e->loc, "Film of %dx%d pixels would need %.1f GiB of memory (limit %.0f GiB)",
                          p->bounds.x1 - p->bounds.x0, p->bounds.y1 - p->bounds.y0,
                          bytes / (1024.0 * 1024 * 1024), FILM_MAX_BYTES / (1024.0 * 1024 * 1024));
    return HZ_OK;
}

hz_status film_params_from_entity_region(scene_entity *e, const film_region *r, film_params *out,
                                         bool *bad_region, hz_error *err)
{
    if (bad_region)
        *bad_region = false;
    film_params_default(out);
    const char *type = e->type ? e->type : "";
    bool gbuffer = strcmp(type, "gbuffer") == 0;
    if (strcmp(type, "rgb") != 0 && !gbuffer)
        return hz_fail_at(err, e->loc,
                          "Film \"%s\" is not supported (supported: \"rgb\", \"gbuffer\")",
                          type);
    param_list *pl = &e->params;
    if (gbuffer)
        film_read_gbuffer(pl, out);
    film_read_resolution(pl, out);
    film_read_filename(pl, out);
    film_read_channels(pl, out);
    film_read_exposure(pl, out);
    film_read_sensor(pl, out);
    if (params_finish(pl, gbuffer ? "Film \"gbuffer\"" : "Film \"rgb\"", err) != HZ_OK)
        return HZ_ERROR;
    if (r && film_params_set_region(out, r, err) != HZ_OK) {
        if (bad_region)
            *bad_region = true;
        return HZ_ERROR;
    }
    return film_check_memory(e, out, err);
}

/* A PNG holds 8-bit sRGB R, G, B and nothing else: the channels the Film
 * asks for beside them are refused rather than silently dropped. pbrt-v4
 * refuses a gbuffer film's PNG too ("EXR is the only format supported"). */
hz_status film_params_check_format(const scene_entity *e, const film_params *p, hz_error *err)
{
    if (!film_params_writes_png(p))
        return HZ_OK;
    const param_list *pl = &e->params;
    if (p->gbuffer)
        return hz_fail_at(err, params_loc(pl, "filename"),
                          "Film \"gbuffer\" writes only EXR (as pbrt-v4), not \"%s\"; give a "
                          "\"string filename\" ending in .exr, or -o NAME.exr", p->filename);
    const struct {
        bool on;
        const char *name;
    } extra[] = {{p->write_z, "writedepth"},
                 {p->write_variance, "writevariance"},
                 {p->write_sample_count, "writesamplecount"}};
    for (size_t i = 0; i < sizeof extra / sizeof extra[0]; ++i)
        if (extra[i].on)
            return hz_fail_at(err, params_loc(pl, extra[i].name),
                              "Film \"bool %s\" needs an EXR: the PNG \"%s\" holds only R, G "
                              "and B; give a \"string filename\" ending in .exr, or -o NAME.exr",
                              extra[i].name, p->filename);
    return HZ_OK;
}

/* XYZ from linear sRGB and (when srgb_from_xyz) back, white D65 at Y = 1:
 * the sensor RGB of pbrt-v4's default "cie1931" sensor is XYZ. */
static void srgb_xyz(double xyz_from_srgb[9], double *srgb_from_xyz)
{
    double xy[8];
    color_space_chromaticities(COLOR_SPACE_SRGB, xy);
    double w[3] = {xy[6] / xy[7], 1.0, (1.0 - xy[6] - xy[7]) / xy[7]};
    color_space_xyz_from_rgb_white(COLOR_SPACE_SRGB, w, xyz_from_srgb);
    if (srgb_from_xyz)
        color_space_rgb_from_xyz_white(COLOR_SPACE_SRGB, w, srgb_from_xyz);
}

void film_params_set_color_space(film_params *p, color_space cs)
{
    p->color_space = cs;
    if (cs == COLOR_SPACE_SRGB)
        return;
    double m[9], out[9];
    color_space_convert_matrix(COLOR_SPACE_SRGB, cs, m);
    film_sensor *s = &p->sensor;
    if (!s->active) { /* "cie1931": sensor RGB is XYZ, which maxcomponentvalue clamps */
        srgb_xyz(s->sensor_from_render, s->output_from_sensor);
        s->active = true;
    }
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            out[r * 3 + c] = m[r * 3] * s->output_from_sensor[c] +
                             m[r * 3 + 1] * s->output_from_sensor[3 + c] +
                             m[r * 3 + 2] * s->output_from_sensor[6 + c];
    memcpy(s->output_from_sensor, out, sizeof out);
}

hz_status film_params_set_region(film_params *p, const film_region *r, hz_error *err)
{
    const double *v = r->v;
    pixel_bounds b;
    if (r->kind == FILM_REGION_NONE)
        return HZ_OK;
    if (r->kind == FILM_REGION_PIXELS) {
        for (int i = 0; i < 4; i++)
            if (!(v[i] == floor(v[i]) && fabs(v[i]) <= (double)(1 << 30)))
                return hz_fail(err, "pixel bounds must be integers, got %g", v[i]);
        b = (pixel_bounds){(int)v[0], (int)v[2], (int)v[1], (int)v[3]};
        if (b.x0 >= b.x1 || b.y0 >= b.y1)
            return hz_fail(err, "pixel bounds [%d,%d)x[%d,%d) are empty (need x0 < x1 and y0 < y1)",
                           b.x0, b.x1, b.y0, b.y1);
        if (b.x0 < 0 || b.y0 < 0 || b.x1 > p->xres || b.y1 > p->yres)
            return hz_fail(err,
                           "pixel bounds [%d,%d)x[%d,%d) are not inside the %dx%d image "
                           "(0 <= x0 < x1 <= %d, 0 <= y0 < y1 <= %d)",
                           b.x0, b.x1, b.y0, b.y1, p->xres, p->yres, p->xres, p->yres);
    } else {
        for (int i = 0; i < 4; i++)
            if (!(v[i] >= 0.0 && v[i] <= 1.0))
                return hz_fail(err, "crop window values must lie in [0, 1], got %g", v[i]);
        if (!(v[0] < v[1] && v[2] < v[3]))
            return hz_fail(err, "crop window [%g,%g]x[%g,%g] is empty (need x0 < x1 and y0 < y1)",
                           v[0], v[1], v[2], v[3]);
        b = crop_bounds(p->xres, p->yres, v);
        if (b.x0 >= b.x1 || b.y0 >= b.y1)
            return hz_fail(err, "crop window [%g,%g]x[%g,%g] covers no pixel of the %dx%d image",
                           v[0], v[1], v[2], v[3], p->xres, p->yres);
    }
    p->bounds = b;
    return HZ_OK;
}

film *film_create(const film_params *p, hz_error *err)
{
    pixel_bounds b = p->bounds;
    if (p->xres < 1 || p->yres < 1 || b.x0 < 0 || b.y0 < 0 || b.x1 > p->xres || b.y1 > p->yres ||
        b.x0 >= b.x1 || b.y0 >= b.y1) {
        hz_fail(err, "film: invalid pixel bounds [%d,%d)x[%d,%d) for a %dx%d image", b.x0, b.x1, b.y0,
                b.y1, p->xres, p->yres);
        return NULL;
    }
    double bytes = film_bytes(p);
    if (bytes > FILM_MAX_BYTES) {
        hz_fail(err, "film: %dx%d pixels would need %.1f GiB of memory", b.x1 - b.x0, b.y1 - b.y0,
                bytes / (1024.0 * 1024 * 1024));
        return NULL;
    }
    film *f = calloc(1, sizeof *f);
    if (!f) {
        hz_fail(err, "film: out of memory");
        return NULL;
    }
    f->p = *p;
    f->width = b.x1 - b.x0;
    f->height = b.y1 - b.y0;
    f->clamp_ratio = 1.0;
    srgb_xyz(f->xyz_from_render, NULL);
    atomic_init(&f->nonfinite, 0);
    size_t n = (size_t)f->width * (size_t)f->height;
    f->pixels = hz_big_calloc(n, sizeof *f->pixels);
    if (p->write_z)
        f->depth = hz_big_calloc(n, sizeof *f->depth);
    if (p->write_variance)
        f->moments = hz_big_calloc(n, sizeof *f->moments);
    if (p->write_sample_count)
        f->count = hz_big_calloc(n, sizeof *f->count);
    if (p->gbuffer)
        f->gbuf = hz_big_calloc(n, sizeof *f->gbuf);
    f->output_from_render = transform_identity();
    if (!f->pixels || (p->write_z && !f->depth) || (p->write_variance && !f->moments) ||
        (p->write_sample_count && !f->count) || (p->gbuffer && !f->gbuf)) {
        hz_fail(err, "film: out of memory for %dx%d pixels (%.1f MiB)", f->width, f->height,
                bytes / (1024.0 * 1024));
        film_destroy(f);
        return NULL;
    }
    return f;
}

void film_destroy(film *f)
{
    if (!f)
        return;
    free(f->pixels);
    free(f->depth);
    free(f->moments);
    free(f->count);
    free(f->gbuf);
    free(f);
}

const film_params *film_get_params(const film *f) { return &f->p; }

void film_set_imaging_ratio(film *f, double imaging_ratio) { f->clamp_ratio = imaging_ratio; }

void film_take_sensor_rgb(film *f)
{
    assert(f->p.sensor.curves);
    f->sensor_rgb_in = true;
}

long film_nonfinite_count(const film *f)
{
    return atomic_load_explicit(&((film *)f)->nonfinite, memory_order_relaxed);
}

void film_get_accumulators(film *f, film_accumulators *out)
{
    /* The structs are plain doubles (no padding), so each array is a flat
     * array of doubles. */
    _Static_assert(sizeof(film_pixel) == 4 * sizeof(double), "film_pixel is 4 doubles");
    _Static_assert(sizeof(film_depth) == 2 * sizeof(double), "film_depth is 2 doubles");
    _Static_assert(sizeof(film_moments) == 8 * sizeof(double), "film_moments is 8 doubles");
    _Static_assert(sizeof(film_gbuffer) == GBUFFER_DOUBLES * sizeof(double),
                   "film_gbuffer is plain doubles");
    size_t n = (size_t)f->width * (size_t)f->height;
    memset(out, 0, sizeof *out);
    out->doubles[0] = (double *)f->pixels;
    out->double_count[0] = 4 * n;
    if (f->depth) {
        out->doubles[1] = (double *)f->depth;
        out->double_count[1] = 2 * n;
    }
    if (f->moments) {
        out->doubles[2] = (double *)f->moments;
        out->double_count[2] = 8 * n;
    }
    if (f->gbuf) {
        out->doubles[3] = (double *)f->gbuf;
        out->double_count[3] = GBUFFER_DOUBLES * n;
    }
    if (f->count) {
        out->counts = f->count;
        out->count_count = n;
    }
}

void film_add_nonfinite(film *f, long n)
{
    atomic_fetch_add_explicit(&f->nonfinite, n, memory_order_relaxed);
}

static size_t film_index(const film *f, int px, int py)
{
    assert(px >= f->p.bounds.x0 && px < f->p.bounds.x1 && py >= f->p.bounds.y0 && py < f->p.bounds.y1);
    return (size_t)(py - f->p.bounds.y0) * (size_t)f->width + (size_t)(px - f->p.bounds.x0);
}

/* imaging_ratio * sum(w L) / sum(w), 0 without weight. */
static rgb pixel_value(const film_pixel *p, double imaging_ratio)
{
    if (p->w == 0.0)
        return rgb_grey(0.0);
    double s = imaging_ratio / p->w;
    return rgb_make(p->r * s, p->g * s, p->b * s);
}

/* The saved pixels' accumulators, packed in the order of the last save's
 * mask (a save touches only as much of the copy as it saves: a pass over a
 * tenth of the image writes, and faults in, a tenth of it), with each saved
 * pixel's place; a save of every pixel keeps the film's own order. */
struct film_snapshot {
    double *doubles[FILM_DOUBLE_ARRAYS];
    uint32_t *counts;
    size_t *slot;   /* per film pixel: its place in the copy, when !identity */
    bool identity;  /* the last save covered every pixel, in place */
    long nonfinite;
};

void film_snapshot_destroy(film_snapshot *s)
{
    if (!s)
        return;
    for (int i = 0; i < FILM_DOUBLE_ARRAYS; ++i)
        free(s->doubles[i]);
    free(s->counts);
    free(s->slot);
    free(s);
}

film_snapshot *film_snapshot_alloc(film *f, hz_error *err)
{
    film_snapshot *s = calloc(1, sizeof *s);
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    bool ok = s != NULL;
    for (int i = 0; ok && i < FILM_DOUBLE_ARRAYS; ++i)
        if (acc.doubles[i] && !(s->doubles[i] = hz_big_malloc(acc.double_count[i] * sizeof(double))))
            ok = false;
    if (ok && acc.counts && !(s->counts = hz_big_malloc(acc.count_count * sizeof(uint32_t))))
        ok = false;
    size_t npix = (size_t)f->width * (size_t)f->height;
    if (ok && !(s->slot = malloc((npix ? npix : 1) * sizeof *s->slot)))
        ok = false;
    if (!ok) {
        film_snapshot_destroy(s);
        hz_fail(err, "out of memory for a copy of the film");
        return NULL;
    }
    s->nonfinite = film_nonfinite_count(f);
    return s;
}

film_snapshot *film_snapshot_create(film *f, hz_error *err)
{
    film_snapshot *s = film_snapshot_alloc(f, err);
    if (s)
        film_snapshot_save(s, f);
    return s;
}

/* Copies pixels [a, b) of every accumulator array, each pixel's `per`
 * values (doubles, or one count) together, to or from the copy's pixels
 * [at, at + b - a). save: film -> snapshot; otherwise snapshot -> film. */
static void snapshot_copy_range(film_snapshot *s, const film_accumulators *acc, size_t npix,
                                size_t a, size_t b, size_t at, bool save)
{
    for (int i = 0; i < FILM_DOUBLE_ARRAYS; ++i)
        if (acc->doubles[i]) {
            size_t per = acc->double_count[i] / npix;
            double *film_side = acc->doubles[i] + a * per, *copy = s->doubles[i] + at * per;
            size_t n = (b - a) * per * sizeof(double);
            if (save)
                memcpy(copy, film_side, n);
            else
                memcpy(film_side, copy, n);
        }
    if (acc->counts) {
        size_t n = (b - a) * sizeof(uint32_t);
        if (save)
            memcpy(s->counts + at, acc->counts + a, n);
        else
            memcpy(acc->counts + a, s->counts + at, n);
    }
}

/* The pixels of `mask` (NULL: all, in place), in runs of consecutive ones,
 * packed in mask order; a save records each pixel's place. */
static void snapshot_copy(film_snapshot *s, film *f, const unsigned char *mask, bool save)
{
    film_accumulators acc;
    film_get_accumulators(f, &acc);
    size_t npix = (size_t)f->width * (size_t)f->height;
    if (npix == 0)
        return;
    if (!mask) {
        assert(save || s->identity); /* a full restore follows a full save */
        snapshot_copy_range(s, &acc, npix, 0, npix, 0, save);
    } else {
        assert(save || !s->identity);
        size_t at = 0;
        for (size_t i = 0; i < npix;) {
            if (!mask[i]) {
                ++i;
                continue;
            }
            size_t j = i + 1;
            while (j < npix && mask[j])
                ++j;
            snapshot_copy_range(s, &acc, npix, i, j, at, save);
            if (save)
                for (size_t k = i; k < j; ++k)
                    s->slot[k] = at + (k - i);
            at += j - i;
            i = j;
        }
    }
    if (save) {
        s->identity = mask == NULL;
        s->nonfinite = film_nonfinite_count(f);
    } else {
        film_add_nonfinite(f, s->nonfinite - film_nonfinite_count(f));
    }
}

void film_snapshot_save(film_snapshot *s, film *f) { snapshot_copy(s, f, NULL, true); }

void film_snapshot_restore(const film_snapshot *s, film *f)
{
    snapshot_copy((film_snapshot *)s, f, NULL, false); /* reads s only */
}

void film_snapshot_save_pixels(film_snapshot *s, film *f, const unsigned char *mask)
{
    snapshot_copy(s, f, mask, true);
}

void film_snapshot_restore_pixels(const film_snapshot *s, film *f, const unsigned char *mask)
{
    snapshot_copy((film_snapshot *)s, f, mask, false);
}

rgb film_snapshot_pixel(const film_snapshot *s, const film *f, int px, int py,
                        double imaging_ratio)
{
    size_t i = film_index(f, px, py);
    return pixel_value((const film_pixel *)s->doubles[0] + (s->identity ? i : s->slot[i]),
                       imaging_ratio);
}

/* West (1979): the weighted form of Welford's update, with weight aw > 0. */
static inline void moments_add(film_moments *m, double aw, rgb L)
{
    double x[3] = {L.r, L.g, L.b};
    m->w += aw;
    m->w2 += aw * aw;
    double k = aw / m->w;
    for (int c = 0; c < 3; c++) {
        double d = x[c] - m->mean[c];
        m->mean[c] += k * d;
        m->m2[c] += aw * d * (x[c] - m->mean[c]);
    }
}

void film_add_sample(film *f, int px, int py, rgb L, double weight, double depth)
{
    if (!isfinite(L.r) || !isfinite(L.g) || !isfinite(L.b) || !isfinite(weight)) {
        atomic_fetch_add_explicit(&f->nonfinite, 1, memory_order_relaxed);
        return;
    }
    /* pbrt-v4 clamps the sensor value, i.e. after the imaging ratio, in the
     * sensor's RGB, and turns it into output RGB when it writes the image
     * (a linear map, so applying it per sample gives the same mean). */
    const film_sensor *sensor = &f->p.sensor;
    if (sensor->active && !f->sensor_rgb_in)
        L = sensor_apply(sensor->sensor_from_render, L);
    if (f->p.max_component_value < INFINITY) {
        /* The sensor RGB of pbrt-v4's default "cie1931" sensor is XYZ. */
        double m =
            rgb_max(sensor->active ? L : sensor_apply(f->xyz_from_render, L)) * f->clamp_ratio;
        if (m > f->p.max_component_value)
            L = rgb_scale(L, f->p.max_component_value / m);
    }
    if (sensor->active)
        L = sensor_apply(sensor->output_from_sensor, L);
    size_t i = film_index(f, px, py);
    film_pixel *p = &f->pixels[i];
    p->r += weight * L.r;
    p->g += weight * L.g;
    p->b += weight * L.b;
    p->w += weight;
    if (f->depth && isfinite(depth)) {
        f->depth[i].sum += fabs(weight) * depth;
        f->depth[i].w += fabs(weight);
    }
    if (f->moments && weight != 0.0)
        moments_add(&f->moments[i], fabs(weight), L);
    if (f->count && f->count[i] != UINT32_MAX)
        f->count[i]++;
}

void film_add_black(film *f, int px, int py, double weight)
{
    if (!isfinite(weight)) {
        atomic_fetch_add_explicit(&f->nonfinite, 1, memory_order_relaxed);
        return;
    }
    /* The colour sums stay as they are: a black sample adds weight * 0 (or
     * -0, which changes no sum: they start at +0). */
    size_t i = film_index(f, px, py);
    f->pixels[i].w += weight;
    if (f->moments && weight != 0.0)
        moments_add(&f->moments[i], fabs(weight), rgb_grey(0.0));
    if (f->count && f->count[i] != UINT32_MAX)
        f->count[i]++;
}

bool film_wants_surface(const film *f) { return f->gbuf != NULL; }

void film_set_output_from_render(film *f, transform output_from_render)
{
    f->output_from_render = output_from_render;
}

static void add3(double *sum, double w, vec3 v)
{
    sum[0] += w * v.x;
    sum[1] += w * v.y;
    sum[2] += w * v.z;
}

void film_add_surface(film *f, int px, int py, double weight, const film_surface *s)
{
    assert(f->gbuf);
    if (!isfinite(weight))
        return; /* film_add_sample counted it */
    film_gbuffer *g = &f->gbuf[film_index(f, px, py)];
    if (!s->hit)
        return;
    g->albedo[0] += weight * s->albedo.r;
    g->albedo[1] += weight * s->albedo.g;
    g->albedo[2] += weight * s->albedo.b;
    g->w += weight;
    add3(g->p, weight, s->p);
    add3(g->n, weight, s->n);
    add3(g->ns, weight, s->ns);
    g->uv[0] += weight * s->u;
    g->uv[1] += weight * s->v;
    /* The slopes of depth in the output space (camera: z; world: z too, as
     * pbrt-v4). */
    g->dz[0] += weight * transform_vector(&f->output_from_render, s->dpdx).z;
    g->dz[1] += weight * transform_vector(&f->output_from_render, s->dpdy).z;
}

rgb film_get_pixel(const film *f, int px, int py, double imaging_ratio)
{
    return pixel_value(&f->pixels[film_index(f, px, py)], imaging_ratio);
}

rgb film_get_variance(const film *f, int px, int py, double imaging_ratio)
{
    assert(f->moments);
    const film_moments *m = &f->moments[film_index(f, px, py)];
    /* (M2 / W) / (n_eff - 1) with n_eff = W^2 / W2, i.e. M2 W2 / (W (W^2 - W2)). */
    double excess = m->w * m->w - m->w2;
    if (!(m->w > 0.0) || !(excess > 0.0))
        return rgb_grey(0.0); /* n_eff <= 1 */
    double s = imaging_ratio * imaging_ratio * m->w2 / (m->w * excess);
    return rgb_make(m->m2[0] * s, m->m2[1] * s, m->m2[2] * s);
}

bool film_keeps_statistics(const film *f) { return f->moments && f->count; }

long film_get_sample_count(const film *f, int px, int py)
{
    assert(f->count);
    return (long)f->count[film_index(f, px, py)];
}

static double film_get_depth(const film *f, int px, int py)
{
    const film_depth *d = &f->depth[film_index(f, px, py)];
    return d->w > 0.0 ? d->sum / d->w : INFINITY;
}

hz_status film_write_exr(const film *f, const char *path, double imaging_ratio, hz_error *err)
{
    return film_write_exr_with(f, path, imaging_ratio, NULL, err);
}

hz_status film_write_png(const film *f, const char *path, double imaging_ratio, hz_error *err)
{
    return film_write_png_with(f, path, imaging_ratio, NULL, err);
}

/* The EXR's channels, in order: R G B A, then Z (write_z), the gbuffer's
 * (pbrt-v4's names and order), the variances and the sample count. */
enum { MAX_CHANNELS = 4 + 1 + GBUFFER_OUT + 6 + 1 };

static int exr_channel_names(const film *f, char names[][64])
{
    static const char *const rgba[] = {"R", "G", "B", "A"};
    static const char *const gbuffer[GBUFFER_OUT] = {
        "Albedo.R", "Albedo.G", "Albedo.B", "P.X", "P.Y", "P.Z", "dzdx", "dzdy",
        "N.X",      "N.Y",      "N.Z",      "Ns.X", "Ns.Y", "Ns.Z", "u",  "v"};
    int n = 0;
    for (int c = 0; c < 4; ++c)
        snprintf(names[n++], 64, "%s", rgba[c]);
    if (f->depth)
        snprintf(names[n++], 64, "Z");
    for (int c = 0; f->gbuf && c < GBUFFER_OUT; ++c)
        snprintf(names[n++], 64, "%s", gbuffer[c]);
    for (int c = 0; f->moments && c < 3; ++c)
        snprintf(names[n++], 64, "Variance.%s", rgba[c]);
    for (int c = 0; f->gbuf && c < 3; ++c)
        snprintf(names[n++], 64, "RelativeVariance.%s", rgba[c]);
    if (f->count)
        snprintf(names[n++], 64, "SampleCount.Y");
    return n;
}

/* A vector's components from the sums s divided by w (0 when w is 0). */
static vec3 mean3(const double *s, double w)
{
    return w != 0.0 ? v3(s[0] / w, s[1] / w, s[2] / w) : v3(0.0, 0.0, 0.0);
}

static float *put3(float *o, vec3 v)
{
    o[0] = (float)v.x;
    o[1] = (float)v.y;
    o[2] = (float)v.z;
    return o + 3;
}

/* Pixel (px, py)'s gbuffer channels (GBUFFER_OUT values). */
static float *gbuffer_values(const film *f, size_t i, float *o)
{
    const film_gbuffer *g = &f->gbuf[i];
    double w = f->pixels[i].w;
    o = put3(o, mean3(g->albedo, w));
    vec3 p = mean3(g->p, g->w);
    o = put3(o, g->w != 0.0 ? transform_point(&f->output_from_render, p) : p);
    *o++ = g->w != 0.0 ? (float)fabs(g->dz[0] / g->w) : 0.0f;
    *o++ = g->w != 0.0 ? (float)fabs(g->dz[1] / g->w) : 0.0f;
    const double *normals[2] = {g->n, g->ns};
    for (int k = 0; k < 2; ++k) {
        vec3 n = transform_normal(&f->output_from_render, mean3(normals[k], 1.0));
        o = put3(o, v3_length_sq(n) > 0.0 ? v3_normalize(n) : n);
    }
    *o++ = g->w != 0.0 ? (float)(g->uv[0] / g->w) : 0.0f;
    *o++ = g->w != 0.0 ? (float)(g->uv[1] / g->w) : 0.0f;
    return o;
}

/* pbrt-v4's GBufferFilm variances: of the samples (not of their mean, as
 * film_get_variance), and that over the sample mean (pbrt-v4's
 * RelativeVariance: 0 where the mean is 0). */
static float *sample_variances(const film *f, int px, int py, double ratio, float *o)
{
    const film_moments *m = &f->moments[film_index(f, px, py)];
    rgb var = film_get_variance(f, px, py, ratio);
    double n_eff = m->w2 > 0.0 ? m->w * m->w / m->w2 : 0.0;
    double v[3] = {var.r * n_eff, var.g * n_eff, var.b * n_eff};
    for (int c = 0; c < 3; ++c)
        o[c] = (float)v[c];
    for (int c = 0; c < 3; ++c) {
        double mean = m->mean[c] * ratio;
        o[3 + c] = mean != 0.0 ? (float)(v[c] / mean) : 0.0f;
    }
    return o + 6;
}

/* Pixel (px, py)'s values in exr_channel_names's order. */
static void exr_channel_values(const film *f, int px, int py, double ratio, float *o)
{
    size_t i = film_index(f, px, py);
    rgb v = film_get_pixel(f, px, py, ratio);
    *o++ = (float)v.r;
    *o++ = (float)v.g;
    *o++ = (float)v.b;
    *o++ = f->pixels[i].w != 0.0 ? 1.0f : 0.0f;
    if (f->depth)
        *o++ = (float)film_get_depth(f, px, py);
    if (f->gbuf)
        o = gbuffer_values(f, i, o);
    if (f->gbuf) {
        o = sample_variances(f, px, py, ratio, o);
    } else if (f->moments) {
        rgb var = film_get_variance(f, px, py, ratio);
        *o++ = (float)var.r;
        *o++ = (float)var.g;
        *o++ = (float)var.b;
    }
    if (f->count)
        *o++ = (float)f->count[i];
}

/* What exr_fill_lines makes the image's lines from. */
typedef struct {
    const film *f;
    double ratio;
    int nc;
} exr_fill_job;

/* exr_image.fill: lines [y0, y1) of the image's channels from the film,
 * made by the writer's threads as they compress them. A film with colour
 * and alpha only (no AOV) skips exr_channel_values' per-pixel dispatch. */
static void exr_fill_lines(void *ctx, int y0, int y1, float *const *pixels)
{
    const exr_fill_job *job = ctx;
    const film *f = job->f;
    size_t first = (size_t)y0 * (size_t)f->width, end = (size_t)y1 * (size_t)f->width;
    if (!f->depth && !f->gbuf && !f->moments && !f->count) {
        assert(job->nc == 4);
        float *r = pixels[0], *g = pixels[1], *b = pixels[2], *a = pixels[3];
        for (size_t i = first; i < end; ++i) {
            rgb v = pixel_value(&f->pixels[i], job->ratio);
            r[i - first] = (float)v.r;
            g[i - first] = (float)v.g;
            b[i - first] = (float)v.b;
            a[i - first] = f->pixels[i].w != 0.0 ? 1.0f : 0.0f;
        }
        return;
    }
    float values[MAX_CHANNELS];
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < f->width; x++) {
            size_t i = (size_t)y * (size_t)f->width + (size_t)x;
            exr_channel_values(f, x + f->p.bounds.x0, y + f->p.bounds.y0, job->ratio, values);
            for (int c = 0; c < job->nc; c++)
                pixels[c][i - first] = values[c];
        }
}

hz_status film_write_exr_with(const film *f, const char *path, double imaging_ratio,
                              const film_output *out, hz_error *err)
{
    imaging_ratio *= f->p.scale;
    exr_image img;
    char names[MAX_CHANNELS][64];
    int nc = exr_channel_names(f, names);
    if (exr_image_alloc_lines(&img, f->width, f->height, nc, err) != HZ_OK)
        return HZ_ERROR;
    if (f->p.color_space != COLOR_SPACE_SRGB) {
        double xy[8];
        color_space_chromaticities(f->p.color_space, xy);
        img.has_chromaticities = true;
        for (int i = 0; i < 8; ++i)
            img.chromaticities[i] = (float)xy[i];
    }
    /* The AOVs need float precision (a variance is tiny, a count exceeds
     * half's 2048 exact integers, positions are large). */
    for (int c = 0; c < nc; c++) {
        snprintf(img.channels[c].name, sizeof img.channels[c].name, "%s", names[c]);
        img.channels[c].half = f->p.savefp16 && c < 4;
    }
    img.data_x0 = f->p.bounds.x0;
    img.data_y0 = f->p.bounds.y0;
    img.display_width = f->p.xres;
    img.display_height = f->p.yres;
    img.threads = out ? out->threads : 0;
    exr_fill_job job = {.f = f, .ratio = imaging_ratio, .nc = nc};
    img.fill = exr_fill_lines;
    img.fill_ctx = &job;
    hz_status st = exr_image_add_attribute(&img, "software", "haze " HAZE_VERSION, err);
    for (int a = 0; out && st == HZ_OK && a < out->attribute_count; a++)
        st = exr_image_add_attribute(&img, out->attributes[a].name, out->attributes[a].value, err);
    if (st == HZ_OK)
        st = exr_write_noted(path, &img, out ? out->note : NULL, err);
    exr_image_free(&img);
    return st;
}

hz_status film_write_png_with(const film *f, const char *path, double imaging_ratio,
                              const film_output *out, hz_error *err)
{
    imaging_ratio *= f->p.scale;
    size_t n = (size_t)f->width * (size_t)f->height;
    uint8_t *buf = malloc(n * 3);
    if (!buf)
        return hz_fail(err, "%s: out of memory for the PNG", path);
    double to_srgb[9]; /* a PNG is sRGB */
    color_space_convert_matrix(f->p.color_space, COLOR_SPACE_SRGB, to_srgb);
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            rgb v = film_get_pixel(f, x + f->p.bounds.x0, y + f->p.bounds.y0, imaging_ratio);
            if (f->p.color_space != COLOR_SPACE_SRGB)
                v = sensor_apply(to_srgb, v);
            uint8_t *o = buf + ((size_t)y * (size_t)f->width + (size_t)x) * 3;
            o[0] = png_out_srgb8(v.r);
            o[1] = png_out_srgb8(v.g);
            o[2] = png_out_srgb8(v.b);
        }
    hz_status st =
        png_out_write_rgb8_noted(path, f->width, f->height, buf, out ? out->note : NULL, err);
    free(buf);
    return st;
}
