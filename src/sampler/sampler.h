/* Pixel samplers. Each (pixel, sample index, seed) has its own deterministic
 * stream, so images do not depend on the thread count or tile order. */
#ifndef HAZE_SAMPLER_SAMPLER_H
#define HAZE_SAMPLER_SAMPLER_H

#include <stdint.h>

#include "core/error.h"
#include "core/vec.h"
#include "scene/scene_desc.h"

typedef enum { SAMPLER_INDEPENDENT, SAMPLER_STRATIFIED, SAMPLER_SOBOL } sampler_kind;

typedef struct {
    sampler_kind kind;
    int spp;               /* samples per pixel (stratified: xsamples*ysamples) */
    int xsamples, ysamples;
    bool jitter;
    uint64_t seed;
    char warning[256];     /* non-empty: print once (e.g. "halton renders with sobol") */
} sampler;

/* Sampler "independent" (pixelsamples 16, seed), "stratified" (xsamples 4,
 * ysamples 4, jitter true, seed), "zsobol"/"sobol" (pixelsamples 16, seed,
 * randomization "owen"); "halton"/"paddedsobol"/"pmj02bn" become sobol with a warning.
 * `seed` is the default for a missing "integer seed" (the --seed option). */
hz_status sampler_from_entity(scene_entity *e, uint64_t seed, sampler *out, hz_error *err);
/* `h` extended by everything that decides the samples: kind, spp, strata,
 * jitter, seed (core/hash.h). */
uint64_t sampler_fingerprint(uint64_t h, const sampler *s);
/* --spp override: stratified picks the most square xsamples*ysamples == spp. */
void sampler_set_spp(sampler *s, int spp);

typedef struct {
    const sampler *s;
    int px, py, index, dim;
    uint64_t hash; /* of (px, py, seed) */
} sampler_state;

void sampler_start(const sampler *s, int px, int py, int sample_index, sampler_state *st);
double sampler_1d(sampler_state *st);
vec2 sampler_2d(sampler_state *st);
/* Consumes n dimensions without computing them (1D and 2D dimensions alike):
 * a caller that does not need a value keeps every later dimension where it was. */
static inline void sampler_skip(sampler_state *st, int n) { st->dim += n; }
/* Copy `copy` (>= 1) of a path split at this state (volpath's "mediumsplits"):
 * every later dimension and stream seed from an independent scramble, each
 * still stratified over the pixel's samples. The film position and the
 * wavelengths are the pixel sample's: a fork is for what follows them. */
void sampler_fork(sampler_state *st, int copy);
/* The film position sample: the first 2D dimension, stratified across the pixel's samples. */
vec2 sampler_pixel_2d(sampler_state *st);
/* The wavelength sample of spectral rendering (color/wavelengths.h): a 1D
 * dimension with its own tag, like the pixel's, so drawing it moves no other
 * dimension. */
double sampler_wavelength_1d(sampler_state *st);
/* A seed for an rng stream (core/rng.h) of this pixel sample, for estimators that
 * use an unbounded number of random numbers, in two steps: its dimension is
 * taken when the sample's dimensions reach it (sampler_skip(st, 1) returning
 * it), its value computed from it when needed, if ever (the same value
 * whenever: it depends on the pixel, the sample and the dimension only). */
static inline int sampler_reserve_dim(sampler_state *st) { return st->dim++; }
uint64_t sampler_stream_seed_at(const sampler_state *st, int dim);

#endif
