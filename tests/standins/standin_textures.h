/* The generated texture files the stand-ins of tests/standins name (their
 * README), written by test_standins and by the spectral part of the bench
 * (bench/spectral_data.c) alike. */
#ifndef HAZE_TESTS_STANDIN_TEXTURES_H
#define HAZE_TESTS_STANDIN_TEXTURES_H

#include "core/error.h"

/* Writes into DIR/textures (which must exist): sky.exr and
 * sunflowers_equiarea_blurred.exr (a 64x64 equal-area sky: a blue gradient
 * over a dark ground and a small warm sun, in the scenes' +z-up light
 * space), stone.png, leaf.png and bump.png (32x32 RGBA). */
hz_status standin_textures_write(const char *dir, hz_error *err);

#endif
