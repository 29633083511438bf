#include "core/noise.h"

#include <math.h>

/* Perlin's permutation of 0..255 (pbrt-v4 lists it twice; indices wrap here). */
static const unsigned char perm[256] = {
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252,
    219, 203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168,
    68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211,
    133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80,
    73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100,
    109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82,
    85, 212, 207, 206, 59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248,
    152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98,
    108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238,
    210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31,
    181, 199, 106, 157, 184, 84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205,
    93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78, 66, 215, 61, 156, 180,
};

/* The gradient of lattice point (x, y, z) dotted with the offset (dx, dy, dz). */
static float grad(int x, int y, int z, float dx, float dy, float dz)
{
    int h = perm[(perm[(perm[x & 255] + y) & 255] + z) & 255] & 15;
    float u = h < 8 || h == 12 || h == 13 ? dx : dy;
    float v = h < 4 || h == 12 || h == 13 ? dy : dz;
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

static float fade(float t) { return 6.0f * t * t * t * t * t - 15.0f * t * t * t * t + 10.0f * t * t * t; }

static float lerpf(float t, float a, float b) { return (1.0f - t) * a + t * b; }

float noise3(float x, float y, float z)
{
    /* Keep the lattice coordinates within int range. */
    x = fmodf(x, (float)(1 << 30));
    y = fmodf(y, (float)(1 << 30));
    z = fmodf(z, (float)(1 << 30));
    int ix = (int)floorf(x), iy = (int)floorf(y), iz = (int)floorf(z);
    float dx = x - (float)ix, dy = y - (float)iy, dz = z - (float)iz;
    ix &= 255;
    iy &= 255;
    iz &= 255;
    float w000 = grad(ix, iy, iz, dx, dy, dz);
    float w100 = grad(ix + 1, iy, iz, dx - 1, dy, dz);
    float w010 = grad(ix, iy + 1, iz, dx, dy - 1, dz);
    float w110 = grad(ix + 1, iy + 1, iz, dx - 1, dy - 1, dz);
    float w001 = grad(ix, iy, iz + 1, dx, dy, dz - 1);
    float w101 = grad(ix + 1, iy, iz + 1, dx - 1, dy, dz - 1);
    float w011 = grad(ix, iy + 1, iz + 1, dx, dy - 1, dz - 1);
    float w111 = grad(ix + 1, iy + 1, iz + 1, dx - 1, dy - 1, dz - 1);
    float wx = fade(dx), wy = fade(dy), wz = fade(dz);
    float x00 = lerpf(wx, w000, w100), x10 = lerpf(wx, w010, w110);
    float x01 = lerpf(wx, w001, w101), x11 = lerpf(wx, w011, w111);
    return lerpf(wz, lerpf(wy, x00, x10), lerpf(wy, x01, x11));
}

static float smooth_step(float x, float a, float b)
{
    if (a == b)
        return x < a ? 0.0f : 1.0f;
    float t = (x - a) / (b - a);
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    return t * t * (3.0f - 2.0f * t);
}

/* The octaves the footprint allows: -1 - log2(largest squared step) / 2,
 * clamped to [0, octaves] (all of them for a zero footprint). */
static float octave_count(vec3 dpdx, vec3 dpdy, int octaves)
{
    float len2 = (float)fmax(v3_length_sq(dpdx), v3_length_sq(dpdy));
    float n = -1.0f - log2f(len2) / 2.0f;
    return n < 0.0f ? 0.0f : n > (float)octaves ? (float)octaves : n;
}

static float noise_at(vec3 p, float lambda)
{
    return noise3(lambda * (float)p.x, lambda * (float)p.y, lambda * (float)p.z);
}

float noise_fbm(vec3 p, vec3 dpdx, vec3 dpdy, float omega, int octaves)
{
    float n = octave_count(dpdx, dpdy, octaves);
    int whole = (int)floorf(n);
    float sum = 0.0f, lambda = 1.0f, o = 1.0f;
    for (int i = 0; i < whole; ++i) {
        sum += o * noise_at(p, lambda);
        lambda *= 1.99f;
        o *= omega;
    }
    return sum + o * smooth_step(n - (float)whole, 0.3f, 0.7f) * noise_at(p, lambda);
}

float noise_turbulence(vec3 p, vec3 dpdx, vec3 dpdy, float omega, int octaves)
{
    float n = octave_count(dpdx, dpdy, octaves);
    int whole = (int)floorf(n);
    float sum = 0.0f, lambda = 1.0f, o = 1.0f;
    for (int i = 0; i < whole; ++i) {
        sum += o * fabsf(noise_at(p, lambda));
        lambda *= 1.99f;
        o *= omega;
    }
    float w = smooth_step(n - (float)whole, 0.3f, 0.7f);
    sum += o * ((1.0f - w) * 0.2f + w * fabsf(noise_at(p, lambda)));
    for (int i = whole; i < octaves; ++i) {
        sum += o * 0.2f;
        o *= omega;
    }
    return sum;
}
