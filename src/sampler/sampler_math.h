/* Integer building blocks of the samplers: 64-bit hashing, Kensler's hashed
 * permutation, the first two Sobol' dimensions and Burley's hash-based Owen
 * scrambling. Pure functions, so samples depend only on their inputs. */
#ifndef HAZE_SAMPLER_SAMPLER_MATH_H
#define HAZE_SAMPLER_SAMPLER_MATH_H

#include <stdint.h>

/* The 64-bit finaliser of MurmurHash3 variant 13 (Stafford), as pbrt's MixBits. */
static inline uint64_t smp_mix64(uint64_t v)
{
    v ^= v >> 31;
    v *= 0x7fb5d329728ea185ull;
    v ^= v >> 27;
    v *= 0x81dadef4bc2dd44dull;
    v ^= v >> 33;
    return v;
}

/* Order-dependent combination: hash(a, b) != hash(b, a). */
static inline uint64_t smp_hash2(uint64_t a, uint64_t b)
{
    return smp_mix64(a ^ smp_mix64(b + 0x9e3779b97f4a7c15ull));
}

static inline uint64_t smp_hash4(uint64_t a, uint64_t b, uint64_t c, uint64_t d)
{
    return smp_hash2(smp_hash2(smp_hash2(a, b), c), d);
}

/* Uniform in [0, 1 - 2^-53]: 1.0 is never returned. */
static inline double smp_uniform(uint64_t h)
{
    return (double)(h >> 11) * 0x1p-53;
}

/* Element i of a pseudo-random permutation of [0, n) selected by p
 * (Kensler 2013, "Correlated Multi-Jittered Sampling"; pbrt-v4's
 * PermutationElement). Each step is invertible on the low bits, so cycle
 * walking until the value falls below n gives a bijection. */
static inline uint32_t smp_permutation_element(uint32_t i, uint32_t n, uint32_t p)
{
    uint32_t w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    do {
        i ^= p;
        i *= 0xe170893du;
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i *= 0x0929eb3fu;
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i *= 1u | p >> 27;
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5;
    } while (i >= n);
    return (uint32_t)(((uint64_t)i + p) % n);
}

static inline uint32_t smp_reverse_bits32(uint32_t v)
{
    v = (v << 16) | (v >> 16);
    v = ((v & 0x00ff00ffu) << 8) | ((v & 0xff00ff00u) >> 8);
    v = ((v & 0x0f0f0f0fu) << 4) | ((v & 0xf0f0f0f0u) >> 4);
    v = ((v & 0x33333333u) << 2) | ((v & 0xccccccccu) >> 2);
    v = ((v & 0x55555555u) << 1) | ((v & 0xaaaaaaaau) >> 1);
    return v;
}

/* Sobol' dimension 0 (van der Corput) and 1 as 0.32 fixed point. Dimension
 * 1's generator matrix is the Pascal matrix mod 2: column k (the one index
 * bit k selects) has bit 31 - m set where m's bits are a subset of k's
 * (Lucas), so bit 31 - m of the point is the parity of the index bits k
 * that contain m. smp_sobol1_reversed computes those parities, bit m, in
 * five shift-and-mask steps (the superset-sum transform over GF(2)), where
 * a loop over the index's 32 scrambled bits took 32 steps. */
static inline uint32_t smp_sobol0(uint32_t i) { return smp_reverse_bits32(i); }
static inline uint32_t smp_sobol1_reversed(uint32_t i)
{
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    i ^= (i >> 16) & 0x0000ffffu;
    return i;
}
static inline uint32_t smp_sobol1(uint32_t i) { return smp_reverse_bits32(smp_sobol1_reversed(i)); }

/* Burley 2020, "Practical Hash-based Owen Scrambling": each output bit is
 * flipped by a hash of the bits above it (in the reversed representation,
 * the bits below), which is exactly a nested uniform (Owen) scramble. */
static inline uint32_t smp_laine_karras_permutation(uint32_t x, uint32_t seed)
{
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

static inline uint32_t smp_owen_scramble(uint32_t x, uint32_t seed)
{
    x = smp_reverse_bits32(x);
    x = smp_laine_karras_permutation(x, seed);
    return smp_reverse_bits32(x);
}

/* smp_owen_scramble(smp_sobol0(i), seed) without the two reversals that
 * cancel: Sobol' dimension 0 is i reversed, which the scramble reverses
 * back. */
static inline uint32_t smp_owen_sobol0(uint32_t i, uint32_t seed)
{
    return smp_reverse_bits32(smp_laine_karras_permutation(i, seed));
}

/* smp_owen_scramble(smp_sobol1(i), seed), the same way. */
static inline uint32_t smp_owen_sobol1(uint32_t i, uint32_t seed)
{
    return smp_reverse_bits32(smp_laine_karras_permutation(smp_sobol1_reversed(i), seed));
}

#endif
