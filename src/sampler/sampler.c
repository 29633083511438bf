/* Pixel samplers: independent, stratified (pbrt-v4's StratifiedSampler) and
 * Owen-scrambled Sobol' (Burley 2020). Every value is a pure function of
 * (pixel, sample index, seed, dimension): nothing is stored between calls
 * except the dimension counter, so tiles and threads cannot change an image. */
#include "sampler/sampler.h"

#include "core/hash.h"

#include <assert.h>
#include <stdio.h>
#include <string.h>

#include "sampler/sampler_math.h"
#include "scene/params.h"

/* Tags keep the streams of different uses apart even at equal dimensions. */
enum { TAG_PIXEL = 0x70697865, TAG_1D = 0x31640000, TAG_2D = 0x32640000, TAG_JITTER = 0x6a697474,
       TAG_STREAM = 0x73747265, TAG_WAVELENGTH = 0x77617665, TAG_FORK = 0x666f726b };

/* Largest spp: sample indices stay 32-bit for Sobol' (and stay far from overflow elsewhere). */
#define SAMPLER_MAX_SPP (1 << 30)

static int round_up_pow2(int n)
{
    int p = 1;
    while (p < n)
        p <<= 1;
    return p;
}

static void append_warning(sampler *s, const char *msg)
{
    size_t len = strlen(s->warning);
    snprintf(s->warning + len, sizeof s->warning - len, "%s%s", len ? "; " : "", msg);
}

/* pbrt-v4 rounds Sobol' sample counts up to a power of two, with a warning. */
static void sobol_round_spp(sampler *s)
{
    int p = round_up_pow2(s->spp);
    if (p != s->spp) {
        char msg[128];
        snprintf(msg, sizeof msg, "sobol: %d pixel samples rounded up to %d (a power of two)", s->spp, p);
        append_warning(s, msg);
        s->spp = p;
    }
}

uint64_t sampler_fingerprint(uint64_t h, const sampler *s)
{
    HASH_FIELD(h, s->kind);
    HASH_FIELD(h, s->spp);
    HASH_FIELD(h, s->xsamples);
    HASH_FIELD(h, s->ysamples);
    HASH_FIELD(h, s->jitter);
    HASH_FIELD(h, s->seed);
    return h;
}

void sampler_set_spp(sampler *s, int spp)
{
    assert(spp >= 1 && spp <= SAMPLER_MAX_SPP); /* the command line validates --spp */
    switch (s->kind) {
    case SAMPLER_INDEPENDENT:
        s->spp = spp;
        break;
    case SAMPLER_STRATIFIED: {
        int d = 1;
        for (int k = 1; (long)k * k <= spp; k++)
            if (spp % k == 0)
                d = k;
        /* The wider side gets more strata: images are usually landscape. */
        s->xsamples = spp / d;
        s->ysamples = d;
        s->spp = spp;
        break;
    }
    case SAMPLER_SOBOL: {
        /* The scene's count was never used: drop its rounding warning. */
        char *w = strstr(s->warning, "sobol: ");
        if (w) {
            char *end = strstr(w, "; ");
            if (end)
                memmove(w, end + 2, strlen(end + 2) + 1);
            else
                *(w > s->warning ? w - 2 : w) = '\0';
        }
        s->spp = spp;
        sobol_round_spp(s);
        break;
    }
    }
}

static hz_status check_spp(param_list *pl, const char *name, int v)
{
    if (v < 1 || v > SAMPLER_MAX_SPP) {
        params_reject(pl, name, "\"integer %s\" must be in [1, %d], got %d", name, SAMPLER_MAX_SPP, v);
        return HZ_ERROR;
    }
    return HZ_OK;
}

hz_status sampler_from_entity(scene_entity *e, uint64_t seed, sampler *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    param_list *pl = &e->params;
    const char *type = e->type ? e->type : "";
    char what[96];
    snprintf(what, sizeof what, "Sampler \"%s\"", type);
    bool sobolish = false;
    if (strcmp(type, "independent") == 0) {
        out->kind = SAMPLER_INDEPENDENT;
        out->spp = params_int(pl, "pixelsamples", 16);
        check_spp(pl, "pixelsamples", out->spp);
    } else if (strcmp(type, "stratified") == 0) {
        out->kind = SAMPLER_STRATIFIED;
        out->xsamples = params_int(pl, "xsamples", 4);
        out->ysamples = params_int(pl, "ysamples", 4);
        out->jitter = params_bool(pl, "jitter", true);
        if (check_spp(pl, "xsamples", out->xsamples) == HZ_OK &&
            check_spp(pl, "ysamples", out->ysamples) == HZ_OK) {
            if ((long long)out->xsamples * out->ysamples > SAMPLER_MAX_SPP)
                params_reject(pl, "xsamples", "xsamples * ysamples = %lld is more than %d samples",
                              (long long)out->xsamples * out->ysamples, SAMPLER_MAX_SPP);
            else
                out->spp = out->xsamples * out->ysamples;
        }
    } else if (strcmp(type, "zsobol") == 0 || strcmp(type, "sobol") == 0 ||
               strcmp(type, "halton") == 0 || strcmp(type, "paddedsobol") == 0 ||
               strcmp(type, "pmj02bn") == 0) {
        out->kind = SAMPLER_SOBOL;
        sobolish = true;
        out->spp = params_int(pl, "pixelsamples", 16);
        if (strcmp(type, "pmj02bn") != 0) {
            const char *r = params_string(pl, "randomization", "owen");
            if (strcmp(r, "owen") && strcmp(r, "fastowen") && strcmp(r, "none") &&
                strcmp(r, "permutedigits"))
                params_reject(pl, "randomization",
                              "unknown randomization \"%s\" (expected \"owen\", \"fastowen\", "
                              "\"permutedigits\" or \"none\")", r);
            else if (strcmp(r, "owen") && strcmp(r, "fastowen")) {
                char msg[128];
                snprintf(msg, sizeof msg, "randomization \"%s\" is replaced by Owen scrambling", r);
                append_warning(out, msg);
            }
        }
        if (strcmp(type, "zsobol") && strcmp(type, "sobol")) {
            char msg[128];
            snprintf(msg, sizeof msg, "Sampler \"%s\" renders with haze's Owen-scrambled Sobol' sampler",
                     type);
            append_warning(out, msg);
        }
        check_spp(pl, "pixelsamples", out->spp);
    } else {
        return hz_fail_at(err, e->loc,
                          "unknown Sampler \"%s\" (haze supports \"independent\", \"stratified\", "
                          "\"zsobol\", \"sobol\"; \"halton\", \"paddedsobol\", \"pmj02bn\" "
                          "render with sobol)", type);
    }
    int s = params_int(pl, "seed", (int)(seed & 0x7fffffff));
    if (params_has(pl, "seed"))
        out->seed = (uint64_t)(int64_t)s;
    else
        out->seed = seed;
    if (params_finish(pl, what, err) != HZ_OK)
        return HZ_ERROR;
    if (sobolish)
        sobol_round_spp(out);
    return HZ_OK;
}

/* ---- per-sample streams -------------------------------------------- */

void sampler_start(const sampler *s, int px, int py, int sample_index, sampler_state *st)
{
    assert(sample_index >= 0 && sample_index < s->spp);
    st->s = s;
    st->px = px;
    st->py = py;
    st->index = sample_index;
    st->dim = 0;
    st->hash = smp_hash4((uint64_t)(int64_t)px, (uint64_t)(int64_t)py, s->seed, 0x68617a65u);
}

void sampler_fork(sampler_state *st, int copy)
{
    assert(copy >= 1);
    st->hash = smp_hash2(st->hash, ((uint64_t)TAG_FORK << 32) | (uint32_t)copy);
}

static uint64_t dim_hash(const sampler_state *st, uint64_t tag, uint64_t dim)
{
    return smp_hash2(st->hash, tag ^ (dim << 32));
}

/* Stratified: the strata of each dimension are visited in a hashed order
 * over the pixel's samples (pbrt-v4 StratifiedSampler). */
static double stratified_1d(const sampler_state *st, uint64_t h)
{
    int n = st->s->spp;
    uint32_t stratum = smp_permutation_element((uint32_t)st->index, (uint32_t)n, (uint32_t)h);
    double delta = st->s->jitter ? smp_uniform(smp_hash2(h, ((uint64_t)TAG_JITTER << 32) | (uint32_t)st->index)) : 0.5;
    double u = (stratum + delta) / n;
    return u < 1.0 ? u : 0x1.fffffffffffffp-1;
}

static vec2 stratified_2d(const sampler_state *st, uint64_t h)
{
    const sampler *s = st->s;
    uint32_t stratum = smp_permutation_element((uint32_t)st->index, (uint32_t)s->spp, (uint32_t)h);
    uint32_t x = stratum % (uint32_t)s->xsamples, y = stratum / (uint32_t)s->xsamples;
    double dx = 0.5, dy = 0.5;
    if (s->jitter) {
        uint64_t j = smp_hash2(h, ((uint64_t)TAG_JITTER << 32) | (uint32_t)st->index);
        dx = smp_uniform(j);
        dy = smp_uniform(smp_mix64(j ^ 0x5bd1e995u));
    }
    vec2 u = v2((x + dx) / s->xsamples, (y + dy) / s->ysamples);
    /* (x + dx) / n can round up to 1 for huge n; keep the [0,1) promise. */
    if (u.x >= 1.0)
        u.x = 0x1.fffffffffffffp-1;
    if (u.y >= 1.0)
        u.y = 0x1.fffffffffffffp-1;
    return u;
}

/* Owen-scrambled Sobol'. The sample index is shuffled by an Owen scramble
 * of its own (Burley's trick): within any aligned block of 2^k indices that
 * is a permutation of the block, so the first 2^k samples of every
 * dimension pair still form a (0,k,2)-net, while different pairs are
 * decorrelated. */
static double sobol_1d(const sampler_state *st, uint64_t h)
{
    uint32_t idx = smp_owen_scramble((uint32_t)st->index, (uint32_t)h);
    uint32_t x = smp_owen_sobol0(idx, (uint32_t)(h >> 32));
    return x * 0x1p-32;
}

static vec2 sobol_2d(const sampler_state *st, uint64_t h, bool shuffle)
{
    uint32_t idx = shuffle ? smp_owen_scramble((uint32_t)st->index, (uint32_t)h) : (uint32_t)st->index;
    uint64_t h2 = smp_mix64(h);
    uint32_t x = smp_owen_sobol0(idx, (uint32_t)(h >> 32));
    uint32_t y = smp_owen_sobol1(idx, (uint32_t)h2);
    return v2(x * 0x1p-32, y * 0x1p-32);
}

static double sample_1d(const sampler_state *st, uint64_t h)
{
    switch (st->s->kind) {
    case SAMPLER_INDEPENDENT:
        return smp_uniform(smp_hash2(h, (uint32_t)st->index));
    case SAMPLER_STRATIFIED:
        return stratified_1d(st, h);
    case SAMPLER_SOBOL:
        return sobol_1d(st, h);
    }
    return 0.0;
}

double sampler_1d(sampler_state *st)
{
    return sample_1d(st, dim_hash(st, TAG_1D, (uint64_t)st->dim++));
}

/* Like the pixel dimension: its own tag, no dimension taken, so spectral
 * rendering draws the same values as RGB rendering everywhere else. */
double sampler_wavelength_1d(sampler_state *st)
{
    return sample_1d(st, dim_hash(st, TAG_WAVELENGTH, 0));
}

static vec2 sample_2d(sampler_state *st, uint64_t h, bool pixel)
{
    switch (st->s->kind) {
    case SAMPLER_INDEPENDENT: {
        uint64_t a = smp_hash2(h, (uint32_t)st->index);
        return v2(smp_uniform(a), smp_uniform(smp_mix64(a ^ 0x9e3779b97f4a7c15ull)));
    }
    case SAMPLER_STRATIFIED:
        return stratified_2d(st, h);
    case SAMPLER_SOBOL:
        return sobol_2d(st, h, !pixel);
    }
    return v2(0.0, 0.0);
}

vec2 sampler_2d(sampler_state *st)
{
    return sample_2d(st, dim_hash(st, TAG_2D, (uint64_t)st->dim++), false);
}

/* The pixel dimension has its own tag and does not advance the dimension
 * counter: its value does not depend on when the caller asks for it. */
vec2 sampler_pixel_2d(sampler_state *st)
{
    return sample_2d(st, dim_hash(st, TAG_PIXEL, 0), true);
}

uint64_t sampler_stream_seed_at(const sampler_state *st, int dim)
{
    return smp_hash2(dim_hash(st, TAG_STREAM, (uint64_t)dim), (uint32_t)st->index);
}

