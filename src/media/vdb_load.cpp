// haze's half of the bridge to OpenVDB/NanoVDB: reads .nvdb files itself, with
// NanoVDB's header-only C++ IO (ZIP through zlib), and hands .vdb files to the
// OpenVDB module (vdb_module.h, openvdb_module.cpp), loaded on the first .vdb
// file, so that haze never links libopenvdb. Exceptions are caught at the
// extern "C" boundary and turned into one line of text; the grid leaves as a
// plain malloc'd, 32-byte aligned byte buffer.
#include "media/vdb_load.h"

#include "media/vdb_bridge.hpp"
#include "media/vdb_module.h"
#include "media/nvdb_check.h"

#include <iostream> // before NanoVDB: GridValidator.h uses std::cerr without it
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/GridValidator.h>
#include <nanovdb/util/IO.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

using namespace haze_vdb;

namespace
{

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

// A NanoVDB buffer type whose memory is the vdb_buffer that C will own
// (32-byte aligned, freed with free()): nanovdb::io::readGrid reads the grid
// straight into it, so loading a .nvdb grid holds one copy, not two.
class c_buffer
{
  public:
    c_buffer() = default;
    c_buffer(const c_buffer &) = delete;
    c_buffer &operator=(const c_buffer &) = delete;
    c_buffer(c_buffer &&o) noexcept : data_(o.data_), size_(o.size_)
    {
        o.data_ = nullptr;
        o.size_ = 0;
    }
    c_buffer &operator=(c_buffer &&o) noexcept
    {
        if (this != &o) {
            clear();
            data_ = o.data_;
            size_ = o.size_;
            o.data_ = nullptr;
            o.size_ = 0;
        }
        return *this;
    }
    ~c_buffer() { clear(); }

    // What nanovdb::io::readGrid calls (the second argument is its context).
    static c_buffer create(uint64_t size, const c_buffer * = nullptr)
    {
        // aligned_alloc needs a multiple of the alignment; the tail is zeroed.
        const uint64_t alloc = std::max<uint64_t>(32, (size + 31) / 32 * 32);
        if (size > std::numeric_limits<size_t>::max() - 32)
            throw std::bad_alloc();
        c_buffer b;
        b.data_ = static_cast<uint8_t *>(std::aligned_alloc(32, size_t(alloc)));
        if (!b.data_)
            throw std::bad_alloc();
        std::memset(b.data_ + size, 0, size_t(alloc - size));
        b.size_ = size;
        return b;
    }
    uint8_t *data() { return data_; }
    const uint8_t *data() const { return data_; }
    uint64_t size() const { return size_; }
    void clear()
    {
        std::free(data_);
        data_ = nullptr;
        size_ = 0;
    }
    // Hands the memory to C (vdb_buffer_free releases it).
    vdb_buffer release()
    {
        vdb_buffer b{data_, size_t(size_)};
        data_ = nullptr;
        size_ = 0;
        return b;
    }

  private:
    uint8_t *data_ = nullptr;
    uint64_t size_ = 0;
};

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
                const nanovdb::GridHandle<c_buffer> &handle)
{
    const nanovdb::NanoGrid<ValueT> *grid = handle.template grid<ValueT>();
    if (!grid)
        throw load_error(path + ": could not read grid \"" + name + "\"");
    // NanoVDB's validator follows offsets it does not check: bound them first.
    char why[256];
    if (nvdb_check_tree(handle.data(), handle.size(), why, sizeof why) != 0)
        throw load_error(path + ": grid \"" + name + "\" is corrupt (" + why + ")");
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
    auto handle = nanovdb::io::readGrid<c_buffer>(path, name);
    if (type == VDB_VEC3)
        check_nvdb<nanovdb::Vec3f>(path, name, handle);
    else
        check_nvdb<float>(path, name, handle);
    return handle.buffer().release();
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


// The OpenVDB module's entry table; throws with the module's message.
const haze_openvdb_api &openvdb_module(const char *path)
{
    const haze_openvdb_api *api = nullptr;
    char msg[1024];
    if (vdb_module_get(&api, msg, sizeof msg) != HZ_OK)
        throw load_error(std::string(path) + ": " + msg);
    return *api;
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
    hz_status st = HZ_OK;
    hz_status guard = guarded(path, err, err_size, [&] {
        file_kind kind;
        std::uintmax_t size = check_file(path, &kind);
        if (kind == file_kind::openvdb)
            st = openvdb_module(path).load_grid(path, size, gridname, type, out, err, err_size);
        else
            *out = load_nvdb(path, gridname, type, size);
    });
    return guard == HZ_OK ? st : guard;
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
    hz_status st = HZ_OK;
    hz_status guard = guarded(path, err, err_size, [&] {
        file_kind kind;
        std::uintmax_t size = check_file(path, &kind);
        if (kind == file_kind::openvdb)
            st = openvdb_module(path).list_grids(path, size, cb, user, err, err_size);
        else
            list_nvdb(path, cb, user);
    });
    return guard == HZ_OK ? st : guard;
}
