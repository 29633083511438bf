/* The RGB -> spectrum coefficient tables (Jakob and Hanika 2019, "A
 * Low-Dimensional Function Space for Efficient Spectral Upsampling"), one per
 * colour space, written at build time by tools/rgb2spec_opt.c into the build
 * tree (rgb2spec_tables.{c,bin}) and built into a module that haze loads when
 * a render needs them (color/rgb2spec_module.h). Read through
 * color/rgb_spectrum.h; the layout is pbrt-v4's RGBToSpectrumTable. */
#ifndef HAZE_COLOR_RGB2SPEC_TABLE_H
#define HAZE_COLOR_RGB2SPEC_TABLE_H

#include "core/color_space.h"

/* One colour space's solution, as the generator writes it (in the generated
 * source it is named rgb2spec_table: the module renames it, see
 * color/module/rgb2spec_module.c). */
typedef struct {
    int res; /* nodes along each axis */
    /* The largest component's nodes, z_nodes[k] = smoothstep(smoothstep(
     * k / (res - 1))) as in pbrt-v4: dense near 0 and 1. */
    const float *z_nodes;
    /* The other two components' nodes as fractions of the largest,
     * increasing from 0 to 1 (see tools/rgb2spec_opt.c). */
    const float *xy_nodes;
    /* [3][res][res][res][3]: for the largest component m (0 r, 1 g, 2 b) at
     * z_nodes[k], the next component (m+1 mod 3) at xy_nodes[i] times it and
     * the one after at xy_nodes[j] times it, [m][k][j][i] holds c0, c1, c2 of
     * the sigmoid polynomial s(c0 l^2 + c1 l + c2), l in nm. */
    const float *coeffs;
    /* The illuminant spectrum (color/illuminant.h) times this has luminance 1:
     * its integral against y-bar over 360..830 nm equals y-bar's. */
    double illuminant_scale;
    /* The illuminant's XYZ at Y = 1 (the colour space's white as a spectral
     * film sees it) and the matrices between XYZ and RGB with that white. */
    double white_xyz[3];
    double xyz_from_rgb[9], rgb_from_xyz[9];
} rgb2spec_solution;

/* The table of one colour space: the module holds one per color_space, in
 * that order. */
typedef struct {
    color_space cs; /* whose illuminant the spectra are under */
    const rgb2spec_solution *solution;
} rgb2spec_table;

#endif
