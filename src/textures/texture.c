#include "textures/texture.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/noise.h"
#include "core/path.h"
#include "core/file.h"
#include "textures/texture_image.h"

typedef enum {
    TEX_CONSTANT,
    TEX_SCALE,        /* in[0] * in[1] */
    TEX_MIX,          /* (1 - in[2]) in[0] + in[2] in[1] */
    TEX_CHECKERBOARD, /* in[0] on even squares, in[1] on odd ones */
    TEX_BILERP,       /* in[0..3] = v00 v01 v10 v11 */
    TEX_IMAGEMAP,
    TEX_DIRECTIONMIX, /* |n . dir| in[0] + (1 - |n . dir|) in[1] */
    TEX_DOTS,         /* in[0] in pbrt-v4's polka dots, in[1] between them */
    TEX_FBM,          /* the 3D textures: on tex_from_render p */
    TEX_WRINKLED,
    TEX_WINDY,
    TEX_MARBLE,
} texture_kind;

typedef enum { WRAP_REPEAT, WRAP_BLACK, WRAP_CLAMP, WRAP_OCTAHEDRAL } tex_wrap;

/* pbrt-v4's 2D mappings: "uv" (s = uscale u + udelta, ...), and on the point
 * in the texture's space "spherical", "cylindrical" and "planar". */
typedef enum { MAP_UV, MAP_SPHERICAL, MAP_CYLINDRICAL, MAP_PLANAR } tex_mapping;

/* (s, t) and their screen derivatives. */
typedef struct {
    double s, t, dsdx, dsdy, dtdx, dtdy;
} tex_coord;

/* A parameter that is either a texture or a constant. */
typedef struct {
    const texture *t;
    rgb v;
} tex_input;


enum { TEX_MAX_LEVELS = 32 };
typedef enum { FILTER_POINT, FILTER_BILINEAR, FILTER_TRILINEAR } tex_filter;

struct texture {
    texture_kind kind;
    bool spectrum;
    double su, sv, du, dv; /* "uv" mapping: s = su u + du, t = sv v + dv */
    tex_input in[4];
    tex_image img;            /* level 0 */
    tex_image level[TEX_MAX_LEVELS]; /* level[0] = img; each next a 2x2 box of the last */
    int levels;
    tex_filter filter;
    bool ewa;    /* "ewa" (run as trilinear): its float lookups are texel lookups */
    tex_wrap wrap;
    double scale;
    bool invert;
    vec3 dir;                  /* directionmix, render space, unit */
    transform tex_from_render; /* the 3D textures' space */
    int octaves;               /* fbm, wrinkled, marble */
    double omega;              /* their "roughness" */
    double variation;          /* marble ("scale" is its frequency) */
    tex_mapping mapping;       /* the 2D textures' (s, t) */
    vec3 v1, v2;               /* planar mapping's axes, texture space */
    bool checker3d;            /* checkerboard "dimension" 3: on tex_from_render p */
};

struct texture_set {
    const texture_entity *entities; /* the scene's, for names while building */
    transform render_from_world;    /* for the textures' own spaces */
    texture *items;
    size_t count;
    /* The materials' "normalmap" images, by file name (the scene's strings) */
    texture *normal_maps;
    const char **normal_map_names;
    size_t normal_map_count;
};

static rgb eval_input(const tex_input *in, const texture_ctx *c)
{
    return in->t ? texture_eval(in->t, c) : in->v;
}

static rgb rgb_lerp(double w, rgb a, rgb b)
{
    return rgb_add(rgb_scale(a, 1.0 - w), rgb_scale(b, w));
}

/* pbrt-v4's 2D checkerboard weight of tex2: the square's parity convolved
 * with a box of 1.5 times the larger derivative in each direction (closed
 * form of the filtered square wave). */
static double checker_d(double x)
{
    double y = x / 2.0 - floor(x / 2.0) - 0.5;
    return x / 2.0 + y * (1.0 - 2.0 * fabs(y));
}

static double checker_bf(double x, double r)
{
    if (floor(x - r) == floor(x + r))
        return 1.0 - 2.0 * (double)((long long)floor(x) & 1);
    return (checker_d(x + r) - 2.0 * checker_d(x) + checker_d(x - r)) / (r * r);
}

static double checker_weight(double s, double t, double ds, double dt)
{
    return 0.5 - checker_bf(s, 1.5 * ds) * checker_bf(t, 1.5 * dt) / 2.0;
}

/* The texel (x, y) after wrapping; false when it is black. */
static bool wrap_texel(tex_wrap w, int width, int height, int *x, int *y)
{
    switch (w) {
    case WRAP_REPEAT:
        *x = ((*x % width) + width) % width;
        *y = ((*y % height) + height) % height;
        return true;
    case WRAP_CLAMP:
        *x = *x < 0 ? 0 : *x >= width ? width - 1 : *x;
        *y = *y < 0 ? 0 : *y >= height ? height - 1 : *y;
        return true;
    case WRAP_BLACK:
        return *x >= 0 && *x < width && *y >= 0 && *y < height;
    case WRAP_OCTAHEDRAL:
        /* pbrt-v4: mirror across the edge that was crossed. */
        if (*x < 0) {
            *x = -*x - 1;
            *y = height - 1 - *y;
        } else if (*x >= width) {
            *x = 2 * width - 1 - *x;
            *y = height - 1 - *y;
        }
        if (*y < 0) {
            *x = width - 1 - *x;
            *y = -*y - 1;
        } else if (*y >= height) {
            *x = width - 1 - *x;
            *y = 2 * height - 1 - *y;
        }
        *x = *x < 0 ? 0 : *x >= width ? width - 1 : *x;
        *y = *y < 0 ? 0 : *y >= height ? height - 1 : *y;
        return true;
    }
    return false;
}

static rgb texel(const texture *t, const tex_image *im, int x, int y)
{
    if (!wrap_texel(t->wrap, im->width, im->height, &x, &y))
        return rgb_grey(0.0);
    const float *p = &im->rgb[3 * ((size_t)y * (size_t)im->width + (size_t)x)];
    return rgb_make(p[0], p[1], p[2]);
}

/* pbrt-v4's Image lookups: texel centres at (i + 0.5) / width. */
static rgb bilerp(const texture *t, const tex_image *im, double s, double tt)
{
    double x = s * im->width - 0.5, y = tt * im->height - 0.5;
    double fx = floor(x), fy = floor(y), dx = x - fx, dy = y - fy;
    int x0 = (int)fx, y0 = (int)fy;
    return rgb_add(rgb_add(rgb_scale(texel(t, im, x0, y0), (1 - dx) * (1 - dy)),
                           rgb_scale(texel(t, im, x0 + 1, y0), dx * (1 - dy))),
                   rgb_add(rgb_scale(texel(t, im, x0, y0 + 1), (1 - dx) * dy),
                           rgb_scale(texel(t, im, x0 + 1, y0 + 1), dx * dy)));
}

/* pbrt-v4's MIPMap::Filter for its non-EWA filters: the level of a filter
 * width of twice the largest st derivative; point and bilinear look up
 * that level, trilinear blends it with the next (from level 1 on). */
static rgb image_filter(const texture *t, double s, double tt, double width, bool *texel_lookup)
{
    int n = t->levels;
    double level = n - 1 + log2(fmax(width, 1e-8));
    *texel_lookup = true;
    if (level >= n - 1)
        return texel(t, &t->level[n - 1], 0, 0);
    int il = level > 0.0 ? (int)floor(level) : 0;
    const tex_image *im = &t->level[il];
    /* pbrt-v4's ewa looks texels up unless the footprint is zero. */
    *texel_lookup = t->ewa && width > 0.0;
    switch (t->filter) {
    case FILTER_POINT:
        *texel_lookup = true;
        return texel(t, im, (int)round(s * im->width - 0.5), (int)round(tt * im->height - 0.5));
    case FILTER_BILINEAR:
        return bilerp(t, im, s, tt);
    case FILTER_TRILINEAR:
        if (il == 0)
            return bilerp(t, im, s, tt);
        return rgb_lerp(level - il, bilerp(t, im, s, tt), bilerp(t, &t->level[il + 1], s, tt));
    }
    return rgb_grey(0.0);
}

/* A float texture's value: channel 0 for texel lookups, channel 1 for
 * bilinear ones (see tex_image). */
static rgb image_lookup(const texture *t, double s, double tt, double width)
{
    bool texel_lookup;
    rgb v = image_filter(t, s, tt, width, &texel_lookup);
    return t->spectrum ? v : rgb_grey(texel_lookup ? v.r : v.g);
}

/* Levels down to 1x1, each texel the mean of the 2x2 below it (clamped at
 * an odd edge); pbrt-v4 first resamples an image whose sides are not powers
 * of 2 to the next powers. */
static hz_status build_pyramid(texture *t, hz_error *err)
{
    t->level[0] = t->img;
    t->levels = 1;
    while (t->levels < TEX_MAX_LEVELS) {
        const tex_image *a = &t->level[t->levels - 1];
        if (a->width == 1 && a->height == 1)
            break;
        tex_image *b = &t->level[t->levels];
        b->width = a->width > 1 ? (a->width + 1) / 2 : 1;
        b->height = a->height > 1 ? (a->height + 1) / 2 : 1;
        b->rgb = malloc((size_t)b->width * (size_t)b->height * 3 * sizeof *b->rgb);
        if (!b->rgb)
            return hz_fail(err, "out of memory");
        ++t->levels;
        for (int y = 0; y < b->height; ++y)
            for (int x = 0; x < b->width; ++x)
                for (int c = 0; c < 3; ++c) {
                    double sum = 0;
                    for (int k = 0; k < 4; ++k) {
                        int xs = 2 * x + (k & 1), ys = 2 * y + (k >> 1);
                        xs = xs < a->width ? xs : a->width - 1;
                        ys = ys < a->height ? ys : a->height - 1;
                        sum += a->rgb[3 * ((size_t)ys * (size_t)a->width + (size_t)xs) +
                                      (size_t)c];
                    }
                    b->rgb[3 * ((size_t)y * (size_t)b->width + (size_t)x) + (size_t)c] =
                        (float)(sum / 4);
                }
    }
    return HZ_OK;
}

/* pbrt-v4's InsidePolkaDot: one dot of radius 0.35 per unit cell around
 * integer st, in the cells where noise says so, shifted by noise. */
static bool inside_polka_dot(double s, double t)
{
    float sc = floorf((float)s + 0.5f), tc = floorf((float)t + 0.5f);
    if (!(noise3(sc + 0.5f, tc + 0.5f, 0.5f) > 0.0f))
        return false;
    const float radius = 0.35f, max_shift = 0.5f - radius;
    float s0 = sc + max_shift * noise3(sc + 1.5f, tc + 2.8f, 0.5f);
    float t0 = tc + max_shift * noise3(sc + 4.5f, tc + 9.8f, 0.5f);
    float ds = (float)s - s0, dt = (float)t - t0;
    return ds * ds + dt * dt < radius * radius;
}

/* pbrt-v4's marble: a sine of the point's height, perturbed by fbm, through
 * a cubic Bezier spline of nine colours, times 1.5. */
static rgb marble(const texture *t, vec3 p, vec3 dpdx, vec3 dpdy)
{
    static const float colors[9][3] = {{.58f, .58f, .6f}, {.58f, .58f, .6f}, {.58f, .58f, .6f},
                                       {.5f, .5f, .5f},   {.6f, .59f, .58f}, {.58f, .58f, .6f},
                                       {.58f, .58f, .6f}, {.2f, .2f, .33f},  {.58f, .58f, .6f}};
    float k = (float)t->scale;
    vec3 q = v3((float)p.x * k, (float)p.y * k, (float)p.z * k);
    float m = (float)q.y + (float)t->variation * noise_fbm(q, v3_scale(dpdx, k),
                                                           v3_scale(dpdy, k),
                                                           (float)t->omega, t->octaves);
    float u = 0.5f + 0.5f * sinf(m);
    const int segments = 9 - 3;
    int first = (int)floorf(u * segments);
    first = first < segments - 1 ? first : segments - 1;
    u = u * segments - (float)first;
    float out[3];
    for (int c = 0; c < 3; ++c) { /* de Casteljau on colors[first .. first + 3] */
        float b[4];
        for (int i = 0; i < 4; ++i)
            b[i] = colors[first + i][c];
        for (int r = 3; r > 0; --r)
            for (int i = 0; i < r; ++i)
                b[i] = (1.0f - u) * b[i] + u * b[i + 1];
        out[c] = 1.5f * b[0];
    }
    return rgb_make(out[0], out[1], out[2]);
}

/* The 3D textures' point and footprint in their own space. */
static float eval_3d(const texture *t, const texture_ctx *c, rgb *spectral)
{
    vec3 p = transform_point(&t->tex_from_render, c->p);
    vec3 dx = transform_vector(&t->tex_from_render, c->dpdx);
    vec3 dy = transform_vector(&t->tex_from_render, c->dpdy);
    switch (t->kind) {
    case TEX_FBM:
        return noise_fbm(p, dx, dy, (float)t->omega, t->octaves);
    case TEX_WRINKLED:
        return noise_turbulence(p, dx, dy, (float)t->omega, t->octaves);
    case TEX_WINDY: {
        float wind = noise_fbm(v3_scale(p, 0.1f), v3_scale(dx, 0.1f), v3_scale(dy, 0.1f), 0.5f, 3);
        float wave = noise_fbm(p, dx, dy, 0.5f, 6);
        return fabsf(wind) * wave;
    }
    case TEX_MARBLE:
        *spectral = marble(t, p, dx, dy);
        return 0.0f;
    default:
        return 0.0f;
    }
}

/* The 2D mappings, as pbrt-v4's TextureMapping2D::Map. */
static tex_coord map2d(const texture *t, const texture_ctx *c)
{
    if (t->mapping == MAP_UV)
        return (tex_coord){t->su * c->u + t->du, t->sv * c->v + t->dv, t->su * c->dudx,
                           t->su * c->dudy,      t->sv * c->dvdx,      t->sv * c->dvdy};
    vec3 p = transform_point(&t->tex_from_render, c->p);
    vec3 dx = transform_vector(&t->tex_from_render, c->dpdx);
    vec3 dy = transform_vector(&t->tex_from_render, c->dpdy);
    vec3 dsdp, dtdp;
    tex_coord out;
    switch (t->mapping) {
    case MAP_SPHERICAL: {
        double x2y2 = p.x * p.x + p.y * p.y, r = sqrt(x2y2);
        dsdp = v3_scale(v3(-p.y, p.x, 0.0), 1.0 / (2.0 * HZ_PI * x2y2));
        dtdp = v3_scale(v3(p.x * p.z / r, p.y * p.z / r, -r),
                        1.0 / (HZ_PI * (x2y2 + p.z * p.z)));
        vec3 w = v3_normalize(p);
        double phi = atan2(w.y, w.x);
        out.s = acos(fmax(-1.0, fmin(1.0, w.z))) / HZ_PI; /* pbrt-v4: theta first */
        out.t = (phi < 0.0 ? phi + 2.0 * HZ_PI : phi) / (2.0 * HZ_PI);
        break;
    }
    case MAP_CYLINDRICAL: {
        double x2y2 = p.x * p.x + p.y * p.y;
        dsdp = v3_scale(v3(-p.y, p.x, 0.0), 1.0 / (2.0 * HZ_PI * x2y2));
        dtdp = v3(0.0, 0.0, 1.0);
        out.s = (HZ_PI + atan2(p.y, p.x)) / (2.0 * HZ_PI);
        out.t = p.z;
        break;
    }
    default: /* MAP_PLANAR */
        dsdp = t->v1;
        dtdp = t->v2;
        out.s = t->du + v3_dot(p, t->v1);
        out.t = t->dv + v3_dot(p, t->v2);
        break;
    }
    /* A point on the axis: no derivative (pbrt-v4 divides by zero there). */
    out.dsdx = v3_is_finite(dsdp) ? v3_dot(dsdp, dx) : 0.0;
    out.dsdy = v3_is_finite(dsdp) ? v3_dot(dsdp, dy) : 0.0;
    out.dtdx = v3_is_finite(dtdp) ? v3_dot(dtdp, dx) : 0.0;
    out.dtdy = v3_is_finite(dtdp) ? v3_dot(dtdp, dy) : 0.0;
    return out;
}

rgb texture_eval(const texture *t, const texture_ctx *c)
{
    tex_coord m = map2d(t, c);
    double s = m.s, tt = m.t;
    switch (t->kind) {
    case TEX_CONSTANT:
        return t->in[0].v;
    case TEX_SCALE:
        return rgb_scale(eval_input(&t->in[0], c), eval_input(&t->in[1], c).r);
    case TEX_MIX:
        return rgb_lerp(eval_input(&t->in[2], c).r, eval_input(&t->in[0], c),
                        eval_input(&t->in[1], c));
    case TEX_CHECKERBOARD: {
        double w;
        if (t->checker3d) {
            vec3 p = transform_point(&t->tex_from_render, c->p);
            vec3 dx = transform_vector(&t->tex_from_render, c->dpdx);
            vec3 dy = transform_vector(&t->tex_from_render, c->dpdy);
            w = 0.5 - 0.5 * checker_bf(p.x, 1.5 * fmax(fabs(dx.x), fabs(dy.x))) *
                          checker_bf(p.y, 1.5 * fmax(fabs(dx.y), fabs(dy.y))) *
                          checker_bf(p.z, 1.5 * fmax(fabs(dx.z), fabs(dy.z)));
        } else {
            w = checker_weight(s, tt, fmax(fabs(m.dsdx), fabs(m.dsdy)),
                               fmax(fabs(m.dtdx), fabs(m.dtdy)));
        }
        rgb a = w != 1.0 ? eval_input(&t->in[0], c) : rgb_grey(0.0);
        rgb b = w != 0.0 ? eval_input(&t->in[1], c) : rgb_grey(0.0);
        return rgb_lerp(w, a, b);
    }
    case TEX_BILERP:
        return rgb_add(rgb_lerp(s, rgb_scale(eval_input(&t->in[0], c), 1 - tt),
                                rgb_scale(eval_input(&t->in[2], c), 1 - tt)),
                       rgb_lerp(s, rgb_scale(eval_input(&t->in[1], c), tt),
                                rgb_scale(eval_input(&t->in[3], c), tt)));
    case TEX_IMAGEMAP: {
        double width = 2 * fmax(fmax(fabs(m.dsdx), fabs(m.dsdy)), fmax(fabs(m.dtdx), fabs(m.dtdy)));
        rgb v = rgb_scale(image_lookup(t, s, 1.0 - tt, width), t->scale);
        if (t->invert)
            v = rgb_sub(rgb_grey(1.0), v);
        else if (!t->spectrum)
            return v; /* pbrt-v4 clamps float images only when inverted */
        return rgb_make(fmax(v.r, 0.0), fmax(v.g, 0.0), fmax(v.b, 0.0));
    }
    case TEX_DIRECTIONMIX: {
        double amt = fabs(v3_dot(c->n, t->dir));
        rgb a = amt != 0.0 ? eval_input(&t->in[0], c) : rgb_grey(0.0);
        rgb b = amt != 1.0 ? eval_input(&t->in[1], c) : rgb_grey(0.0);
        return rgb_add(rgb_scale(a, amt), rgb_scale(b, 1.0 - amt));
    }
    case TEX_DOTS:
        return eval_input(&t->in[inside_polka_dot(s, tt) ? 0 : 1], c);
    case TEX_FBM:
    case TEX_WRINKLED:
    case TEX_WINDY:
    case TEX_MARBLE: {
        rgb spectral = rgb_grey(0.0);
        float v = eval_3d(t, c, &spectral);
        return t->kind == TEX_MARBLE ? spectral : rgb_grey(v);
    }
    }
    return rgb_grey(0.0);
}

double texture_eval_float(const texture *t, const texture_ctx *c)
{
    return texture_eval(t, c).r;
}

const texture *texture_set_find(const texture_set *s, const char *name, bool spectrum)
{
    if (!s)
        return NULL;
    /* The last definition before the use wins; the set is built in order. */
    for (size_t i = s->count; i-- > 0;)
        if (s->entities[i].spectrum == spectrum && strcmp(s->entities[i].name, name) == 0)
            return &s->items[i];
    return NULL;
}

/* ---- building ----------------------------------------------------------- */

/* A parameter of a texture: "texture NAME" (a float texture when `spectrum`
 * is false) or a value (float, or rgb/spectrum when `spectrum`). */
static hz_status read_input(const texture_set *s, param_list *pl, const char *name,
                            bool spectrum, rgb def, tex_input *out, hz_error *err)
{
    out->t = NULL;
    const char *ref = params_texture(pl, name);
    if (ref) {
        out->t = texture_set_find(s, ref, spectrum);
        if (!out->t)
            return hz_fail_at(err, params_loc(pl, name),
                              "\"texture %s\": no %s texture named \"%s\" defined before it",
                              name, spectrum ? "spectrum" : "float", ref);
        return HZ_OK;
    }
    out->v = spectrum ? params_rgb(pl, name, def) : rgb_grey(params_float(pl, name, def.r));
    return HZ_OK;
}

/* The texture's own space (the CTM at its Texture directive), for the
 * mappings and the 3D textures. */
static hz_status texture_space(const texture_set *s, const texture_entity *te, texture *t,
                               hz_error *err)
{
    t->tex_from_render =
        transform_inverse(transform_compose(s->render_from_world, te->world_from_texture));
    bool finite = true;
    for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k)
            finite &= isfinite(t->tex_from_render.m.m[r][k]) != 0;
    if (!finite)
        return hz_fail_at(err, te->entity.loc, "Texture \"%s\": its transform is not invertible",
                          te->name);
    return HZ_OK;
}

static hz_status read_mapping(const texture_set *s, const texture_entity *te, param_list *pl,
                              texture *t, hz_error *err)
{
    const char *mapping = params_string(pl, "mapping", "uv");
    if (strcmp(mapping, "uv") == 0) {
        t->mapping = MAP_UV;
        t->su = params_float(pl, "uscale", 1.0);
        t->sv = params_float(pl, "vscale", 1.0);
        t->du = params_float(pl, "udelta", 0.0);
        t->dv = params_float(pl, "vdelta", 0.0);
        return HZ_OK;
    }
    if (strcmp(mapping, "spherical") == 0) {
        t->mapping = MAP_SPHERICAL;
    } else if (strcmp(mapping, "cylindrical") == 0) {
        t->mapping = MAP_CYLINDRICAL;
    } else if (strcmp(mapping, "planar") == 0) {
        t->mapping = MAP_PLANAR;
        t->v1 = params_vector3(pl, "v1", v3(1, 0, 0));
        t->v2 = params_vector3(pl, "v2", v3(0, 1, 0));
        t->du = params_float(pl, "udelta", 0.0);
        t->dv = params_float(pl, "vdelta", 0.0);
    } else {
        return hz_fail_at(err, params_loc(pl, "mapping"),
                          "texture \"mapping\" \"%s\" is unknown (pbrt-v4 has \"uv\", "
                          "\"spherical\", \"cylindrical\", \"planar\")",
                          mapping);
    }
    return texture_space(s, te, t, err);
}

static hz_status read_imagemap(param_list *pl, file_loc loc, texture *t, hz_error *err)
{
    t->kind = TEX_IMAGEMAP;
    const char *filter = params_string(pl, "filter", "bilinear");
    /* ewa runs as trilinear (docs/differences-from-pbrt.md). */
    if (strcmp(filter, "point") == 0)
        t->filter = FILTER_POINT;
    else if (strcmp(filter, "bilinear") == 0)
        t->filter = FILTER_BILINEAR;
    else if (strcmp(filter, "trilinear") == 0 || strcmp(filter, "ewa") == 0 ||
             strcmp(filter, "EWA") == 0) {
        t->filter = FILTER_TRILINEAR;
        t->ewa = filter[0] != 't';
    }
    else
        return hz_fail_at(err, params_loc(pl, "filter"), "unknown \"filter\" \"%s\"", filter);
    /* pbrt-v4 reads "maxanisotropy" whatever the filter and uses it only for
     * ewa, which haze renders as trilinear: it bounds nothing here. */
    double aniso = params_float(pl, "maxanisotropy", 8.0);
    if (!(aniso >= 1.0 && isfinite(aniso)))
        params_reject(pl, "maxanisotropy", "\"maxanisotropy\" must be finite and >= 1, got %g",
                      aniso);
    const char *wrap = params_string(pl, "wrap", "repeat");
    static const char *const wraps[] = {"repeat", "black", "clamp", "octahedralsphere"};
    int w = -1;
    for (int i = 0; i < 4; ++i)
        if (strcmp(wrap, wraps[i]) == 0)
            w = i;
    if (w < 0)
        return hz_fail_at(err, params_loc(pl, "wrap"), "unknown \"wrap\" \"%s\"", wrap);
    t->wrap = (tex_wrap)w;
    t->scale = params_float(pl, "scale", 1.0);
    t->invert = params_bool(pl, "invert", false);
    const char *name = params_string(pl, "filename", NULL);
    if (!name)
        return hz_fail_at(err, loc, "Texture \"imagemap\" needs \"string filename\"");
    bool png = file_has_suffix(name, ".png");
    int enc;
    double gamma;
    if (tex_image_read_encoding(pl, png, &enc, &gamma, err) != HZ_OK)
        return HZ_ERROR;
    if (!png && !file_has_suffix(name, ".exr"))
        return hz_fail_at(err, params_loc(pl, "filename"),
                          "image texture \"%s\": haze reads .png and .exr", name);
    char *path = path_of_scene_file(loc, name);
    if (!path)
        return hz_fail(err, "out of memory");
    float *alpha = NULL;
    hz_status st = png ? tex_image_read_png(path, params_loc(pl, "filename"), enc, gamma, &t->img,
                                            &alpha, err)
                       : tex_image_read_exr(path, params_loc(pl, "filename"), &t->img, &alpha, err);
    free(path);
    if (st == HZ_OK && !t->spectrum)
        tex_image_float_channels(&t->img, alpha);
    free(alpha);
    if (st == HZ_OK && (t->img.width <= 0 || t->img.height <= 0))
        return hz_fail_at(err, params_loc(pl, "filename"), "image texture \"%s\" is empty",
                          name);
    return st == HZ_OK ? build_pyramid(t, err) : st;
}

/* ---- one builder per texture class ---- */

static hz_status build_constant(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    (void)s;
    (void)err;
    param_list *pl = &te->entity.params;
    t->kind = TEX_CONSTANT;
    t->in[0].v = t->spectrum ? params_rgb(pl, "value", rgb_grey(1.0))
                             : rgb_grey(params_float(pl, "value", 1));
    return HZ_OK;
}

static hz_status build_scale(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    param_list *pl = &te->entity.params;
    rgb one = rgb_grey(1.0);
    t->kind = TEX_SCALE;
    if (read_input(s, pl, "tex", t->spectrum, one, &t->in[0], err) != HZ_OK ||
        read_input(s, pl, "scale", false, one, &t->in[1], err) != HZ_OK)
        return HZ_ERROR;
    return HZ_OK;
}

static hz_status build_mix(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    param_list *pl = &te->entity.params;
    bool sp = t->spectrum;
    t->kind = TEX_MIX;
    if (read_input(s, pl, "tex1", sp, rgb_grey(0.0), &t->in[0], err) != HZ_OK ||
        read_input(s, pl, "tex2", sp, rgb_grey(1.0), &t->in[1], err) != HZ_OK ||
        read_input(s, pl, "amount", false, rgb_grey(0.5), &t->in[2], err) != HZ_OK)
        return HZ_ERROR;
    return HZ_OK;
}

static hz_status build_checkerboard(texture_set *s, texture_entity *te, texture *t,
                                    hz_error *err)
{
    param_list *pl = &te->entity.params;
    bool sp = t->spectrum;
    t->kind = TEX_CHECKERBOARD;
    int dim = params_int(pl, "dimension", 2);
    if (dim != 2 && dim != 3)
        return hz_fail_at(err, params_loc(pl, "dimension"),
                          "checkerboard \"dimension\" must be 2 or 3, got %d", dim);
    t->checker3d = dim == 3;
    if ((dim == 3 ? texture_space(s, te, t, err) : read_mapping(s, te, pl, t, err)) != HZ_OK ||
        read_input(s, pl, "tex1", sp, rgb_grey(1.0), &t->in[0], err) != HZ_OK ||
        read_input(s, pl, "tex2", sp, rgb_grey(0.0), &t->in[1], err) != HZ_OK)
        return HZ_ERROR;
    return HZ_OK;
}

static hz_status build_bilerp(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    param_list *pl = &te->entity.params;
    t->kind = TEX_BILERP;
    static const char *const v[4] = {"v00", "v01", "v10", "v11"};
    if (read_mapping(s, te, pl, t, err) != HZ_OK)
        return HZ_ERROR;
    for (int i = 0; i < 4; ++i)
        if (read_input(s, pl, v[i], t->spectrum, rgb_grey(i & 1 ? 1.0 : 0.0), &t->in[i], err) !=
            HZ_OK)
            return HZ_ERROR;
    return HZ_OK;
}

static hz_status build_imagemap(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    param_list *pl = &te->entity.params;
    if (read_mapping(s, te, pl, t, err) != HZ_OK)
        return HZ_ERROR;
    return read_imagemap(pl, te->entity.loc, t, err);
}

static hz_status build_directionmix(texture_set *s, texture_entity *te, texture *t,
                                    hz_error *err)
{
    param_list *pl = &te->entity.params;
    t->kind = TEX_DIRECTIONMIX;
    transform render_from_texture = transform_compose(s->render_from_world,
                                                      te->world_from_texture);
    vec3 d = transform_vector(&render_from_texture, params_vector3(pl, "dir", v3(0, 1, 0)));
    if (!(v3_length(d) > 0.0) || !v3_is_finite(d))
        return hz_fail_at(err, params_loc(pl, "dir"),
                          "directionmix \"dir\" must be a finite, non-zero vector");
    t->dir = v3_normalize(d);
    if (read_input(s, pl, "tex1", t->spectrum, rgb_grey(0.0), &t->in[0], err) != HZ_OK ||
        read_input(s, pl, "tex2", t->spectrum, rgb_grey(1.0), &t->in[1], err) != HZ_OK)
        return HZ_ERROR;
    return HZ_OK;
}

/* As pbrt-v4 renders it: its DotsTexture constructors take (outside,
 * inside) and Create passes ("inside", "outside"), so "inside" shows
 * between the dots and "outside" in them. Scenes were made by looking at
 * that image. */
static hz_status build_dots(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    param_list *pl = &te->entity.params;
    t->kind = TEX_DOTS;
    if (read_mapping(s, te, pl, t, err) != HZ_OK ||
        read_input(s, pl, "outside", t->spectrum, rgb_grey(0.0), &t->in[0], err) != HZ_OK ||
        read_input(s, pl, "inside", t->spectrum, rgb_grey(1.0), &t->in[1], err) != HZ_OK)
        return HZ_ERROR;
    return HZ_OK;
}

/* fbm, wrinkled, windy (float) and marble (spectrum): noise in texture
 * space. */
static hz_status build_noise(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    param_list *pl = &te->entity.params;
    const char *cls = te->entity.type;
    bool is_marble = strcmp(cls, "marble") == 0;
    if (t->spectrum != is_marble)
        return hz_fail_at(err, te->entity.loc,
                          "Texture class \"%s\" makes %s textures only (as in pbrt-v4)", cls,
                          is_marble ? "spectrum" : "float");
    t->kind = is_marble                   ? TEX_MARBLE
              : strcmp(cls, "fbm") == 0   ? TEX_FBM
              : strcmp(cls, "windy") == 0 ? TEX_WINDY
                                          : TEX_WRINKLED;
    if (texture_space(s, te, t, err) != HZ_OK)
        return HZ_ERROR;
    if (t->kind != TEX_WINDY) { /* windy's octaves and roughness are fixed */
        t->octaves = params_int(pl, "octaves", 8);
        t->omega = params_float(pl, "roughness", 0.5);
        if (t->octaves < 0 || t->octaves > 64)
            params_reject(pl, "octaves", "\"octaves\" must be in [0, 64], got %d", t->octaves);
        if (!isfinite(t->omega))
            params_reject(pl, "roughness", "\"roughness\" must be finite");
    }
    if (is_marble) {
        t->scale = params_float(pl, "scale", 1.0);
        t->variation = params_float(pl, "variation", 0.2);
        if (!isfinite(t->scale) || !isfinite(t->variation))
            params_reject(pl, "scale", "marble \"scale\" and \"variation\" must be finite");
    }
    return HZ_OK;
}

static const struct {
    const char *cls;
    hz_status (*build)(texture_set *s, texture_entity *te, texture *t, hz_error *err);
} texture_classes[] = {
    {"constant", build_constant},
    {"scale", build_scale},
    {"mix", build_mix},
    {"checkerboard", build_checkerboard},
    {"bilerp", build_bilerp},
    {"imagemap", build_imagemap},
    {"directionmix", build_directionmix},
    {"dots", build_dots},
    {"fbm", build_noise},
    {"wrinkled", build_noise},
    {"windy", build_noise},
    {"marble", build_noise},
};

static hz_status build_texture(texture_set *s, texture_entity *te, texture *t, hz_error *err)
{
    const char *cls = te->entity.type;
    *t = (texture){.spectrum = te->spectrum, .su = 1.0, .sv = 1.0};
    for (size_t i = 0; i < sizeof texture_classes / sizeof texture_classes[0]; ++i)
        if (strcmp(cls, texture_classes[i].cls) == 0) {
            if (texture_classes[i].build(s, te, t, err) != HZ_OK)
                return HZ_ERROR;
            char what[128];
            snprintf(what, sizeof what, "Texture \"%s\" \"%s\"", te->name, cls);
            return params_finish(&te->entity.params, what, err);
        }
    return hz_fail_at(err, te->entity.loc,
                      "Texture class \"%s\" is not supported (supported: \"constant\", "
                      "\"scale\", \"mix\", \"directionmix\", \"checkerboard\", "
                      "\"bilerp\", \"dots\", \"imagemap\", \"fbm\", \"wrinkled\", "
                      "\"windy\", \"marble\"; \"ptex\" is refused: haze reads no Ptex "
                      "files)",
                      cls);
}

static void free_images(texture *t)
{
    free(t->img.rgb);
    for (int i = 1; i < t->levels; ++i)
        free(t->level[i].rgb);
}

static hz_status read_normal_maps(texture_set *s, scene_desc *sd, hz_errors *errs, hz_error *err);

hz_status texture_set_create(scene_desc *sd, transform render_from_world, hz_errors *errs,
                             texture_set **out, hz_error *err)
{
    *out = NULL;
    texture_set *s = calloc(1, sizeof *s);
    if (!s)
        return hz_fail(err, "out of memory");
    s->entities = sd->textures;
    s->render_from_world = render_from_world;
    s->items = calloc(sd->texture_count ? sd->texture_count : 1, sizeof *s->items);
    if (!s->items) {
        free(s);
        return hz_fail(err, "out of memory");
    }
    for (size_t i = 0; i < sd->texture_count; ++i) {
        if (build_texture(s, &sd->textures[i], &s->items[i], err) != HZ_OK) {
            free_images(&s->items[i]);
            if (!err->loc.file) {
                s->count = i;
                texture_set_destroy(s);
                return HZ_ERROR;
            }
            hz_errors_add(errs, err);
            s->items[i] = (texture){.kind = TEX_CONSTANT, .spectrum = sd->textures[i].spectrum};
        }
        s->count = i + 1;
    }
    if (read_normal_maps(s, sd, errs, err) != HZ_OK) {
        texture_set_destroy(s);
        return HZ_ERROR;
    }
    *out = s;
    return HZ_OK;
}

void texture_set_destroy(texture_set *s)
{
    if (!s)
        return;
    for (size_t i = 0; i < s->count; ++i)
        free_images(&s->items[i]);
    for (size_t i = 0; i < s->normal_map_count; ++i)
        free_images(&s->normal_maps[i]);
    free(s->items);
    free(s->normal_maps);
    free(s->normal_map_names);
    free(s);
}

const texture *texture_set_normal_map(const texture_set *s, const char *name)
{
    for (size_t i = 0; i < s->normal_map_count; ++i)
        if (strcmp(s->normal_map_names[i], name) == 0)
            return s->normal_maps[i].img.rgb ? &s->normal_maps[i] : NULL;
    return NULL;
}

/* pbrt-v4's normal map: the image read as linear RGB (PNG or EXR), looked up
 * bilinearly at (u, 1 - v) with repeat: an imagemap texture of those
 * settings, evaluated without a footprint. */
static hz_status read_normal_map(const char *name, file_loc loc, texture *t, hz_error *err)
{
    *t = (texture){.kind = TEX_IMAGEMAP, .spectrum = true, .su = 1.0, .sv = 1.0,
                   .filter = FILTER_BILINEAR, .scale = 1.0};
    bool png = file_has_suffix(name, ".png");
    if (!png && !file_has_suffix(name, ".exr"))
        return hz_fail_at(err, loc, "normal map \"%s\": haze reads .png and .exr", name);
    char *path = path_of_scene_file(loc, name);
    if (!path)
        return hz_fail(err, "out of memory");
    float *alpha = NULL;
    hz_status st = png ? tex_image_read_png(path, loc, 1, 1.0, &t->img, &alpha, err)
                       : tex_image_read_exr(path, loc, &t->img, &alpha, err);
    free(alpha);
    free(path);
    if (st == HZ_OK && (t->img.width <= 0 || t->img.height <= 0))
        return hz_fail_at(err, loc, "normal map \"%s\" is empty", name);
    return st == HZ_OK ? build_pyramid(t, err) : st;
}

/* Every distinct "normalmap" of the scene's materials, read once. */
static hz_status read_normal_maps(texture_set *s, scene_desc *sd, hz_errors *errs, hz_error *err)
{
    s->normal_maps = calloc(sd->material_count ? sd->material_count : 1, sizeof *s->normal_maps);
    s->normal_map_names =
        calloc(sd->material_count ? sd->material_count : 1, sizeof *s->normal_map_names);
    if (!s->normal_maps || !s->normal_map_names)
        return hz_fail(err, "out of memory");
    for (size_t i = 0; i < sd->material_count; ++i) {
        param_list *pl = &sd->materials[i].entity.params;
        const char *name = params_peek_string(pl, "normalmap", NULL);
        if (!name)
            continue;
        bool seen = false;
        for (size_t j = 0; j < s->normal_map_count && !seen; ++j)
            seen = strcmp(s->normal_map_names[j], name) == 0;
        if (seen)
            continue;
        size_t k = s->normal_map_count++;
        s->normal_map_names[k] = name;
        if (read_normal_map(name, params_loc(pl, "normalmap"), &s->normal_maps[k], err) !=
            HZ_OK) {
            free_images(&s->normal_maps[k]);
            s->normal_maps[k] = (texture){.kind = TEX_CONSTANT};
            if (!err->loc.file || !errs)
                return HZ_ERROR;
            hz_errors_add(errs, err);
        }
    }
    return HZ_OK;
}

static bool rgb_is_grey(rgb c) { return c.r == c.g && c.g == c.b; }

static bool input_is_grey(const tex_input *in)
{
    return in->t ? texture_is_grey(in->t) : rgb_is_grey(in->v);
}

bool texture_is_grey(const texture *t)
{
    if (!t->spectrum)
        return true;
    switch (t->kind) {
    case TEX_CONSTANT:
        return input_is_grey(&t->in[0]);
    case TEX_SCALE:
    case TEX_CHECKERBOARD:
    case TEX_DIRECTIONMIX:
    case TEX_DOTS:
        return input_is_grey(&t->in[0]) && input_is_grey(&t->in[1]);
    case TEX_MIX: /* in[2] is the float amount */
        return input_is_grey(&t->in[0]) && input_is_grey(&t->in[1]);
    case TEX_BILERP:
        return input_is_grey(&t->in[0]) && input_is_grey(&t->in[1]) &&
               input_is_grey(&t->in[2]) && input_is_grey(&t->in[3]);
    case TEX_IMAGEMAP: {
        const float *p = t->img.rgb;
        for (size_t i = 0, n = (size_t)t->img.width * t->img.height; i < n; ++i, p += 3)
            if (p[0] != p[1] || p[1] != p[2])
                return false;
        return true;
    }
    case TEX_FBM:
    case TEX_WRINKLED:
    case TEX_WINDY:
        return true;
    case TEX_MARBLE:
        return false;
    }
    return false;
}
