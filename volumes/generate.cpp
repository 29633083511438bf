// Writes haze's small test and demo volumes (FloatGrids named "density", some
// with a Vec3SGrid velocity "v"; a few hundred KB each at most):
//
//   box.vdb, box.nvdb  density exactly 1 on voxels [0,31]^3, voxel size 1/32, no
//                      offset: voxel (i,j,k) sits at world (i,j,k)/32
//   fog_sphere.vdb     radius 0.75 sphere centred at the world origin, density 1
//                      inside, a smooth fall-off over its outer 0.125
//   sheet.vdb          a one-voxel-thin sheet: voxels [0,63] x {0} x [0,63] at
//                      density 1, voxel size 1/64, world x, z in [-0.5, 0.5], y = 0
//   smoke.vdb          a rising plume (fBm value noise, densities in [0,1]) plus a
//                      Vec3f velocity grid "v" on the same voxels
//   plume.vdb          a puffy, swirling plume ("density" in [0,1], voxel size
//                      1/64, within 1 x 2 x 1 world units standing on y = 0) with
//                      a velocity grid "v" (world units per second, rising 0.7 to
//                      1.3 and swirling about the column) at half the resolution
//                      (voxel size 1/32), defined over the density's voxels
//                      dilated by 8 density voxels so that Eulerian motion blur
//                      finds a velocity wherever density can be moved to
//                      (displacements up to 8 voxels, 1/8 world unit); the
//                      velocity is stored as half floats
//   box_velocity.vdb   box.vdb's "density" and a constant velocity "v" = (1, 0.25,
//                      0) on the same index space over voxels [-3,50] x [-3,38] x
//                      [-3,34]: the box's voxels, dilated to hold every point
//                      the box reaches when moved by up to (0.5, 0.125, 0) world
//                      units (16 and 4 voxels); and "v0", zero on the same voxels
//   sparse.vdb         eight soft balls (radius 8.5 voxels, density 1 with a
//                      one-voxel fall-off) near the corners of voxels [0,127]^3,
//                      voxel size 1/64, world [-1, 1] x [0, 2] x [-1, 1]: the
//                      active voxels are about 1% of the bounding box (make
//                      bench's occupancy benchmark)
//   box_fire.vdb/.nvdb box.vdb's "density" and a "temperature" of 2500 (kelvin)
//                      on the same voxels, and "temperature_coarse": 2500 on
//                      voxels [-2,17]^3 of size 1/16 (its own transform,
//                      covering the box and one density voxel beyond it)
//   box_color.vdb      box.vdb's "density" and a vec3 "color" (0.2, 0.5, 1) on
//                      voxels [-2,33]^3 of the same index space: constant
//                      wherever the density's trilinear field is not 0
//   box_inactive.vdb   box.vdb's "density" with the slab of voxels [0,31]^2 x
//                      [12,19] made inactive and set to 50: inactive voxels
//                      that do not hold the background (haze takes them as
//                      the background; the box's optical depth along z is
//                      24 voxels, 0.75 world units)
//   explosion.vdb      a fireball rising on a stem of smoke (scenes/explosion.pbrt):
//                      "density" in [0,1] on voxels of size 1/40 within
//                      x, z in [-0.8, 0.8], y in [0, 2] (world units), a
//                      "temperature" (kelvin, 0 outside the hot core, up to
//                      about 2600 in it) on the same voxels, a "flame" (the
//                      core's heat in [0,1], a simulation tool's flame grid)
//                      and a vec3 soot "color" (grey-brown smoke, lighter and
//                      warmer towards the fire) on the same voxels, and a velocity
//                      "v" (world units per second: expanding from the
//                      fireball's centre and rising) at half the resolution,
//                      over the density's voxels dilated by 6
//   dup_names.vdb      two float grids both named "density" (OpenVDB calls
//                      them "density[0]" and "density[1]"): 1 and then 2 on
//                      voxels [0,1]^3, voxel size 1/4. Only with `--only
//                      dup_names.vdb`: the test build writes it (20 KB of
//                      node masks, for a file that only shows a refusal)
//   vec_ramp.vdb/.nvdb "v": the linear field v(i,j,k) = (0.5 i - 1, 0.25 j, 2 - k)
//                      on voxels [0,7]^3 (voxel size 0.25, offset (1, 2, 3)), and
//                      "density": 1 on the same voxels (for type checks); the
//                      .nvdb is ZIP-compressed
//
// Deterministic: fixed seeds and our own integer hash (OpenVDB still writes a
// random file UUID into each header, so the bytes differ between runs).
// Usage: haze_volumes OUTDIR [--only-new | --only dup_names.vdb]
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/tools/Morphology.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace
{

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::Vec3SGrid;

uint32_t hash3(int32_t x, int32_t y, int32_t z, uint32_t seed)
{
    // A few rounds of a multiply-xorshift mix (lowbias32) over the lattice point.
    uint32_t h = seed;
    for (uint32_t v : {uint32_t(x), uint32_t(y), uint32_t(z)}) {
        h ^= v + 0x9e3779b9u + (h << 6) + (h >> 2);
        h ^= h >> 16;
        h *= 0x7feb352du;
        h ^= h >> 15;
        h *= 0x846ca68bu;
        h ^= h >> 16;
    }
    return h;
}

double lattice(int32_t x, int32_t y, int32_t z, uint32_t seed)
{
    return hash3(x, y, z, seed) * (1.0 / 4294967296.0);
}

double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

// Value noise in [0,1): quintic interpolation of hashed lattice values.
double value_noise(double x, double y, double z, uint32_t seed)
{
    double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    int32_t ix = int32_t(fx), iy = int32_t(fy), iz = int32_t(fz);
    double tx = fade(x - fx), ty = fade(y - fy), tz = fade(z - fz);
    double c[2][2][2];
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int d = 0; d < 2; ++d)
                c[a][b][d] = lattice(ix + a, iy + b, iz + d, seed);
    auto lerp = [](double t, double u, double v) { return u + t * (v - u); };
    double x00 = lerp(tx, c[0][0][0], c[1][0][0]), x10 = lerp(tx, c[0][1][0], c[1][1][0]);
    double x01 = lerp(tx, c[0][0][1], c[1][0][1]), x11 = lerp(tx, c[0][1][1], c[1][1][1]);
    return lerp(tz, lerp(ty, x00, x10), lerp(ty, x01, x11));
}

// Fractional Brownian motion, normalised to [0,1).
double fbm(double x, double y, double z, int octaves, uint32_t seed)
{
    double sum = 0, amp = 0.5, norm = 0;
    for (int o = 0; o < octaves; ++o) {
        sum += amp * value_noise(x, y, z, seed + uint32_t(o) * 101u);
        norm += amp;
        amp *= 0.5;
        x *= 2.03;
        y *= 2.03;
        z *= 2.03;
    }
    return sum / norm;
}

double smoothstep(double e0, double e1, double x)
{
    double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

FloatGrid::Ptr make_density(double voxel_size, openvdb::Vec3d offset)
{
    FloatGrid::Ptr grid = FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto xf = openvdb::math::Transform::createLinearTransform(voxel_size);
    xf->postTranslate(offset);
    grid->setTransform(xf);
    return grid;
}

FloatGrid::Ptr box()
{
    FloatGrid::Ptr grid = make_density(1.0 / 32.0, openvdb::Vec3d(0.0));
    auto acc = grid->getAccessor();
    for (int i = 0; i < 32; ++i)
        for (int j = 0; j < 32; ++j)
            for (int k = 0; k < 32; ++k)
                acc.setValue(Coord(i, j, k), 1.0f);
    return grid;
}

// A float grid named `name` holding `value` on voxels [lo, hi]^3 of size h.
FloatGrid::Ptr constant_cube(const char *name, double h, int lo, int hi, float value)
{
    FloatGrid::Ptr grid = make_density(h, openvdb::Vec3d(0.0));
    grid->setName(name);
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    auto acc = grid->getAccessor();
    for (int i = lo; i <= hi; ++i)
        for (int j = lo; j <= hi; ++j)
            for (int k = lo; k <= hi; ++k)
                acc.setValue(Coord(i, j, k), value);
    return grid;
}

// The fireball: a turbulent ball of hot gas (centre (0, 1.25, 0), radius
// ~0.5) on a narrowing stem of cooler smoke rising from the ground, with a
// dark, ragged rim; temperature falls from the core outwards and is cut by
// noise into flame tongues.
void explosion(FloatGrid::Ptr &density, FloatGrid::Ptr &temperature, Vec3SGrid::Ptr &velocity,
               FloatGrid::Ptr &flame, Vec3SGrid::Ptr &color)
{
    const int n = 40; // voxels per world unit
    const double vs = 1.0 / n;
    density = make_density(vs, openvdb::Vec3d(-0.8, 0.0, -0.8));
    temperature = FloatGrid::create(0.0f);
    temperature->setName("temperature");
    temperature->setGridClass(openvdb::GRID_UNKNOWN);
    temperature->setTransform(density->transform().copy());
    flame = FloatGrid::create(0.0f);
    flame->setName("flame");
    flame->setGridClass(openvdb::GRID_UNKNOWN);
    flame->setTransform(density->transform().copy());
    color = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    color->setName("color");
    color->setTransform(density->transform().copy());
    auto dacc = density->getAccessor();
    auto tacc = temperature->getAccessor();
    auto facc = flame->getAccessor();
    auto cacc = color->getAccessor();
    const uint32_t seed = 90210u;
    const double cy = 1.25;
    for (int j = 0; j < 2 * n; ++j)
        for (int i = 0; i < 64; ++i)
            for (int k = 0; k < 64; ++k) {
                double x = (i + 0.5) * vs - 0.8, y = (j + 0.5) * vs, z = (k + 0.5) * vs - 0.8;
                double nz = fbm(x * 5.0 + 11.0, y * 5.0, z * 5.0 - 7.0, 5, seed);
                double nf = fbm(x * 11.0, y * 11.0 + 3.0, z * 11.0, 4, seed + 17u);
                // Ball: distance from the centre, squashed, with a noisy surface.
                double dx = x, dy = (y - cy) * 1.15, dz = z;
                double q = std::sqrt(dx * dx + dy * dy + dz * dz) / 0.5 + 0.9 * (nz - 0.5);
                double ball = 1.0 - smoothstep(0.75, 1.0, q);
                // Stem: a column narrowing upwards from the ground to the ball.
                double rs = 0.09 + 0.1 * (1.0 - y / cy);
                double qs = std::sqrt(x * x + z * z) / rs + 0.8 * (nz - 0.5);
                double stem = y < cy ? (1.0 - smoothstep(0.6, 1.0, qs)) * smoothstep(0.0, 0.15, y)
                                     : 0.0;
                double d = std::max(ball, 0.6 * stem) * (0.3 + 0.7 * nz);
                if (d < 0.02)
                    continue;
                d = std::min(d, 1.0);
                dacc.setValue(Coord(i, j, k), float(d));
                // Hot core with flame tongues: 0 where the tongues end.
                double hot = 1.0 - smoothstep(0.05, 0.7, q + 0.9 * (nf - 0.5));
                if (hot > 0.0) {
                    tacc.setValue(Coord(i, j, k), float(700.0 + 1900.0 * hot * hot));
                    facc.setValue(Coord(i, j, k), float(hot));
                }
                double warm = std::max(hot, 0.0);
                cacc.setValue(Coord(i, j, k),
                              openvdb::Vec3s(float(0.45 + 0.5 * warm), float(0.42 + 0.33 * warm),
                                             float(0.38 + 0.1 * warm)));
            }
    // Velocity at half resolution over the dilated density: outward from the
    // ball's centre (faster near it) and rising.
    velocity = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setName("v");
    velocity->setGridClass(openvdb::GRID_STAGGERED);
    velocity->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    auto vxf = openvdb::math::Transform::createLinearTransform(2.0 * vs);
    vxf->postTranslate(openvdb::Vec3d(-0.8, 0.0, -0.8));
    velocity->setTransform(vxf);
    FloatGrid::Ptr mask = density->deepCopy();
    openvdb::tools::dilateActiveValues(mask->tree(), 6, openvdb::tools::NN_FACE_EDGE_VERTEX);
    auto vacc = velocity->getAccessor();
    for (auto it = mask->cbeginValueOn(); it; ++it) {
        Coord c = it.getCoord();
        Coord h(c.x() >> 1, c.y() >> 1, c.z() >> 1);
        double x = (2 * h.x() + 1) * vs - 0.8, y = (2 * h.y() + 1) * vs, z = (2 * h.z() + 1) * vs - 0.8;
        double dx = x, dy = y - cy, dz = z;
        double r = std::sqrt(dx * dx + dy * dy + dz * dz) + 1e-6;
        double out = 0.5 * std::exp(-r * 1.5);
        vacc.setValue(h, openvdb::Vec3s(float(out * dx / r), float(0.6 + out * dy / r),
                                        float(out * dz / r)));
    }
}

FloatGrid::Ptr fog_sphere()
{
    // 64^3 voxels of size 1/32 centred on the origin.
    FloatGrid::Ptr grid = make_density(1.0 / 32.0, openvdb::Vec3d(-1.0));
    auto acc = grid->getAccessor();
    const double radius = 24.0, soft = 4.0; // in voxels
    for (int i = 0; i < 64; ++i)
        for (int j = 0; j < 64; ++j)
            for (int k = 0; k < 64; ++k) {
                double r = std::sqrt((i - 32.0) * (i - 32.0) + (j - 32.0) * (j - 32.0) +
                                     (k - 32.0) * (k - 32.0));
                double d = 1.0 - smoothstep(radius - soft, radius, r);
                if (d > 0.0)
                    acc.setValue(Coord(i, j, k), float(d));
            }
    return grid;
}

FloatGrid::Ptr sheet()
{
    FloatGrid::Ptr grid = make_density(1.0 / 64.0, openvdb::Vec3d(-0.5, 0.0, -0.5));
    auto acc = grid->getAccessor();
    for (int i = 0; i < 64; ++i)
        for (int k = 0; k < 64; ++k)
            acc.setValue(Coord(i, 0, k), 1.0f);
    return grid;
}

// Eight soft balls near the corners of [0,127]^3: about 1% of the box active.
FloatGrid::Ptr sparse()
{
    FloatGrid::Ptr grid = make_density(1.0 / 64.0, openvdb::Vec3d(-1.0, 0.0, -1.0));
    auto acc = grid->getAccessor();
    const double radius = 8.5, lo = 9.0, hi = 118.0;
    for (int b = 0; b < 8; ++b) {
        double cx = b & 1 ? hi : lo, cy = b & 2 ? hi : lo, cz = b & 4 ? hi : lo;
        for (int i = int(cx - radius) - 1; i <= int(cx + radius) + 1; ++i)
            for (int j = int(cy - radius) - 1; j <= int(cy + radius) + 1; ++j)
                for (int k = int(cz - radius) - 1; k <= int(cz + radius) + 1; ++k) {
                    double r = std::sqrt((i - cx) * (i - cx) + (j - cy) * (j - cy) +
                                         (k - cz) * (k - cz));
                    double d = 1.0 - smoothstep(radius - 1.0, radius, r);
                    if (d > 0.0)
                        acc.setValue(Coord(i, j, k), float(d));
                }
    }
    return grid;
}

// A plume rising along +y: a column whose radius grows with height, eroded by
// fBm so its edge is wispy, fading in at the source and out at the top.
void smoke(FloatGrid::Ptr &density, Vec3SGrid::Ptr &velocity)
{
    const int nx = 48, ny = 96, nz = 48;
    const double vs = 1.0 / 48.0;
    density = make_density(vs, openvdb::Vec3d(-0.5, 0.0, -0.5));
    velocity = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setName("v");
    velocity->setGridClass(openvdb::GRID_STAGGERED);
    velocity->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    velocity->setTransform(density->transform().copy());
    auto dacc = density->getAccessor();
    auto vacc = velocity->getAccessor();
    const uint32_t seed = 20240611u;
    for (int j = 0; j < ny; ++j) {
        double h = double(j) / (ny - 1); // 0 at the source, 1 at the top
        double radius = (0.10 + 0.22 * h) * nx;
        double cx = nx * 0.5 + 4.0 * std::sin(6.0 * h), cz = nz * 0.5 + 3.0 * std::cos(5.0 * h);
        for (int i = 0; i < nx; ++i)
            for (int k = 0; k < nz; ++k) {
                double dx = i - cx, dz = k - cz;
                double r = std::sqrt(dx * dx + dz * dz);
                double n = fbm(i * 0.09, j * 0.06 - 0.0, k * 0.09, 4, seed);
                double edge = 1.0 - smoothstep(0.55, 1.0, r / radius + 0.6 * (n - 0.5));
                double d = edge * smoothstep(0.0, 0.08, h) * (1.0 - smoothstep(0.75, 1.0, h));
                d *= 0.35 + 0.65 * n;
                if (d < 0.01)
                    continue;
                d = std::min(d, 1.0);
                dacc.setValue(Coord(i, j, k), float(d));
                // Rising, with a gentle swirl about the column's axis (world units/s).
                float swirl = float(0.3 * std::min(r / radius, 1.0));
                float vx = float(-dz / std::max(r, 1e-6)) * swirl;
                float vz = float(dx / std::max(r, 1e-6)) * swirl;
                vacc.setValue(Coord(i, j, k), openvdb::Vec3s(vx, float(0.8 + 0.4 * n), vz));
            }
    }
}

// A puffy plume rising along +y with a velocity field: puffs are bands of
// density along the column, displaced by fBm, so rising and swirling motion
// shows as blur. Both are functions of world position (metres): the plume
// stands on y = 0 in x, z in [-0.5, 0.5], y in [0, 2].
struct plume_frame {
    double cx, cz, radius; // the column's axis and radius at a height
};

plume_frame plume_at(double y)
{
    return {0.06 * std::sin(2.5 * y), 0.06 * std::cos(2.0 * y), 0.08 + 0.15 * y};
}

// Metres per second: rising (faster on the axis), swirling about the axis
// (solid-body inside the column, decaying outside) and spreading near the top.
openvdb::Vec3s plume_velocity(const openvdb::Vec3d &p)
{
    plume_frame f = plume_at(std::clamp(p.y(), 0.0, 2.0));
    double dx = p.x() - f.cx, dz = p.z() - f.cz;
    double r = std::sqrt(dx * dx + dz * dz), q = r / f.radius;
    double vy = 0.7 + 0.6 * std::exp(-0.5 * q * q);
    double swirl = 0.9 * std::min(q, 1.0) * std::exp(-0.5 * std::max(q - 1.0, 0.0));
    double spread = 0.3 * smoothstep(1.2, 2.0, p.y());
    double ux = r > 1e-9 ? dx / r : 0.0, uz = r > 1e-9 ? dz / r : 0.0;
    return openvdb::Vec3s(float(-uz * swirl + ux * spread), float(vy),
                          float(ux * swirl + uz * spread));
}

void plume(FloatGrid::Ptr &density, Vec3SGrid::Ptr &velocity)
{
    const int n = 64; // voxels per metre
    const double vs = 1.0 / n;
    density = make_density(vs, openvdb::Vec3d(-0.5, 0.0, -0.5));
    auto dacc = density->getAccessor();
    const uint32_t seed = 7771u;
    for (int j = 0; j < 2 * n; ++j) {
        double y = (j + 0.5) * vs;
        plume_frame f = plume_at(y);
        // Noise in a frame twisted about the axis: swirling wisps.
        double a = 1.6 * y, ca = std::cos(a), sa = std::sin(a);
        for (int i = 0; i < n; ++i)
            for (int k = 0; k < n; ++k) {
                double dx = (i + 0.5) * vs - 0.5 - f.cx, dz = (k + 0.5) * vs - 0.5 - f.cz;
                double q = std::sqrt(dx * dx + dz * dz) / f.radius;
                if (q > 1.6)
                    continue;
                double nz = fbm((ca * dx - sa * dz) * 16.0, y * 9.0, (sa * dx + ca * dz) * 16.0, 5,
                                seed);
                double edge = 1.0 - smoothstep(0.5, 0.9, q + 1.1 * (nz - 0.5));
                double band = 0.5 + 0.5 * std::sin(2.0 * 3.14159265358979 * (3.0 * y + 2.0 * nz));
                double puffs = 0.1 + 0.9 * smoothstep(0.3, 0.7, band);
                double d = edge * puffs * smoothstep(0.0, 0.1, y) *
                           (1.0 - smoothstep(1.6, 1.95, y));
                d *= smoothstep(0.25, 0.65, nz);
                if (d < 0.01)
                    continue;
                dacc.setValue(Coord(i, j, k), float(std::min(d, 1.0)));
            }
    }
    // The velocity: half the resolution, over the density's voxels dilated by
    // 8 density voxels (every coarse voxel whose trilinear stencil reaches them).
    FloatGrid::TreeType band(density->tree());
    openvdb::tools::dilateActiveValues(band, 8, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    velocity = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setName("v");
    velocity->setGridClass(openvdb::GRID_STAGGERED);
    velocity->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    auto vxf = openvdb::math::Transform::createLinearTransform(2.0 * vs);
    vxf->postTranslate(openvdb::Vec3d(-0.5, 0.0, -0.5));
    velocity->setTransform(vxf);
    velocity->setSaveFloatAsHalf(true);
    auto vacc = velocity->getAccessor();
    auto half = [](int32_t x) { return x >= 0 ? x / 2 : -((1 - x) / 2); }; // floor(x / 2)
    for (auto it = band.cbeginLeaf(); it; ++it)
        for (auto v = it->cbeginValueOn(); v; ++v) {
            Coord c = v.getCoord();
            Coord lo(half(c.x()), half(c.y()), half(c.z()));
            for (int a = 0; a < 2; ++a)
                for (int b = 0; b < 2; ++b)
                    for (int e = 0; e < 2; ++e) {
                        Coord cc = lo.offsetBy(a, b, e);
                        if (!vacc.isValueOn(cc))
                            vacc.setValue(cc, plume_velocity(vxf->indexToWorld(cc)));
                    }
        }
}

// box.vdb's box with a constant velocity over the dilated region.
Vec3SGrid::Ptr box_velocity(const FloatGrid &density, const char *name, openvdb::Vec3s value)
{
    Vec3SGrid::Ptr v = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    v->setName(name);
    v->setTransform(density.transform().copy());
    v->tree().fill(openvdb::CoordBBox(Coord(-3, -3, -3), Coord(50, 38, 34)), value, true);
    return v;
}

// A linear vector field on one leaf (trilinear lookups reproduce it exactly).
void vec_ramp(FloatGrid::Ptr &density, Vec3SGrid::Ptr &velocity)
{
    density = make_density(0.25, openvdb::Vec3d(1.0, 2.0, 3.0));
    velocity = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setName("v");
    velocity->setTransform(density->transform().copy());
    auto dacc = density->getAccessor();
    auto vacc = velocity->getAccessor();
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j)
            for (int k = 0; k < 8; ++k) {
                dacc.setValue(Coord(i, j, k), 1.0f);
                vacc.setValue(Coord(i, j, k),
                              openvdb::Vec3s(0.5f * i - 1.0f, 0.25f * j, 2.0f - float(k)));
            }
}

void write_vdb(const std::string &path, openvdb::GridPtrVec grids)
{
    std::string tmp = path + ".tmp";
    openvdb::io::File file(tmp);
    file.setCompression(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
    openvdb::MetaMap meta;
    meta.insertMeta("creator", openvdb::StringMetadata("haze volumes/generate.cpp"));
    file.write(grids, meta);
    file.close();
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
        throw std::runtime_error("cannot rename " + tmp + " to " + path);
    std::printf("wrote %s\n", path.c_str());
}

// Grids that share a name, which haze refuses to choose between.
openvdb::GridPtrVec dup_names()
{
    openvdb::GridPtrVec grids;
    for (float value : {1.0f, 2.0f}) {
        FloatGrid::Ptr g = constant_cube("density", 0.25, 0, 1, value);
        g->setGridClass(openvdb::GRID_FOG_VOLUME);
        grids.push_back(g);
    }
    return grids;
}

template <typename GridT>
nanovdb::GridHandle<nanovdb::HostBuffer> to_nano(const GridT &grid)
{
    return nanovdb::openToNanoVDB(grid, nanovdb::StatsMode::MinMax, nanovdb::ChecksumMode::Partial);
}

void write_nvdb(const std::string &path,
                std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> handles,
                nanovdb::io::Codec codec = nanovdb::io::Codec::NONE)
{
    std::string tmp = path + ".tmp";
    nanovdb::io::writeGrids(tmp, handles, codec);
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
        throw std::runtime_error("cannot rename " + tmp + " to " + path);
    std::printf("wrote %s\n", path.c_str());
}

// The volumes added last (what --only-new writes).
void write_newer(const std::string &dir)
{
    {
        FloatGrid::Ptr b = box();
        FloatGrid::Ptr t = constant_cube("temperature", 1.0 / 32.0, 0, 31, 2500.0f);
        FloatGrid::Ptr tc = constant_cube("temperature_coarse", 1.0 / 16.0, -2, 17, 2500.0f);
        write_vdb(dir + "/box_fire.vdb", {b, t, tc});
        std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> h;
        h.push_back(to_nano(*b));
        h.push_back(to_nano(*t));
        h.push_back(to_nano(*tc));
        write_nvdb(dir + "/box_fire.nvdb", std::move(h), nanovdb::io::Codec::ZIP);
    }
    {
        FloatGrid::Ptr d, t, f;
        Vec3SGrid::Ptr v, c;
        explosion(d, t, v, f, c);
        write_vdb(dir + "/explosion.vdb", {d, t, v, f, c});
    }
    {
        Vec3SGrid::Ptr c = Vec3SGrid::create(openvdb::Vec3s(0.0f));
        c->setName("color");
        c->setTransform(openvdb::math::Transform::createLinearTransform(1.0 / 32.0));
        auto acc = c->getAccessor();
        for (int i = -2; i <= 33; ++i)
            for (int j = -2; j <= 33; ++j)
                for (int k = -2; k <= 33; ++k)
                    acc.setValue(Coord(i, j, k), openvdb::Vec3s(0.2f, 0.5f, 1.0f));
        write_vdb(dir + "/box_color.vdb", {box(), c});
    }
    {
        FloatGrid::Ptr b = box();
        auto acc = b->getAccessor();
        for (int i = 0; i <= 31; ++i)
            for (int j = 0; j <= 31; ++j)
                for (int k = 12; k <= 19; ++k)
                    acc.setValueOff(Coord(i, j, k), 50.0f);
        write_vdb(dir + "/box_inactive.vdb", {b});
    }
}

// The first volumes.
void write_first(const std::string &dir)
{
    FloatGrid::Ptr b = box();
    write_vdb(dir + "/box.vdb", {b});
    {
        std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> h;
        h.push_back(to_nano(*b));
        write_nvdb(dir + "/box.nvdb", std::move(h));
    }
    write_vdb(dir + "/fog_sphere.vdb", {fog_sphere()});
    write_vdb(dir + "/sheet.vdb", {sheet()});
    write_vdb(dir + "/sparse.vdb", {sparse()});
    FloatGrid::Ptr d;
    Vec3SGrid::Ptr v;
    smoke(d, v);
    write_vdb(dir + "/smoke.vdb", {d, v});
    plume(d, v);
    write_vdb(dir + "/plume.vdb", {d, v});
    write_vdb(dir + "/box_velocity.vdb",
              {b, box_velocity(*b, "v", openvdb::Vec3s(1.0f, 0.25f, 0.0f)),
               box_velocity(*b, "v0", openvdb::Vec3s(0.0f))});
    vec_ramp(d, v);
    write_vdb(dir + "/vec_ramp.vdb", {d, v});
    {
        std::vector<nanovdb::GridHandle<nanovdb::HostBuffer>> h;
        h.push_back(to_nano(*v));
        h.push_back(to_nano(*d));
        // ZIP: a NanoVDB vec3 grid is half a megabyte uncompressed (its upper
        // internal node alone).
        write_nvdb(dir + "/vec_ramp.nvdb", std::move(h), nanovdb::io::Codec::ZIP);
    }
}

} // namespace

int main(int argc, char **argv)
{
    const bool only = argc == 4 && std::string(argv[2]) == "--only";
    const bool only_new = argc == 3 && std::string(argv[2]) == "--only-new";
    if ((argc != 2 && !only && !only_new) || (only && std::string(argv[3]) != "dup_names.vdb")) {
        std::fprintf(stderr, "usage: %s OUTDIR [--only-new | --only dup_names.vdb]\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    try {
        openvdb::initialize();
        if (only) {
            write_vdb(dir + "/dup_names.vdb", dup_names());
            return 0;
        }
        write_newer(dir);
        if (!only_new)
            write_first(dir);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "haze_volumes: %s\n", e.what());
        return 1;
    }
    return 0;
}
