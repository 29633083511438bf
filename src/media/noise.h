/* Perlin's improved gradient noise (Perlin 2002, "Improving Noise": his
 * permutation, 12 gradients through the cube's edge midpoints folded to 16,
 * the quintic fade), in single precision and in the order pbrt-v4 evaluates
 * it, so that media built on it (pbrt-v4's "cloud") see the same field. */
#ifndef HAZE_MEDIA_NOISE_H
#define HAZE_MEDIA_NOISE_H

/* In [-1, 1]; 0 at integer lattice points; period 256. */
float noise3(float x, float y, float z);

#endif
