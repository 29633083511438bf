/* Perlin's improved gradient noise (Perlin 2002, "Improving Noise": his
 * permutation, 12 gradients through the cube's edge midpoints folded to 16,
 * the quintic fade), in single precision and in the order pbrt-v4 evaluates
 * it, so that what is built on it (pbrt-v4's "cloud" medium, its fbm,
 * wrinkled, windy, marble and dots textures) sees the same field. */
#ifndef HAZE_CORE_NOISE_H
#define HAZE_CORE_NOISE_H

#include "core/vec.h"

/* In [-1, 1]; 0 at integer lattice points; period 256. */
float noise3(float x, float y, float z);

/* pbrt-v4's fractional Brownian motion: octaves of noise at frequencies
 * 1.99^i and amplitudes omega^i, as many as the footprint (dpdx, dpdy: the
 * point's change per pixel; zero: all) leaves above the Nyquist rate, the
 * last one faded in. Turbulence sums the noise's magnitudes, and counts the
 * octaves the footprint drops at 0.2 each. Single precision, pbrt-v4's order. */
float noise_fbm(vec3 p, vec3 dpdx, vec3 dpdy, float omega, int octaves);
float noise_turbulence(vec3 p, vec3 dpdx, vec3 dpdy, float omega, int octaves);

#endif
