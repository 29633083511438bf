// Writes haze's small test and demo volumes (all FloatGrids named "density", in
// non-negative index space, a few hundred KB at most):
//
//   box.vdb, box.nvdb  density exactly 1 on voxels [0,31]^3, voxel size 1/32, no
//                      offset: voxel (i,j,k) sits at world (i,j,k)/32
//   fog_sphere.vdb     radius 0.75 sphere centred at the world origin, density 1
//                      inside, a smooth fall-off over its outer 0.125
//   sheet.vdb          a one-voxel-thin sheet: voxels [0,63] x {0} x [0,63] at
//                      density 1, voxel size 1/64, world x, z in [-0.5, 0.5], y = 0
//   smoke.vdb          a rising plume (fBm value noise, densities in [0,1]) plus a
//                      Vec3f velocity grid "v" on the same voxels
//
// Deterministic: fixed seeds and our own integer hash (OpenVDB still writes a
// random file UUID into each header, so the bytes differ between runs).
// Usage: haze_volumes OUTDIR
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
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

void write_nvdb(const std::string &path, const FloatGrid &grid)
{
    auto handle =
        nanovdb::openToNanoVDB(grid, nanovdb::StatsMode::MinMax, nanovdb::ChecksumMode::Partial);
    std::string tmp = path + ".tmp";
    nanovdb::io::writeGrid(tmp, handle);
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
        throw std::runtime_error("cannot rename " + tmp + " to " + path);
    std::printf("wrote %s\n", path.c_str());
}

} // namespace

int main(int argc, char **argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    try {
        openvdb::initialize();
        FloatGrid::Ptr b = box();
        write_vdb(dir + "/box.vdb", {b});
        write_nvdb(dir + "/box.nvdb", *b);
        write_vdb(dir + "/fog_sphere.vdb", {fog_sphere()});
        write_vdb(dir + "/sheet.vdb", {sheet()});
        FloatGrid::Ptr d;
        Vec3SGrid::Ptr v;
        smoke(d, v);
        write_vdb(dir + "/smoke.vdb", {d, v});
    } catch (const std::exception &e) {
        std::fprintf(stderr, "haze_volumes: %s\n", e.what());
        return 1;
    }
    return 0;
}
