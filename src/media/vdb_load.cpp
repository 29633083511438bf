// The bridge between OpenVDB (C++ only) and haze's C code. Everything C++ stays in
// this file: exceptions are caught at the extern "C" boundary and turned into one
// line of text; the grid leaves as a plain malloc'd, 32-byte aligned byte buffer.
#include "media/vdb_load.h"

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/GridValidator.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

// A failure with a message meant for the user (already one line, already naming
// the file), as opposed to exceptions from the libraries, which get the path
// prepended.
struct load_error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

void init_openvdb()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

void set_error(char *err, size_t err_size, const std::string &msg)
{
    if (!err || err_size == 0)
        return;
    // Library messages can span lines; the user gets one.
    std::string line = msg;
    std::replace(line.begin(), line.end(), '\n', ' ');
    std::snprintf(err, err_size, "%s", line.c_str());
}

enum class file_kind { missing, empty, openvdb, nanovdb, unknown };

// Tell the formats apart by their magic numbers rather than the extension, so a
// mislabelled file still loads and a non-VDB file gets a clear message.
file_kind sniff(const char *path, std::uintmax_t *size_out)
{
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in)
        return file_kind::missing;
    std::streamoff size = in.tellg();
    *size_out = size > 0 ? static_cast<std::uintmax_t>(size) : 0;
    if (size <= 0)
        return file_kind::empty;
    in.seekg(0);
    unsigned char magic[8] = {0};
    in.read(reinterpret_cast<char *>(magic), sizeof magic);
    std::streamsize got = in.gcount();
    const uint32_t vdb_magic = 0x56444220u; // openvdb::OPENVDB_MAGIC, little-endian on disk
    const uint64_t nvdb_magic = NANOVDB_MAGIC_NUMBER;
    if (got >= 4) {
        uint32_t m32 = uint32_t(magic[0]) | uint32_t(magic[1]) << 8 | uint32_t(magic[2]) << 16 |
                       uint32_t(magic[3]) << 24;
        if (m32 == vdb_magic)
            return file_kind::openvdb;
    }
    if (got == 8) {
        uint64_t m64 = 0;
        for (int i = 7; i >= 0; --i)
            m64 = m64 << 8 | magic[i];
        if (m64 == nvdb_magic)
            return file_kind::nanovdb;
    }
    return file_kind::unknown;
}

std::string join(const std::vector<std::string> &names)
{
    if (names.empty())
        return "none";
    std::string s;
    for (size_t i = 0; i < names.size(); ++i)
        s += (i ? ", " : "") + ("\"" + names[i] + "\"");
    return s;
}

// Copies the handle's bytes into memory that C owns and frees with free().
template <typename HandleT> vdb_buffer to_buffer(const HandleT &handle)
{
    const size_t size = handle.size();
    const size_t alloc = (size + 31) / 32 * 32; // aligned_alloc needs a multiple
    void *data = std::aligned_alloc(32, alloc);
    if (!data)
        throw std::bad_alloc();
    std::memcpy(data, handle.data(), size);
    std::memset(static_cast<char *>(data) + size, 0, alloc - size);
    return vdb_buffer{data, size};
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
        for (uint32_t i = 0, n = r.u32("metadata count"); i < n; ++i) {
            r.string("metadata name");
            r.string("metadata type");
            r.skip(r.u32("metadata size"), "metadata value");
        }
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
        throw load_error(path + ": not a readable VDB file (" + e.what() + ")");
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

// What each value type is called in messages, and its OpenVDB grid type.
const char *type_name(vdb_value_type type) { return type == VDB_VEC3 ? "vec3s" : "float"; }

template <typename GridT>
vdb_buffer convert_vdb(const std::string &path, const std::string &name,
                       const openvdb::GridBase::Ptr &base)
{
    typename GridT::Ptr grid = openvdb::gridPtrCast<GridT>(base);
    if (!grid)
        throw load_error(path + ": grid \"" + name + "\" is " + base->valueType() +
                         ", expected " + openvdb::typeNameAsString<typename GridT::ValueType>());
    // Node min/max statistics are what empty-space skipping and the motion
    // bounds use (for vectors: the values of least and greatest length).
    auto handle =
        nanovdb::openToNanoVDB(*grid, nanovdb::StatsMode::MinMax, nanovdb::ChecksumMode::Partial);
    if (!handle)
        throw load_error(path + ": converting grid \"" + name + "\" to NanoVDB failed");
    return to_buffer(handle);
}

vdb_buffer load_vdb(const std::string &path, const std::string &name, vdb_value_type type,
                    std::uintmax_t size)
{
    auto file_ptr = open_vdb(path, size);
    openvdb::io::File &file = *file_ptr;
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
    return type == VDB_VEC3 ? convert_vdb<openvdb::Vec3SGrid>(path, name, base)
                            : convert_vdb<openvdb::FloatGrid>(path, name, base);
}

std::vector<nanovdb::io::GridMetaData> nvdb_meta(const std::string &path)
{
    try {
        return nanovdb::io::readGridMetaData(path);
    } catch (const std::exception &e) {
        throw load_error(path + ": not a readable NanoVDB file (" + e.what() + ")");
    }
}

template <typename ValueT>
void check_nvdb(const std::string &path, const std::string &name,
                const nanovdb::GridHandle<nanovdb::HostBuffer> &handle)
{
    const nanovdb::NanoGrid<ValueT> *grid = handle.template grid<ValueT>();
    if (!grid)
        throw load_error(path + ": could not read grid \"" + name + "\"");
    if (!nanovdb::isValid(*grid, /*detailed=*/true))
        throw load_error(path + ": grid \"" + name + "\" is corrupt (failed validation)");
}

vdb_buffer load_nvdb(const std::string &path, const std::string &name, vdb_value_type type,
                     std::uintmax_t size)
{
    std::vector<nanovdb::io::GridMetaData> metas = nvdb_meta(path);
    std::vector<std::string> names;
    const nanovdb::io::GridMetaData *found = nullptr;
    for (const auto &m : metas) {
        names.push_back(m.gridName);
        if (!found && m.gridName == name)
            found = &m;
    }
    if (!found)
        throw load_error(path + ": no grid named \"" + name + "\" (grids: " + join(names) + ")");
    nanovdb::GridType want = type == VDB_VEC3 ? nanovdb::GridType::Vec3f : nanovdb::GridType::Float;
    if (found->gridType != want)
        throw load_error(path + ": grid \"" + name + "\" is " + nanovdb::toStr(found->gridType) +
                         ", expected " + nanovdb::toStr(want));
    if (found->codec == nanovdb::io::Codec::NONE && found->gridSize > size)
        throw load_error(path + ": file is truncated (grid \"" + name + "\" needs " +
                         std::to_string(found->gridSize) + " bytes, file has " +
                         std::to_string(size) + ")");
    auto handle = nanovdb::io::readGrid(path, name);
    if (type == VDB_VEC3)
        check_nvdb<nanovdb::Vec3f>(path, name, handle);
    else
        check_nvdb<float>(path, name, handle);
    return to_buffer(handle);
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

void list_vdb(const std::string &path, std::uintmax_t size, vdb_grid_callback cb, void *user)
{
    auto file = open_vdb(path, size);
    openvdb::GridPtrVecPtr grids = file->getGrids();
    file->close();
    for (const openvdb::GridBase::Ptr &g : *grids) {
        vdb_grid_info info{};
        std::string name = g->getName(), type = g->valueType();
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
}

void list_nvdb(const std::string &path, vdb_grid_callback cb, void *user)
{
    std::vector<nanovdb::io::GridMetaData> metas = nvdb_meta(path);
    for (const auto &m : metas) {
        vdb_grid_info info{};
        info.name = m.gridName.c_str();
        info.type = nanovdb::toStr(m.gridType);
        info.active_voxels = m.voxelCount;
        for (int a = 0; a < 3; ++a) {
            info.index_min[a] = m.indexBBox[0][a];
            info.index_max[a] = m.indexBBox[1][a];
            info.voxel_size[a] = m.voxelSize[a];
        }
        auto handle = nanovdb::io::readGrid(path, m.gridName);
        if (handle.size() < sizeof(nanovdb::GridData))
            throw load_error(path + ": could not read grid \"" + m.gridName + "\"");
        // Same convention as for .vdb files (NanoVDB's own world bbox spans
        // [min, max + 1] instead).
        const nanovdb::Map &map = reinterpret_cast<const nanovdb::GridData *>(handle.data())->mMap;
        for (int a = 0; a < 3; ++a) {
            info.world_min[a] = std::numeric_limits<double>::infinity();
            info.world_max[a] = -std::numeric_limits<double>::infinity();
        }
        for (int c = 0; c < 8; ++c) {
            nanovdb::Vec3d p(c & 1 ? m.indexBBox[1][0] + 0.5 : m.indexBBox[0][0] - 0.5,
                             c & 2 ? m.indexBBox[1][1] + 0.5 : m.indexBBox[0][1] - 0.5,
                             c & 4 ? m.indexBBox[1][2] + 0.5 : m.indexBBox[0][2] - 0.5);
            nanovdb::Vec3d w = map.applyMap(p);
            for (int a = 0; a < 3; ++a) {
                info.world_min[a] = std::min(info.world_min[a], w[a]);
                info.world_max[a] = std::max(info.world_max[a], w[a]);
            }
        }
        if (const nanovdb::NanoGrid<float> *grid = handle.template grid<float>()) {
            info.has_range = 1;
            info.min_value = grid->tree().root().minimum();
            info.max_value = grid->tree().root().maximum();
        } else if (const nanovdb::NanoGrid<nanovdb::Vec3f> *vgrid =
                       handle.template grid<nanovdb::Vec3f>()) {
            // NanoVDB's statistics of vectors: the shortest and longest value.
            info.has_range = 1;
            info.min_value = vgrid->tree().root().minimum().length();
            info.max_value = vgrid->tree().root().maximum().length();
        }
        cb(&info, user);
    }
}

// Runs `body`, turning every exception into an error message.
template <typename F> hz_status guarded(const char *path, char *err, size_t err_size, F &&body)
{
    try {
        body();
        return HZ_OK;
    } catch (const load_error &e) {
        set_error(err, err_size, e.what());
    } catch (const std::bad_alloc &) {
        set_error(err, err_size,
                  std::string(path) + ": out of memory (file corrupt or truncated?)");
    } catch (const std::exception &e) {
        set_error(err, err_size, std::string(path) + ": " + e.what());
    } catch (...) {
        set_error(err, err_size, std::string(path) + ": unknown error while reading");
    }
    return HZ_ERROR;
}

std::uintmax_t check_file(const char *path, file_kind *kind)
{
    std::uintmax_t size = 0;
    *kind = sniff(path, &size);
    switch (*kind) {
    case file_kind::missing:
        throw load_error(std::string(path) + ": cannot open file (" + std::strerror(errno) + ")");
    case file_kind::empty:
        throw load_error(std::string(path) + ": file is empty, expected a .vdb or .nvdb file");
    case file_kind::unknown:
        throw load_error(std::string(path) + ": not a VDB file (expected a .vdb or .nvdb file)");
    case file_kind::openvdb:
    case file_kind::nanovdb: break;
    }
    return size;
}

} // namespace

extern "C" void vdb_buffer_free(vdb_buffer *b)
{
    if (!b)
        return;
    std::free(b->data);
    b->data = nullptr;
    b->size = 0;
}

extern "C" hz_status vdb_load_typed_grid(const char *path, const char *gridname,
                                         vdb_value_type type, vdb_buffer *out, char *err,
                                         size_t err_size)
{
    if (err && err_size)
        err[0] = '\0';
    *out = vdb_buffer{nullptr, 0};
    return guarded(path, err, err_size, [&] {
        file_kind kind;
        std::uintmax_t size = check_file(path, &kind);
        *out = kind == file_kind::openvdb ? load_vdb(path, gridname, type, size)
                                          : load_nvdb(path, gridname, type, size);
    });
}

extern "C" hz_status vdb_load_grid(const char *path, const char *gridname, vdb_buffer *out,
                                   char *err, size_t err_size)
{
    return vdb_load_typed_grid(path, gridname, VDB_FLOAT, out, err, err_size);
}

extern "C" hz_status vdb_list_grids(const char *path, vdb_grid_callback cb, void *user, char *err,
                                    size_t err_size)
{
    if (err && err_size)
        err[0] = '\0';
    return guarded(path, err, err_size, [&] {
        file_kind kind;
        std::uintmax_t size = check_file(path, &kind);
        if (kind == file_kind::openvdb)
            list_vdb(path, size, cb, user);
        else
            list_nvdb(path, cb, user);
    });
}
