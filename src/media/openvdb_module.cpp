// The OpenVDB module, libhaze_openvdb.so: everything that needs libopenvdb.
// haze dlopens it on the first .vdb file (vdb_module.h) and calls it through the
// entry table at the end of this file. It checks a .vdb file's layout, reads a
// grid and converts it to NanoVDB (with node statistics), and lists a file's
// grids for `haze info`. The entry table is the one symbol haze looks up (the
// module is built with default visibility: hiding OpenVDB's template
// instantiations made openvdb::initialize() crash). No exception leaves it;
// failures are one line in `err`.
#include "media/vdb_bridge.hpp"
#include "media/vdb_module.h"

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/util/logging.h>
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

using namespace haze_vdb;

namespace
{

// OpenVDB built with log4cplus logs warnings (coloured, to stdout) that are
// not haze's messages: quiet them where its logging header is the real one
// (elsewhere setLevel is a stub, and the reader keeps stdout out of its
// replies; vdb_reader.c).
void init_openvdb()
{
    static std::once_flag once;
    std::call_once(once, [] {
        openvdb::initialize();
        openvdb::logging::setLevel(openvdb::logging::Level::Fatal);
    });
}

// OpenVDB trusts a file's structure: a truncated file makes it read lengths and
// offsets from past the end (we have seen it allocate gigabytes for one name). So
// walk the layout first, with every length checked against the file size: header,
// file metadata, then each grid descriptor, whose recorded end must lie within the
// file. (Format as written by openvdb::io::File since file version 216.)
class layout_reader
{
  public:
    layout_reader(const std::string &path, std::uintmax_t size)
        : in_(path, std::ios::binary), size_(size)
    {
    }
    void skip(std::uintmax_t n, const char *what)
    {
        need(n, what);
        in_.seekg(static_cast<std::streamoff>(n), std::ios::cur);
        pos_ += n;
    }
    uint32_t u32(const char *what) { return uint32_t(read_le(4, what)); }
    uint64_t u64(const char *what) { return read_le(8, what); }
    uint32_t string(const char *what)
    {
        uint32_t n = u32(what);
        skip(n, what);
        return n;
    }
    std::uintmax_t size() const { return size_; }
    void seek_to(std::uintmax_t pos, const char *what)
    {
        if (pos < pos_)
            throw load_error(std::string("corrupt file (") + what + " points backwards)");
        skip(pos - pos_, what);
    }

  private:
    void need(std::uintmax_t n, const char *what)
    {
        if (n > size_ - pos_)
            throw load_error("file is truncated (" + std::string(what) + " at byte " +
                             std::to_string(pos_) + " needs " + std::to_string(n) +
                             " bytes, file has " + std::to_string(size_) + ")");
    }
    uint64_t read_le(int n, const char *what)
    {
        need(uintmax_t(n), what);
        unsigned char b[8] = {0};
        in_.read(reinterpret_cast<char *>(b), n);
        pos_ += uintmax_t(n);
        uint64_t v = 0;
        for (int i = n - 1; i >= 0; --i)
            v = v << 8 | b[i];
        return v;
    }
    std::ifstream in_;
    std::uintmax_t size_, pos_ = 0;
};

void skip_file_metadata(layout_reader &r)
{
    for (uint32_t i = 0, n = r.u32("metadata count"); i < n; ++i) {
        r.string("metadata name");
        r.string("metadata type");
        r.skip(r.u32("metadata size"), "metadata value");
    }
}

// A descriptor's recorded end is where the next one starts, so it must lie within
// the file.
void check_grid_descriptors(layout_reader &r)
{
    uint32_t grids = r.u32("grid count");
    for (uint32_t g = 0; g < grids; ++g) {
        r.string("grid name");
        r.string("grid type");
        r.string("grid instance parent");
        r.u64("grid position");
        r.u64("grid block position");
        uint64_t end = r.u64("grid end");
        if (end > r.size())
            throw load_error("file is truncated (grid " + std::to_string(g + 1) + " of " +
                             std::to_string(grids) + " ends at byte " + std::to_string(end) +
                             ", file has " + std::to_string(r.size()) + ")");
        r.seek_to(end, "grid end"); // where the next descriptor starts
    }
}

void check_vdb_layout(const std::string &path, std::uintmax_t size)
{
    try {
        layout_reader r(path, size);
        r.skip(8, "magic number");
        uint32_t version = r.u32("file version");
        if (version < 216)
            return; // older layouts: leave it to OpenVDB
        r.skip(8, "library version");
        r.skip(1, "grid offsets flag");
        r.skip(36, "UUID");
        skip_file_metadata(r);
        check_grid_descriptors(r);
    } catch (const load_error &e) {
        throw load_error(path + ": " + e.what());
    }
}

std::unique_ptr<openvdb::io::File> open_vdb(const std::string &path, std::uintmax_t file_size)
{
    init_openvdb();
    auto file = std::make_unique<openvdb::io::File>(path);
    file->setCopyMaxBytes(0); // never copy to a temporary file
    check_vdb_layout(path, file_size);
    try {
        // Delayed loading would map the file lazily; the whole grid is converted.
        file->open(/*delayLoad=*/false);
    } catch (const std::exception &e) {
        throw load_error(path + ": not a readable VDB file (" + plain_text(e.what()) + ")");
    }
    return file;
}

std::vector<std::string> vdb_names(openvdb::io::File &file)
{
    std::vector<std::string> names;
    for (auto it = file.beginName(); it != file.endName(); ++it)
        names.push_back(it.gridName());
    return names;
}

// `name` without OpenVDB's "[N]" suffix, which tells apart grids that share a
// name ("density[0]", "density[1]").
std::string base_name(const std::string &name)
{
    size_t open = name.rfind('[');
    if (name.size() < 3 || name.back() != ']' || open == std::string::npos ||
        open + 2 >= name.size())
        return name;
    for (size_t i = open + 1; i + 1 < name.size(); ++i)
        if (name[i] < '0' || name[i] > '9')
            return name;
    return name.substr(0, open);
}

// OpenVDB reads the first of several grids called `name` (and logs a warning
// about it); haze will not guess which one a scene means, and names them as
// OpenVDB does so that "string gridname" can pick one.
void refuse_ambiguous(const std::string &path, openvdb::io::File &file, const std::string &name)
{
    if (base_name(name) != name)
        return; // an indexed name picks one grid
    std::vector<std::string> same;
    for (const std::string &n : vdb_names(file))
        if (base_name(n) == name)
            same.push_back(n);
    if (same.size() > 1)
        throw load_error(path + ": " + std::to_string(same.size()) + " grids are named \"" + name +
                         "\"; name one of them as OpenVDB does: " + join(same));
}

// What each value type is called in messages, and its OpenVDB grid type.
const char *type_name(vdb_value_type type) { return type == VDB_VEC3 ? "vec3s" : "float"; }

template <typename GridT>
vdb_buffer convert_vdb(const std::string &path, const std::string &name,
                       const openvdb::GridBase::Ptr &base, int memfd)
{
    typename GridT::Ptr grid = openvdb::gridPtrCast<GridT>(base);
    if (!grid)
        throw load_error(path + ": grid \"" + name + "\" is " + base->valueType() +
                         ", expected " + openvdb::typeNameAsString<typename GridT::ValueType>());
    // Node min/max statistics are what empty-space skipping and the motion
    // bounds use (for vectors: the values of least and greatest length). The
    // grid is built straight into the buffer haze receives: the reader's
    // peak is OpenVDB's tree and the NanoVDB grid, not a third copy.
    using OpenBuildT = typename GridT::TreeType::BuildType;
    using NanoBuildT = typename nanovdb::OpenToNanoType<OpenBuildT>::Type;
    nanovdb::OpenToNanoVDB<OpenBuildT, NanoBuildT, nanovdb::AbsDiff, c_buffer> convert;
    auto handle = convert(*grid, nanovdb::StatsMode::MinMax, nanovdb::ChecksumMode::Partial, 0,
                          c_buffer::in_file(memfd));
    if (!handle)
        throw load_error(path + ": converting grid \"" + name + "\" to NanoVDB failed");
    return handle.buffer().release();
}

vdb_buffer load_vdb(const std::string &path, const std::string &name, vdb_value_type type,
                    std::uintmax_t size, int memfd)
{
    auto file_ptr = open_vdb(path, size);
    openvdb::io::File &file = *file_ptr;
    refuse_ambiguous(path, file, name);
    if (!file.hasGrid(name))
        throw load_error(path + ": no grid named \"" + name +
                         "\" (grids: " + join(vdb_names(file)) + ")");
    openvdb::GridBase::Ptr meta = file.readGridMetadata(name);
    bool ok = type == VDB_VEC3 ? meta->isType<openvdb::Vec3SGrid>()
                               : meta->isType<openvdb::FloatGrid>();
    if (!ok)
        throw load_error(path + ": grid \"" + name + "\" is " + meta->valueType() +
                         ", expected " + type_name(type));
    openvdb::GridBase::Ptr base = file.readGrid(name);
    file.close();
    return type == VDB_VEC3 ? convert_vdb<openvdb::Vec3SGrid>(path, name, base, memfd)
                            : convert_vdb<openvdb::FloatGrid>(path, name, base, memfd);
}

// World bounds of the cells of the voxels in [lo, hi]: the 8 corners of
// [lo - 1/2, hi + 1/2] mapped through the transform.
void world_cells(const openvdb::math::Transform &xf, const openvdb::CoordBBox &box,
                 vdb_grid_info &info)
{
    for (int a = 0; a < 3; ++a) {
        info.world_min[a] = std::numeric_limits<double>::infinity();
        info.world_max[a] = -std::numeric_limits<double>::infinity();
    }
    for (int c = 0; c < 8; ++c) {
        openvdb::Vec3d p((c & 1 ? box.max().x() + 0.5 : box.min().x() - 0.5),
                         (c & 2 ? box.max().y() + 0.5 : box.min().y() - 0.5),
                         (c & 4 ? box.max().z() + 0.5 : box.min().z() - 0.5));
        openvdb::Vec3d w = xf.indexToWorld(p);
        for (int a = 0; a < 3; ++a) {
            info.world_min[a] = std::min(info.world_min[a], w[a]);
            info.world_max[a] = std::max(info.world_max[a], w[a]);
        }
    }
}

template <typename GridT, typename F>
void value_range(const GridT &grid, F &&f, vdb_grid_info &info)
{
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        double v = f(*it);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    if (lo <= hi) {
        info.has_range = 1;
        info.min_value = lo;
        info.max_value = hi;
    }
}

// One grid at a time, each released before the next is read: a file of
// thousands of grids is described in the memory of its largest one (all of
// them at once took 6 GiB for a 190 MiB file of 20,000 grids). Each grid is
// listed by the name "gridname" accepts ("density[0]" and "density[1]"
// for two grids named "density").
void list_vdb(const std::string &path, std::uintmax_t size, vdb_grid_callback cb, void *user)
{
    auto file = open_vdb(path, size);
    for (const std::string &name : vdb_names(*file)) {
        openvdb::GridBase::ConstPtr g = file->readGrid(name);
        vdb_grid_info info{};
        std::string type = g->valueType();
        info.name = name.c_str();
        info.type = type.c_str();
        info.active_voxels = g->activeVoxelCount();
        openvdb::CoordBBox box = g->evalActiveVoxelBoundingBox();
        if (box.empty())
            box = openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(0));
        for (int a = 0; a < 3; ++a) {
            info.index_min[a] = box.min()[a];
            info.index_max[a] = box.max()[a];
        }
        world_cells(g->transform(), box, info);
        openvdb::Vec3d vs = g->voxelSize();
        for (int a = 0; a < 3; ++a)
            info.voxel_size[a] = vs[a];
        if (auto fg = openvdb::gridConstPtrCast<openvdb::FloatGrid>(g))
            value_range(
                *fg, [](float v) { return double(v); }, info);
        else if (auto dg = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(g))
            value_range(
                *dg, [](double v) { return v; }, info);
        else if (auto vg = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(g))
            value_range(
                *vg, [](const openvdb::Vec3s &v) { return double(v.length()); }, info);
        cb(&info, user);
    }
    file->close();
}


hz_status module_load_grid(const char *path, uint64_t file_size, const char *gridname,
                           vdb_value_type type, int memfd, vdb_buffer *out, char *err,
                           size_t err_size)
{
    *out = vdb_buffer{nullptr, 0, nullptr, 0};
    return guarded(path, err, err_size,
                   [&] { *out = load_vdb(path, gridname, type, file_size, memfd); });
}

hz_status module_list_grids(const char *path, uint64_t file_size, vdb_grid_callback cb,
                            void *user, char *err, size_t err_size)
{
    return guarded(path, err, err_size, [&] { list_vdb(path, file_size, cb, user); });
}

} // namespace

extern "C" {
extern const haze_openvdb_api haze_openvdb_entry;
const haze_openvdb_api haze_openvdb_entry = {
    HAZE_OPENVDB_ABI,
    sizeof(haze_openvdb_api),
    module_load_grid,
    module_list_grids,
};
}
