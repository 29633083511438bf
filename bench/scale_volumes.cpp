// make bench's scale part (bench/scale.sh): the volumes whose cost should
// follow the image and the optical depth, not the voxel count. Written into
// bench/cache/ (never committed: the largest is over a GB).
//
//   sphere-R.vdb/.nvdb  the unit sphere of smooth density 1 - r (r the distance
//                       from the centre in world units), R voxels across its
//                       radius: voxel (i,j,k) at world (i,j,k)/R holds
//                       1 - |(i,j,k)|/R where that is > 0. Every R has the same
//                       field up to its discretisation, so the same optical
//                       depth (sigma_t x 1 along a diameter).
//   sparse.vdb/.nvdb    small balls (radius 10 voxels, density 1 - d/10) at
//                       hashed places inside voxels [-500, 499]^3, voxel size
//                       1/500 (world [-1, 1]^3): about 2% of the bound active.
//   sparse-2000.vdb/.nvdb  the same balls, as many per voxel of bound, inside
//                       voxels [-1000, 999]^3, voxel size 1/1000: 2% of 2000^3
//                       (a 2.2 GB .nvdb; not part of make bench).
//   cloud-R.vdb/.nvdb   a cumulus of radius R voxels (voxel size 1/R): four
//                       blobs eroded by fBm noise, 24% of the bound active
//                       (the bigcloud part's cloud-250: 500^3, 133 MiB).
//
// Usage: haze_scale_volumes OUTDIR (sphere R | cloud R | sparse | sparse-2000)...
// Prints one line per file: its name, the active voxels and the occupancy.
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

using openvdb::Coord;
using openvdb::FloatGrid;
using LeafT = FloatGrid::TreeType::LeafNodeType;

FloatGrid::Ptr make_density(double voxel_size)
{
    FloatGrid::Ptr grid = FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel_size));
    return grid;
}

// A field's leaves over voxels [-R - 8, R + 8)^3, built in parallel (one z
// row of leaves per task) and added to the tree in order: a 400-voxel radius
// is 268M voxels. f(x, y, z) is the density at voxel (x, y, z); 0 leaves the
// voxel inactive.
template <typename F> FloatGrid::Ptr field(int R, const F &f)
{
    FloatGrid::Ptr grid = make_density(1.0 / R);
    const int lo = (-R / 8 - 1) * 8, n = (2 * R + 16) / 8 + 1;
    std::vector<std::vector<LeafT *>> rows(size_t(n) * size_t(n));
    tbb::parallel_for(0, n * n, [&](int row) {
        const int ox = lo + 8 * (row % n), oy = lo + 8 * (row / n);
        for (int iz = 0; iz < n; ++iz) {
            const int oz = lo + 8 * iz;
            LeafT *leaf = nullptr;
            for (int a = 0; a < 8; ++a)
                for (int b = 0; b < 8; ++b)
                    for (int c = 0; c < 8; ++c) {
                        const float d = f(ox + a, oy + b, oz + c);
                        if (!(d > 0.0f))
                            continue;
                        if (!leaf)
                            leaf = new LeafT(Coord(ox, oy, oz), 0.0f);
                        leaf->setValueOn(Coord(ox + a, oy + b, oz + c), d);
                    }
            if (leaf)
                rows[size_t(row)].push_back(leaf);
        }
    });
    for (auto &row : rows)
        for (LeafT *leaf : row)
            grid->tree().addLeaf(leaf);
    return grid;
}

FloatGrid::Ptr sphere(int R)
{
    return field(R, [R](int x, int y, int z) {
        return float(1.0 - std::sqrt(double(x) * x + double(y) * y + double(z) * z) / R);
    });
}

uint32_t hash(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Balls until 2% of the bound's (2 half)^3 voxels are active.
FloatGrid::Ptr sparse(int half)
{
    const int rb = 10;
    FloatGrid::Ptr grid = make_density(1.0 / half);
    auto acc = grid->getAccessor();
    const uint64_t want = uint64_t(0.02 * 8.0 * double(half) * double(half) * double(half));
    uint64_t active = 0;
    for (uint32_t ball = 0; active < want; ++ball) {
        int c[3];
        for (uint32_t a = 0; a < 3; ++a)
            c[a] = -half + rb + int(hash(ball * 3 + a + 1) % uint32_t(2 * (half - rb)));
        for (int i = -rb; i <= rb; ++i)
            for (int j = -rb; j <= rb; ++j)
                for (int k = -rb; k <= rb; ++k) {
                    const double d = 1.0 - std::sqrt(double(i * i + j * j + k * k)) / rb;
                    if (d <= 0)
                        continue;
                    Coord p(c[0] + i, c[1] + j, c[2] + k);
                    active += !acc.isValueOn(p);
                    acc.setValue(p, std::max(acc.getValue(p), float(d)));
                }
    }
    return grid;
}

// Value noise in [0, 1]: hashed lattice values, smoothly interpolated.
double lattice(int x, int y, int z)
{
    return hash(uint32_t(x) * 73856093u ^ hash(uint32_t(y) * 19349663u ^ hash(uint32_t(z) * 83492791u))) *
           (1.0 / 4294967296.0);
}

double value_noise(double x, double y, double z)
{
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const int ix = int(fx), iy = int(fy), iz = int(fz);
    auto s = [](double t) { return t * t * (3.0 - 2.0 * t); };
    const double u = s(x - fx), v = s(y - fy), w = s(z - fz);
    double c[2][2];
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            c[a][b] = lattice(ix + a, iy + b, iz) * (1 - w) + lattice(ix + a, iy + b, iz + 1) * w;
    const double c0 = c[0][0] * (1 - v) + c[0][1] * v, c1 = c[1][0] * (1 - v) + c[1][1] * v;
    return c0 * (1 - u) + c1 * u;
}

// A cumulus of radius R voxels: four overlapping blobs whose edges fBm noise
// (four octaves, the coarsest a fifth of R) erodes, density rising to 1
// within a tenth of R of the edge: a dense core, wisps and holes at every
// scale, about a quarter of the bound active.
FloatGrid::Ptr cloud(int R)
{
    const double blobs[4][4] = {{0.0, -0.15, 0.0, 0.7},
                                {0.42, 0.05, 0.12, 0.48},
                                {-0.38, 0.0, -0.18, 0.52},
                                {0.08, 0.38, 0.02, 0.45}};
    return field(R, [R, blobs](int x, int y, int z) {
        const double p[3] = {double(x) / R, double(y) / R, double(z) / R};
        double shape = -1.0;
        for (const auto &b : blobs) {
            const double dx = p[0] - b[0], dy = p[1] - b[1], dz = p[2] - b[2];
            shape = std::max(shape, 1.0 - std::sqrt(dx * dx + dy * dy + dz * dz) / b[3]);
        }
        if (shape < -0.3)
            return 0.0f;
        double fbm = 0.0, amp = 0.5, freq = 5.0;
        for (int o = 0; o < 4; ++o, amp *= 0.5, freq *= 2.0)
            fbm += amp * value_noise(p[0] * freq + 17.0 * o, p[1] * freq, p[2] * freq);
        const double d = (shape + 0.45 * (fbm - 0.47)) * 10.0;
        return float(d <= 0.0 ? 0.0 : d >= 1.0 ? 1.0 : d);
    });
}

void write(const std::string &dir, const std::string &name, const FloatGrid::Ptr &grid,
           double bound_voxels)
{
    const std::string vdb = dir + "/" + name + ".vdb", nvdb = dir + "/" + name + ".nvdb";
    {
        openvdb::io::File file(vdb + ".tmp");
        file.setCompression(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
        file.write({grid});
        file.close();
    }
    auto handle =
        nanovdb::openToNanoVDB(*grid, nanovdb::StatsMode::MinMax, nanovdb::ChecksumMode::Partial);
    nanovdb::io::writeGrid(nvdb + ".tmp", handle, nanovdb::io::Codec::NONE);
    if (std::rename((vdb + ".tmp").c_str(), vdb.c_str()) != 0 ||
        std::rename((nvdb + ".tmp").c_str(), nvdb.c_str()) != 0)
        throw std::runtime_error("cannot rename the files of " + name);
    const double active = double(grid->activeVoxelCount());
    std::printf("%s\t%.0f active voxels\t%.2f%% of the bound\n", name.c_str(), active,
                100.0 * active / bound_voxels);
}

} // namespace

int main(int argc, char **argv)
{
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s OUTDIR (sphere R | cloud R | sparse | sparse-2000)...\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    try {
        openvdb::initialize();
        for (int i = 2; i < argc; ++i) {
            const std::string what = argv[i];
            if (what == "sparse") {
                write(dir, "sparse", sparse(500), 1e9);
            } else if (what == "sparse-2000") {
                write(dir, "sparse-2000", sparse(1000), 8e9);
            } else if (what == "cloud" && i + 1 < argc && std::atoi(argv[i + 1]) > 0) {
                const int R = std::atoi(argv[++i]);
                write(dir, "cloud-" + std::to_string(R), cloud(R), 8.0 * R * R * R);
            } else if (what == "sphere" && i + 1 < argc && std::atoi(argv[i + 1]) > 0) {
                const int R = std::atoi(argv[++i]);
                write(dir, "sphere-" + std::to_string(R), sphere(R), 8.0 * R * R * R);
            } else {
                std::fprintf(stderr, "haze_scale_volumes: expected \"sphere R\", \"cloud R\", \"sparse\" or \"sparse-2000\", got \"%s\"\n",
                             what.c_str());
                return 2;
            }
        }
    } catch (const std::exception &e) {
        std::fprintf(stderr, "haze_scale_volumes: %s\n", e.what());
        return 1;
    }
    return 0;
}
