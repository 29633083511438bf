/* `haze info FILE`: see info.h. Output goes to a memory stream first and is
 * copied to the caller's stream only on success, so a file that fails halfway
 * (a truncated VDB, a scene with an error) prints just the one error line. */
#define _POSIX_C_SOURCE 200809L
#include "cli/info.h"

#include "core/file.h"
#include "core/text.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

#include "film/exr.h"
#include "integrator/integrator.h"
#include "materials/measured_data.h"
#include "media/vdb_load.h"
#include "scene/scene_desc.h"

typedef enum { KIND_VDB, KIND_NVDB, KIND_EXR, KIND_BSDF, KIND_TEXT, KIND_UNKNOWN } file_kind;

static bool is_text(const unsigned char *buf, size_t n)
{
    /* No NUL and no control characters but whitespace (UTF-8 passes). */
    for (size_t i = 0; i < n; i++)
        if (buf[i] < 0x20 && buf[i] != '\t' && buf[i] != '\n' && buf[i] != '\r' &&
            buf[i] != '\f' && buf[i] != '\v')
            return false;
    return true;
}

/* Text is taken for a scene when it is named *.pbrt, or when its first word
 * (after blank space and # comments) is shaped like a pbrt directive: every
 * one is a capitalised word of letters (LookAt, Camera, WorldBegin). Other
 * text, down to a single stray byte, is then "not a scene" rather than a
 * parse error about its first word. */
static bool looks_like_scene(const char *path, const unsigned char *buf, size_t n)
{
    size_t len = strlen(path);
    if (len > 5 && strcmp(path + len - 5, ".pbrt") == 0)
        return true;
    size_t i = 0;
    for (;;) {
        while (i < n && (buf[i] == ' ' || (buf[i] >= '\t' && buf[i] <= '\r')))
            i++;
        if (i == n || buf[i] != '#')
            break;
        while (i < n && buf[i] != '\n')
            i++;
    }
    if (i == n || buf[i] < 'A' || buf[i] > 'Z')
        return false;
    while (i < n && ((buf[i] >= 'A' && buf[i] <= 'Z') || (buf[i] >= 'a' && buf[i] <= 'z')))
        i++;
    return i == n || buf[i] <= ' ' || buf[i] == '"' || buf[i] == '[' || buf[i] == '#';
}

/* Reads the first bytes of the file and tells the format from them. */
static hz_status sniff(const char *path, file_kind *kind, hz_error *err)
{
    int fd;
    off_t size;
    hz_error ferr;
    if (file_open_regular(path, &fd, &size, &ferr) != HZ_OK)
        return hz_fail(err, "%s: cannot open file (%s)", path, ferr.message);
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        close(fd);
        return hz_fail(err, "%s: cannot open file (%s)", path, strerror(errno));
    }
    unsigned char buf[4096];
    size_t n = fread(buf, 1, sizeof buf, f);
    bool read_error = ferror(f) != 0;
    int read_errno = errno;
    fclose(f);
    if (read_error)
        return hz_fail(err, "%s: cannot read file (%s)", path, strerror(read_errno));
    if (n == 0)
        return hz_fail(err, "%s: file is empty", path);

    static const unsigned char vdb_magic[4] = {0x20, 0x42, 0x44, 0x56}; /* 0x56444220 LE */
    static const unsigned char exr_magic[4] = {0x76, 0x2f, 0x31, 0x01}; /* 20000630 LE */
    if (n >= 4 && !memcmp(buf, vdb_magic, 4)) {
        *kind = KIND_VDB;
    } else if (n >= 8 && !memcmp(buf, "NanoVDB", 7)) {
        *kind = KIND_NVDB; /* "NanoVDB0" (grid), "NanoVDB1"/"NanoVDB2" (newer files) */
    } else if (n >= 4 && !memcmp(buf, exr_magic, 4)) {
        *kind = KIND_EXR;
    } else if (n >= 12 && !memcmp(buf, "tensor_file", 12)) {
        *kind = KIND_BSDF;
    } else {
        *kind = is_text(buf, n) && looks_like_scene(path, buf, n) ? KIND_TEXT : KIND_UNKNOWN;
    }
    return HZ_OK;
}

/* ------------------------------------------------------------------ VDB */

typedef struct {
    FILE *out;
    int count;
} vdb_ctx;

static void print_ivec(FILE *out, const int32_t v[3])
{
    fprintf(out, "[%d, %d, %d]", (int)v[0], (int)v[1], (int)v[2]);
}

static void print_dvec(FILE *out, const double v[3])
{
    fprintf(out, "[%.6g, %.6g, %.6g]", v[0], v[1], v[2]);
}

static bool is_vector_type(const char *type)
{
    return !strncmp(type, "vec", 3) || !strncmp(type, "Vec", 3);
}

static void vdb_grid(const vdb_grid_info *g, void *user)
{
    vdb_ctx *c = user;
    FILE *out = c->out;
    c->count++;
    fprintf(out, "\ngrid \"%s\"\n", g->name);
    fprintf(out, "  %-15s %s\n", "type", g->type);
    fprintf(out, "  %-15s %llu\n", "active voxels", (unsigned long long)g->active_voxels);
    if (g->active_voxels == 0) {
        fprintf(out, "  %-15s (none: the grid has no active voxels)\n", "index bounds");
    } else {
        fprintf(out, "  %-15s ", "index bounds");
        print_ivec(out, g->index_min);
        fprintf(out, " .. ");
        print_ivec(out, g->index_max);
        fprintf(out, "  (%lld x %lld x %lld)\n",
                (long long)g->index_max[0] - g->index_min[0] + 1,
                (long long)g->index_max[1] - g->index_min[1] + 1,
                (long long)g->index_max[2] - g->index_min[2] + 1);
        fprintf(out, "  %-15s ", "world bounds");
        print_dvec(out, g->world_min);
        fprintf(out, " .. ");
        print_dvec(out, g->world_max);
        fprintf(out, "\n");
    }
    fprintf(out, "  %-15s ", "voxel size");
    if (g->voxel_size[0] == g->voxel_size[1] && g->voxel_size[1] == g->voxel_size[2])
        fprintf(out, "%.6g\n", g->voxel_size[0]);
    else
        fprintf(out, "%.6g x %.6g x %.6g\n", g->voxel_size[0], g->voxel_size[1], g->voxel_size[2]);
    if (g->has_range) {
        bool vec = is_vector_type(g->type);
        fprintf(out, "  %-15s %.6g .. %.6g%s\n", "value range", g->min_value, g->max_value,
                vec ? "  (vector length)" : "");
    } else {
        fprintf(out, "  %-15s %s\n", "value range",
                g->active_voxels ? "(not computed for this type)" : "(no active values)");
    }
}

static hz_status describe_vdb(const char *path, file_kind kind, FILE *out, hz_error *err)
{
    vdb_ctx c = {out, 0};
    fprintf(out, "%s: %s\n", path, kind == KIND_VDB ? "OpenVDB file" : "NanoVDB file");
    if (vdb_list_grids(path, vdb_grid, &c, err->message, sizeof err->message) != HZ_OK)
        return HZ_ERROR;
    fprintf(out, "\n%d grid%s\n", c.count, c.count == 1 ? "" : "s");
    return HZ_OK;
}

/* ------------------------------------------------------------------ EXR */

static void exr_silent(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    (void)code;
    (void)msg;
}

static const char *compression_name(int c)
{
    static const char *names[] = {"none", "rle", "zips", "zip", "piz",
                                  "pxr24", "b44", "b44a", "dwaa", "dwab"};
    return c >= 0 && c < (int)(sizeof names / sizeof names[0]) ? names[c] : "unknown";
}

static void print_attribute(FILE *out, const exr_attribute_t *a)
{
    fprintf(out, "  %-20s %-16s ", a->name, a->type_name);
    switch (a->type) {
    case EXR_ATTR_BOX2I:
        fprintf(out, "(%d, %d) .. (%d, %d)", a->box2i->min.x, a->box2i->min.y, a->box2i->max.x,
                a->box2i->max.y);
        break;
    case EXR_ATTR_BOX2F:
        fprintf(out, "(%g, %g) .. (%g, %g)", a->box2f->min.x, a->box2f->min.y, a->box2f->max.x,
                a->box2f->max.y);
        break;
    case EXR_ATTR_CHLIST:
        fprintf(out, "%d channel%s", a->chlist->num_channels, a->chlist->num_channels == 1 ? "" : "s");
        break;
    case EXR_ATTR_COMPRESSION:
        fprintf(out, "%s", compression_name(a->uc));
        break;
    case EXR_ATTR_LINEORDER:
        fprintf(out, "%s", a->uc == EXR_LINEORDER_INCREASING_Y   ? "increasing y"
                           : a->uc == EXR_LINEORDER_DECREASING_Y ? "decreasing y"
                           : a->uc == EXR_LINEORDER_RANDOM_Y     ? "random y"
                                                                 : "unknown");
        break;
    case EXR_ATTR_ENVMAP:
        fprintf(out, "%s", a->uc == EXR_ENVMAP_LATLONG ? "latlong"
                           : a->uc == EXR_ENVMAP_CUBE  ? "cube"
                                                       : "unknown");
        break;
    case EXR_ATTR_FLOAT: fprintf(out, "%g", a->f); break;
    case EXR_ATTR_DOUBLE: fprintf(out, "%g", a->d); break;
    case EXR_ATTR_INT: fprintf(out, "%d", a->i); break;
    case EXR_ATTR_STRING:
        fprintf(out, "\"%.*s\"", a->string->length, a->string->str ? a->string->str : "");
        break;
    case EXR_ATTR_STRING_VECTOR:
        fprintf(out, "%d string%s", a->stringvector->n_strings,
                a->stringvector->n_strings == 1 ? "" : "s");
        break;
    case EXR_ATTR_FLOAT_VECTOR:
        fprintf(out, "%d float%s", a->floatvector->length, a->floatvector->length == 1 ? "" : "s");
        break;
    case EXR_ATTR_RATIONAL:
        fprintf(out, "%d/%u", a->rational->num, a->rational->denom);
        break;
    case EXR_ATTR_V2I: fprintf(out, "(%d, %d)", a->v2i->x, a->v2i->y); break;
    case EXR_ATTR_V2F: fprintf(out, "(%g, %g)", a->v2f->x, a->v2f->y); break;
    case EXR_ATTR_V2D: fprintf(out, "(%g, %g)", a->v2d->x, a->v2d->y); break;
    case EXR_ATTR_V3I: fprintf(out, "(%d, %d, %d)", a->v3i->x, a->v3i->y, a->v3i->z); break;
    case EXR_ATTR_V3F: fprintf(out, "(%g, %g, %g)", a->v3f->x, a->v3f->y, a->v3f->z); break;
    case EXR_ATTR_V3D: fprintf(out, "(%g, %g, %g)", a->v3d->x, a->v3d->y, a->v3d->z); break;
    case EXR_ATTR_CHROMATICITIES:
        fprintf(out, "r (%g, %g) g (%g, %g) b (%g, %g) w (%g, %g)", a->chromaticities->red_x,
                a->chromaticities->red_y, a->chromaticities->green_x, a->chromaticities->green_y,
                a->chromaticities->blue_x, a->chromaticities->blue_y, a->chromaticities->white_x,
                a->chromaticities->white_y);
        break;
    case EXR_ATTR_TILEDESC:
        fprintf(out, "%ux%u tiles", a->tiledesc->x_size, a->tiledesc->y_size);
        break;
    default: fprintf(out, "(not shown)"); break;
    }
    fprintf(out, "\n");
}

/* All header attributes of the first part, sorted by name. */
static hz_status exr_attributes(const char *path, FILE *out, hz_error *err)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_silent;
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    int32_t count = 0;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_attribute_count(ctx, 0, &count);
    if (rv != EXR_ERR_SUCCESS) {
        if (ctx)
            exr_finish(&ctx);
        return hz_fail(err, "%s: cannot read EXR header: %s", path, exr_get_default_error_message(rv));
    }
    fprintf(out, "attributes (%d)\n", (int)count);
    for (int32_t i = 0; i < count; i++) {
        const exr_attribute_t *a = NULL;
        if (exr_get_attribute_by_index(ctx, 0, EXR_ATTR_LIST_SORTED_ORDER, i, &a) == EXR_ERR_SUCCESS && a)
            print_attribute(out, a);
    }
    exr_finish(&ctx);
    return HZ_OK;
}

static hz_status describe_exr(const char *path, FILE *out, hz_error *err)
{
    exr_image img;
    if (exr_read(path, &img, err) != HZ_OK)
        return HZ_ERROR;
    fprintf(out, "%s: OpenEXR image\n", path);
    fprintf(out, "  %-15s %d x %d\n", "size", img.width, img.height);
    /* The file's own coordinates (exr_image counts from the display window's
     * corner). */
    long long dx = img.file_display_x0, dy = img.file_display_y0;
    fprintf(out, "  %-15s (%lld, %lld) .. (%lld, %lld)\n", "data window", dx + img.data_x0,
            dy + img.data_y0, dx + img.data_x0 + img.width - 1, dy + img.data_y0 + img.height - 1);
    fprintf(out, "  %-15s (%lld, %lld) .. (%lld, %lld)  (%d x %d)\n", "display window", dx, dy,
            dx + img.display_width - 1, dy + img.display_height - 1, img.display_width,
            img.display_height);
    fprintf(out, "\nchannels (%d)\n", img.channel_count);
    fprintf(out, "  %-14s %-6s %12s %12s %12s %8s %8s\n", "name", "type", "min", "max", "mean", "NaN",
            "Inf");
    size_t pixels = (size_t)img.width * (size_t)img.height;
    for (int c = 0; c < img.channel_count; c++) {
        const exr_channel *ch = &img.channels[c];
        double lo = INFINITY, hi = -INFINITY, sum = 0.0;
        size_t nan = 0, inf = 0, finite = 0;
        for (size_t i = 0; i < pixels; i++) {
            float v = ch->pixels[i];
            if (isnan(v)) {
                nan++;
            } else if (isinf(v)) {
                inf++;
            } else {
                finite++;
                sum += v;
                if (v < lo)
                    lo = v;
                if (v > hi)
                    hi = v;
            }
        }
        fprintf(out, "  %-14s %-6s ", ch->name, ch->half ? "half" : "float");
        if (finite)
            fprintf(out, "%12.6g %12.6g %12.6g", lo, hi, sum / (double)finite);
        else
            fprintf(out, "%12s %12s %12s", "-", "-", "-");
        fprintf(out, " %8zu %8zu\n", nan, inf);
    }
    exr_image_free(&img);
    fprintf(out, "\n");
    return exr_attributes(path, out, err);
}

/* ----------------------------------------------------------------- pbrt */

/* A parameter's first number, without marking it used; `def` when absent. */
static double param_num(const param_list *pl, const char *name, double def, bool *present)
{
    for (size_t i = 0; i < pl->count; i++) {
        const param *p = &pl->items[i];
        if (!strcmp(p->name, name) && p->nums && p->count > 0) {
            if (present)
                *present = true;
            return p->nums[0];
        }
    }
    if (present)
        *present = false;
    return def;
}

static hz_status describe_pbrt(const char *path, FILE *out, hz_error *err)
{
    scene_desc sd;
    if (scene_parse_file(path, &sd, err) != HZ_OK)
        return HZ_ERROR;
    fprintf(out, "%s: pbrt-v4 scene\n", path);

    bool has;
    double fov = param_num(&sd.camera.entity.params, "fov", 90, &has);
    fprintf(out, "  %-15s %s", "camera", sd.camera.entity.type);
    if (!strcmp(sd.camera.entity.type, "perspective"))
        fprintf(out, ", fov %g%s", fov, has ? "" : " (default)");
    fprintf(out, "\n");

    bool hx, hy;
    int xres = (int)param_num(&sd.film.params, "xresolution", 1280, &hx);
    int yres = (int)param_num(&sd.film.params, "yresolution", 720, &hy);
    fprintf(out, "  %-15s %s, %d x %d%s, \"%s\"\n", "film", sd.film.type, xres, yres,
            hx || hy ? "" : " (default)", params_peek_string(&sd.film.params, "filename", "pbrt.exr"));

    int spp = (int)param_num(&sd.sampler.params, "pixelsamples", 16, &has);
    fprintf(out, "  %-15s %s, %d spp%s\n", "sampler", sd.sampler.type, spp, has ? "" : " (default)");
    fprintf(out, "  %-15s %s\n", "filter", sd.filter.type);
    /* No Integrator directive (line 0): haze renders with its default. */
    const char *why, *what;
    if (strcmp(sd.integrator.type, "singlescatter") == 0 ||
        (sd.integrator.loc.line == 0 &&
         integrator_default_kind(&sd, &why, &what) == INTEGRATOR_SINGLESCATTER)) {
        fprintf(out, "  %-15s %s, transmittance %s, step %g voxels, shadow step %g voxels\n",
                "integrator", "singlescatter",
                params_peek_string(&sd.integrator.params, "transmittance", "jittered"),
                param_num(&sd.integrator.params, "stepsize", 1.0, &has),
                param_num(&sd.integrator.params, "shadowstepsize", 2.0, &has));
    } else {
        int depth = (int)param_num(&sd.integrator.params, "maxdepth", 5, &has);
        fprintf(out, "  %-15s %s, max depth %d%s", "integrator", sd.integrator.type, depth,
                has ? "" : " (default)");
        /* volpath's own knobs, where the scene sets them. */
        double cache = param_num(&sd.integrator.params, "shadowcache", 0.0, NULL);
        double step = param_num(&sd.integrator.params, "stepsize", 0.0, NULL);
        double splits = param_num(&sd.integrator.params, "mediumsplits", 1.0, NULL);
        if (cache > 0.0)
            fprintf(out, ", shadow cache %g voxels", cache);
        if (step > 0.0)
            fprintf(out, ", marched at %g voxels", step);
        if (splits > 1.0)
            fprintf(out, ", %g continuations from the first medium vertex", splits);
        fprintf(out, "\n");
    }

    size_t area = 0;
    for (size_t i = 0; i < sd.shape_count; i++)
        area += sd.shapes[i].has_area_light;
    for (size_t i = 0; i < sd.object_shape_count; i++)
        area += sd.object_shapes[i].has_area_light;
    size_t named = 0;
    for (size_t i = 0; i < sd.material_count; i++)
        named += sd.materials[i].name != NULL;

    fprintf(out, "\n");
    fprintf(out, "  %-15s %zu", "shapes", sd.shape_count);
    if (sd.object_shape_count)
        fprintf(out, " (+ %zu in %zu object%s)", sd.object_shape_count, sd.object_count,
                sd.object_count == 1 ? "" : "s");
    fprintf(out, "\n");
    fprintf(out, "  %-15s %zu (+ %zu area light%s)\n", "lights", sd.light_count, area,
            area == 1 ? "" : "s");
    fprintf(out, "  %-15s %zu (%zu named)\n", "materials", sd.material_count, named);
    fprintf(out, "  %-15s %zu\n", "instances", sd.instance_count);
    fprintf(out, "  %-15s %zu\n", "media", sd.medium_count);
    scene_desc_free(&sd);
    return HZ_OK;
}

/* ------------------------------------------------------------------------ */

/* Names and strings come from the file: each line goes out with control
 * bytes and invalid UTF-8 escaped (an escape sequence in a grid name must not
 * reach the terminal). */
static void print_escaped(FILE *out, const char *text, size_t size)
{
    char line[4 * 4096 + 1];
    for (size_t start = 0; start < size;) {
        const char *nl = memchr(text + start, '\n', size - start);
        size_t end = nl ? (size_t)(nl - text) : size;
        for (size_t chunk = start; chunk < end; chunk += 4096) {
            text_escape(text + chunk, end - chunk < 4096 ? end - chunk : 4096, line, sizeof line);
            fputs(line, out);
        }
        if (nl)
            fputc('\n', out);
        start = end + 1;
    }
}

/* ----------------------------------------------------------------- BSDF */

/* An RGL tensor file: its fields, then whether it is a measured BRDF haze
 * renders (Material "measured") and what it holds, or why not. */
static hz_status describe_bsdf(const char *path, FILE *out, hz_error *err)
{
    tensor_file *t = NULL;
    if (tensor_file_read(path, &t, err) != HZ_OK)
        return HZ_ERROR;
    fprintf(out, "%s: tensor file, %zu fields\n", path, tensor_file_field_count(t));
    for (size_t i = 0; i < tensor_file_field_count(t); ++i) {
        const tensor_field *f = tensor_file_field_at(t, i);
        fprintf(out, "  %-12s %-8s [", f->name, tensor_dtype_name(f->dtype));
        for (int j = 0; j < f->ndim; ++j)
            fprintf(out, "%s%llu", j ? ", " : "", (unsigned long long)f->shape[j]);
        fprintf(out, "]\n");
    }
    const tensor_field *d = tensor_file_field(t, "description");
    if (d && d->dtype == TENSOR_U8)
        fprintf(out, "  description: %.*s\n", (int)(d->count < 400 ? d->count : 400),
                (const char *)d->data);
    measured_brdf *m = NULL;
    hz_error e;
    if (measured_brdf_from_tensor(t, &m, &e) == HZ_OK) {
        const tensor_field *th = tensor_file_field(t, "theta_i");
        const tensor_field *ph = tensor_file_field(t, "phi_i");
        const tensor_field *l = tensor_file_field(t, "wavelengths");
        fprintf(out, "  measured BRDF: %s, %zu x %zu incident directions, %zu wavelengths "
                     "(%g..%g nm), jacobian %d\n",
                m->isotropic ? "isotropic" : "anisotropic", th->count, ph->count, l->count,
                (double)tensor_field_f32(l, 0), (double)tensor_field_f32(l, l->count - 1),
                m->jacobian);
        measured_brdf_destroy(m);
    } else {
        fprintf(out, "  not a measured BRDF haze renders: %s\n", e.message);
    }
    tensor_file_destroy(t);
    return HZ_OK;
}

hz_status info_describe(const char *path, FILE *out, hz_error *err)
{
    hz_error local;
    if (!err)
        err = &local;
    err->message[0] = '\0';
    file_kind kind = KIND_UNKNOWN;
    if (sniff(path, &kind, err) != HZ_OK)
        return HZ_ERROR;
    if (kind == KIND_UNKNOWN)
        return hz_fail(err,
                       "%s: unrecognised file format: not a .vdb, .nvdb, .exr, .bsdf or .pbrt "
                       "file (OpenVDB, NanoVDB, OpenEXR, RGL measured BRDF or pbrt-v4 scene)",
                       path);

    char *text = NULL;
    size_t size = 0;
    FILE *mem = open_memstream(&text, &size);
    if (!mem)
        return hz_fail(err, "%s: out of memory", path);
    hz_status st;
    switch (kind) {
    case KIND_VDB:
    case KIND_NVDB: st = describe_vdb(path, kind, mem, err); break;
    case KIND_EXR: st = describe_exr(path, mem, err); break;
    case KIND_BSDF: st = describe_bsdf(path, mem, err); break;
    default: st = describe_pbrt(path, mem, err); break;
    }
    if (fclose(mem) != 0 && st == HZ_OK)
        st = hz_fail(err, "%s: out of memory", path);
    if (st == HZ_OK && text)
        print_escaped(out, text, size);
    free(text);
    return st;
}
