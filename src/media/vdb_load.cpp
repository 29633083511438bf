// haze's half of the bridge to OpenVDB/NanoVDB: reads .nvdb files itself, with
// NanoVDB's header-only C++ IO (ZIP through zlib), and hands .vdb files to the
// OpenVDB module (vdb_module.h, openvdb_module.cpp), loaded on the first .vdb
// file, so that haze never links libopenvdb. Exceptions are caught at the
// extern "C" boundary and turned into one line of text; the grid leaves as a
// plain malloc'd, 32-byte aligned byte buffer.
#include "media/vdb_load.h"

extern "C" {
#include "core/file.h"
}

#include "media/vdb_bridge.hpp"
#include "media/vdb_cache.h"
#include "media/vdb_isolated.h"
#include "media/vdb_module.h"
#include "media/nvdb_check.h"

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/GridHandle.h>
#include <nanovdb/util/IO.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <functional>
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

// A vdb_buffer this side still owns: freed when an exception passes.
class owned_buffer
{
  public:
    owned_buffer() = default;
    explicit owned_buffer(vdb_buffer b) : b_(b) {}
    owned_buffer(const owned_buffer &) = delete;
    owned_buffer &operator=(const owned_buffer &) = delete;
    owned_buffer(owned_buffer &&o) noexcept : b_(o.release()) {}
    owned_buffer &operator=(owned_buffer &&o) noexcept
    {
        if (this != &o) {
            vdb_buffer_free(&b_);
            b_ = o.release();
        }
        return *this;
    }
    ~owned_buffer() { vdb_buffer_free(&b_); }
    uint8_t *data() const { return static_cast<uint8_t *>(b_.data); }
    size_t size() const { return b_.size; }
    // Hands the memory to C (vdb_buffer_free releases it).
    vdb_buffer release()
    {
        vdb_buffer b = b_;
        b_ = vdb_buffer{nullptr, 0, nullptr, 0};
        return b;
    }

  private:
    vdb_buffer b_{nullptr, 0, nullptr, 0};
};

// The grid's header copied out of a buffer (which may be only 8-byte
// aligned: NanoVDB's types want 32).
nanovdb::GridData grid_header(const owned_buffer &buf)
{
    nanovdb::GridData gd;
    std::memcpy(static_cast<void *>(&gd), buf.data(), sizeof gd);
    return gd;
}

// The .nvdb file format read with every size checked against the file before
// it is used: NanoVDB's own reader trusts the name length (and reads past a
// name without its NUL), the compressed chunk size and the grid size it finds
// in the file. Layout (NanoVDB 32.x): segments of a 16-byte header, then one
// 176-byte record plus the name per grid, then the grids' data in order; a
// ZIP-coded grid's data is its compressed size (8 bytes) and the zlib stream.
struct nvdb_entry {
    nanovdb::io::MetaData meta;
    std::string name;
    uint64_t data_offset; // where the grid's data starts in the file
    nanovdb::io::Codec codec;
};

// NanoVDB's toStr indexes a table with the type read from the file.
const char *type_name(nanovdb::GridType t)
{
    int i = int(t);
    return i >= 0 && i < int(nanovdb::GridType::End) ? nanovdb::toStr(t) : "an unknown type";
}

load_error corrupt(const std::string &path, const std::string &what)
{
    return load_error(path + ": not a valid NanoVDB file (" + what + ")");
}

void read_at(std::ifstream &is, const std::string &path, uint64_t offset, void *dst, uint64_t n)
{
    is.seekg(std::streamoff(offset));
    is.read(static_cast<char *>(dst), std::streamsize(n));
    if (!is)
        throw corrupt(path, "read failed at byte " + std::to_string(offset));
}

std::vector<nvdb_entry> nvdb_index(const std::string &path, uint64_t file_size)
{
    static_assert(sizeof(nanovdb::io::Header) == 16 && sizeof(nanovdb::io::MetaData) == 176,
                  "NanoVDB file records changed size");
    std::ifstream is(path, std::ios::in | std::ios::binary);
    if (!is)
        throw load_error(path + ": cannot open file (" + std::strerror(errno) + ")");
    std::vector<nvdb_entry> out;
    uint64_t pos = 0;
    while (pos < file_size) {
        nanovdb::io::Header h;
        if (file_size - pos < sizeof h)
            throw corrupt(path, "truncated segment header");
        read_at(is, path, pos, &h, sizeof h);
        pos += sizeof h;
        if (h.magic != NANOVDB_MAGIC_NUMBER)
            throw corrupt(path, "bad magic number");
        if (h.version.getMajor() != NANOVDB_MAJOR_VERSION_NUMBER)
            throw load_error(path + ": NanoVDB file version " + std::to_string(h.version.getMajor()) +
                             ", expected " + std::to_string(NANOVDB_MAJOR_VERSION_NUMBER));
        if (h.codec != nanovdb::io::Codec::NONE && h.codec != nanovdb::io::Codec::ZIP)
            throw load_error(path + ": NanoVDB codec " + std::to_string(int(h.codec)) +
                             " is not supported (uncompressed and ZIP are)");
        size_t first = out.size();
        for (unsigned g = 0; g < h.gridCount; ++g) {
            nvdb_entry e;
            if (file_size - pos < sizeof e.meta)
                throw corrupt(path, "truncated grid record");
            read_at(is, path, pos, &e.meta, sizeof e.meta);
            pos += sizeof e.meta;
            if (e.meta.nameSize == 0 || e.meta.nameSize > 4096 || file_size - pos < e.meta.nameSize)
                throw corrupt(path, "grid name of " + std::to_string(e.meta.nameSize) + " bytes");
            std::vector<char> name(e.meta.nameSize);
            read_at(is, path, pos, name.data(), name.size());
            pos += e.meta.nameSize;
            if (name.back() != '\0')
                throw corrupt(path, "grid name without its terminating NUL");
            e.name = name.data();
            e.codec = h.codec;
            out.push_back(std::move(e));
        }
        for (size_t i = first; i < out.size(); ++i) {
            if (out[i].meta.fileSize > file_size - pos)
                throw load_error(path + ": file is truncated (grid \"" + out[i].name + "\" needs " +
                                 std::to_string(out[i].meta.fileSize) + " bytes)");
            out[i].data_offset = pos;
            pos += out[i].meta.fileSize;
        }
    }
    return out;
}

// An uncompressed grid that starts 8-byte aligned in the file (as NanoVDB
// writes a grid named "density") is mapped rather than read: private,
// copy-on-write pages of the page cache, so loading it copies nothing and
// zeroes no memory, and a file in the page cache loads at the speed of its
// page tables. Empty when the file cannot be mapped (the caller reads it).
owned_buffer nvdb_map(const std::string &path, const nvdb_entry &e)
{
    const long page = sysconf(_SC_PAGESIZE);
    if (e.codec != nanovdb::io::Codec::NONE || e.data_offset % 8 != 0 || page <= 0)
        return owned_buffer();
    const uint64_t start = e.data_offset / uint64_t(page) * uint64_t(page);
    const uint64_t end = e.data_offset + e.meta.gridSize;
    int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return owned_buffer();
    struct stat st;
    void *m = MAP_FAILED;
    // Only while the file still holds the whole grid: a mapped page past
    // its end would fault (SIGBUS) when read.
    if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && uint64_t(st.st_size) >= end)
        m = mmap(nullptr, size_t(end - start), PROT_READ | PROT_WRITE, MAP_PRIVATE, fd,
                 off_t(start));
    close(fd);
    if (m == MAP_FAILED)
        return owned_buffer();
    madvise(m, size_t(end - start), MADV_WILLNEED); // read ahead a cold file
    return owned_buffer(vdb_buffer{static_cast<uint8_t *>(m) + (e.data_offset - start),
                                   size_t(e.meta.gridSize), m, size_t(end - start)});
}

// The grid's bytes read (or decompressed) into a C-owned, 32-byte aligned
// buffer.
owned_buffer nvdb_read_bytes(const std::string &path, const nvdb_entry &e)
{
    const uint64_t grid_size = e.meta.gridSize, file_bytes = e.meta.fileSize;
    std::ifstream is(path, std::ios::in | std::ios::binary);
    if (!is)
        throw load_error(path + ": cannot open file (" + std::strerror(errno) + ")");
    if (e.codec == nanovdb::io::Codec::NONE) {
        owned_buffer buf(c_buffer::create(grid_size).release());
        read_at(is, path, e.data_offset, buf.data(), grid_size);
        return buf;
    }
    uint64_t chunk = 0;
    if (file_bytes < sizeof chunk)
        throw corrupt(path, "grid \"" + e.name + "\" has no compressed data");
    read_at(is, path, e.data_offset, &chunk, sizeof chunk);
    // zlib expands at most ~1032:1.
    if (chunk > file_bytes - sizeof chunk || grid_size > 1100 * chunk + 4096)
        throw corrupt(path, "grid \"" + e.name + "\" compressed sizes are inconsistent");
    std::vector<Bytef> packed(size_t(chunk) ? size_t(chunk) : 1);
    read_at(is, path, e.data_offset + sizeof chunk, packed.data(), chunk);
    owned_buffer buf(c_buffer::create(grid_size).release());
    uLongf n = uLongf(grid_size);
    if (uncompress(buf.data(), &n, packed.data(), uLong(chunk)) != Z_OK || n != grid_size)
        throw corrupt(path, "grid \"" + e.name + "\" does not decompress");
    return buf;
}

// The grid's bytes, mapped or read; float and vec3f grids are checked
// (nvdb_check.h: the structure and the header's checksum) before anything
// follows an offset in them.
owned_buffer nvdb_read(const std::string &path, const nvdb_entry &e)
{
    const uint64_t grid_size = e.meta.gridSize;
    if (grid_size < sizeof(nanovdb::GridData) + sizeof(nanovdb::TreeData<3>))
        throw corrupt(path, "grid \"" + e.name + "\" of " + std::to_string(grid_size) + " bytes");
    if (grid_size > std::numeric_limits<uint32_t>::max())
        throw load_error(path + ": grid \"" + e.name + "\" is over 4 GiB (not supported)");
    if (e.codec == nanovdb::io::Codec::NONE && grid_size != e.meta.fileSize)
        throw corrupt(path, "grid \"" + e.name + "\" size does not match its data");
    owned_buffer buf = nvdb_map(path, e);
    if (!buf.data())
        buf = nvdb_read_bytes(path, e);
    const nanovdb::GridType type = grid_header(buf).mGridType;
    if (type == nanovdb::GridType::Float || type == nanovdb::GridType::Vec3f) {
        char why[256];
        if (nvdb_check_grid(buf.data(), buf.size(), why, sizeof why) != 0)
            throw load_error(path + ": grid \"" + e.name + "\" is corrupt (" + why + ")");
    }
    return buf;
}

std::string join_names(const std::vector<nvdb_entry> &entries)
{
    std::vector<std::string> names;
    for (const auto &e : entries)
        names.push_back(e.name);
    return join(names);
}

vdb_buffer load_nvdb(const std::string &path, const std::string &name, vdb_value_type type,
                     std::uintmax_t size)
{
    std::vector<nvdb_entry> entries = nvdb_index(path, size);
    const nvdb_entry *found = nullptr;
    for (const auto &e : entries)
        if (!found && e.name == name)
            found = &e;
    if (!found)
        throw load_error(path + ": no grid named \"" + name + "\" (grids: " + join_names(entries) +
                         ")");
    nanovdb::GridType want = type == VDB_VEC3 ? nanovdb::GridType::Vec3f : nanovdb::GridType::Float;
    if (found->meta.gridType != want)
        throw load_error(path + ": grid \"" + name + "\" is " + type_name(found->meta.gridType) +
                         ", expected " + type_name(want));
    owned_buffer buf = nvdb_read(path, *found);
    if (grid_header(buf).mGridType != want)
        throw corrupt(path, "grid \"" + name + "\" type differs from its record");
    return buf.release();
}

void list_nvdb(const std::string &path, std::uintmax_t size, vdb_grid_callback cb, void *user)
{
    std::vector<nvdb_entry> entries = nvdb_index(path, size);
    for (const auto &e : entries) {
        const nanovdb::io::MetaData &m = e.meta;
        vdb_grid_info info{};
        info.name = e.name.c_str();
        info.type = type_name(m.gridType);
        info.active_voxels = m.voxelCount;
        for (int a = 0; a < 3; ++a) {
            info.index_min[a] = m.indexBBox[0][a];
            info.index_max[a] = m.indexBBox[1][a];
            info.voxel_size[a] = m.voxelSize[a];
        }
        owned_buffer buf = nvdb_read(path, e);
        // Same convention as for .vdb files (NanoVDB's own world bbox spans
        // [min, max + 1] instead).
        const nanovdb::GridData gd = grid_header(buf);
        for (int a = 0; a < 3; ++a) {
            info.world_min[a] = std::numeric_limits<double>::infinity();
            info.world_max[a] = -std::numeric_limits<double>::infinity();
        }
        for (int c = 0; c < 8; ++c) {
            nanovdb::Vec3d p(c & 1 ? m.indexBBox[1][0] + 0.5 : m.indexBBox[0][0] - 0.5,
                             c & 2 ? m.indexBBox[1][1] + 0.5 : m.indexBBox[0][1] - 0.5,
                             c & 4 ? m.indexBBox[1][2] + 0.5 : m.indexBBox[0][2] - 0.5);
            nanovdb::Vec3d w = gd.mMap.applyMap(p);
            for (int a = 0; a < 3; ++a) {
                info.world_min[a] = std::min(info.world_min[a], w[a]);
                info.world_max[a] = std::max(info.world_max[a], w[a]);
            }
        }
        // Only grids nvdb_read checked have their root read (vectors: NanoVDB's
        // statistics are the shortest and longest value).
        if (gd.mGridType == nanovdb::GridType::Float || gd.mGridType == nanovdb::GridType::Vec3f) {
            info.has_range = 1;
            nvdb_root_range(buf.data(), buf.size(), &info.min_value, &info.max_value);
        }
        cb(&info, user);
    }
}

std::uintmax_t check_file(const char *path, file_kind *kind)
{
    // A FIFO would block sniff's open for ever; /dev/urandom would look empty.
    hz_error not_regular;
    if (file_check_regular(path, &not_regular) != HZ_OK)
        throw load_error(not_regular.message);
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

// The converted grids of a .vdb file from the cache (vdb_cache.h): true when
// every request is served (a grid, or the marker of an optional grid the file
// lacks); otherwise nothing is kept and the caller converts.
bool cache_load(const vdb_cache &c, const vdb_grid_request *req, size_t n, vdb_buffer *outs,
                int *present)
{
    char entry[sizeof c.dir + 64];
    bool ok = true;
    for (size_t i = 0; i < n && ok; ++i) {
        struct stat st;
        if (req[i].optional && vdb_cache_entry(&c, req[i].name, req[i].type, true, entry,
                                               sizeof entry) &&
            stat(entry, &st) == 0)
            continue; // present[i] stays 0
        ok = vdb_cache_entry(&c, req[i].name, req[i].type, false, entry, sizeof entry) &&
             stat(entry, &st) == 0 && S_ISREG(st.st_mode);
        char msg[256];
        ok = ok && guarded(entry, msg, sizeof msg, [&] {
                 outs[i] = load_nvdb(entry, req[i].name, req[i].type, std::uintmax_t(st.st_size));
             }) == HZ_OK;
        present[i] = ok;
    }
    if (!ok)
        for (size_t i = 0; i < n; ++i) {
            vdb_buffer_free(&outs[i]);
            present[i] = 0;
        }
    return ok;
}

// Writes `path` whole or not at all: a temporary file in the same directory,
// renamed over it.
void cache_write(const std::string &path, const std::function<bool(std::ostream &)> &body)
{
    std::string tmp = path + ".tmp-" + std::to_string(long(getpid()));
    bool ok;
    {
        std::ofstream os(tmp, std::ios::out | std::ios::binary | std::ios::trunc);
        ok = os && body(os);
        os.close();
        ok = ok && !os.fail();
    }
    if (!ok || std::rename(tmp.c_str(), path.c_str()) != 0)
        std::remove(tmp.c_str());
}

// Stores what the reader converted; a failure only costs the next render
// the conversion again.
void cache_store(const vdb_cache &c, const vdb_grid_request *req, size_t n,
                 const vdb_buffer *outs, const int *present)
{
    if (!vdb_cache_prepare(&c))
        return;
    char entry[sizeof c.dir + 64];
    for (size_t i = 0; i < n; ++i) {
        if (!vdb_cache_entry(&c, req[i].name, req[i].type, !present[i], entry, sizeof entry))
            continue;
        if (!present[i]) {
            cache_write(entry, [](std::ostream &) { return true; });
            continue;
        }
        // A handle over the reader's buffer (not owned: no copy), written as
        // NanoVDB's own file format.
        nanovdb::GridHandle<nanovdb::HostBuffer> handle(
            nanovdb::HostBuffer::createFull(outs[i].size, outs[i].data));
        cache_write(entry, [&](std::ostream &os) {
            try {
                nanovdb::io::writeGrid(os, handle, nanovdb::io::Codec::NONE);
            } catch (...) {
                return false;
            }
            return bool(os);
        });
    }
}

} // namespace

extern "C" hz_status vdb_load_grid_set(const char *path, const vdb_grid_request *req, size_t n,
                                       vdb_buffer *outs, int *present, size_t *failed, char *err,
                                       size_t err_size)
{
    if (err && err_size)
        err[0] = '\0';
    *failed = 0;
    for (size_t i = 0; i < n; ++i) {
        outs[i] = vdb_buffer{nullptr, 0, nullptr, 0};
        present[i] = 0;
    }
    file_kind kind = file_kind::unknown;
    std::uintmax_t size = 0;
    hz_status st = guarded(path, err, err_size, [&] { size = check_file(path, &kind); });
    if (st != HZ_OK)
        return st;
    if (kind == file_kind::openvdb) {
        vdb_cache cache;
        bool cached = vdb_cache_open(&cache, path, size);
        if (cached && cache_load(cache, req, n, outs, present))
            return HZ_OK;
        st = vdb_module_load_grid_isolated(path, size, req, n, outs, present, failed, err,
                                           err_size);
        if (st == HZ_OK && cached)
            cache_store(cache, req, n, outs, present);
        return st;
    }
    for (size_t i = 0; i < n; ++i) {
        st = guarded(path, err, err_size,
                     [&] { outs[i] = load_nvdb(path, req[i].name, req[i].type, size); });
        if (st == HZ_OK) {
            present[i] = 1;
        } else if (!(req[i].optional && vdb_error_is_missing_grid(err))) {
            *failed = i;
            for (size_t k = 0; k < n; ++k)
                vdb_buffer_free(&outs[k]);
            return HZ_ERROR;
        }
    }
    if (err && err_size)
        err[0] = '\0';
    return HZ_OK;
}

extern "C" hz_status vdb_load_typed_grid(const char *path, const char *gridname,
                                         vdb_value_type type, vdb_buffer *out, char *err,
                                         size_t err_size)
{
    vdb_grid_request req = {gridname, type, 0};
    int present;
    size_t failed;
    return vdb_load_grid_set(path, &req, 1, out, &present, &failed, err, err_size);
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
            list_nvdb(path, size, cb, user);
    });
    return guard == HZ_OK ? st : guard;
}

extern "C" hz_status vdb_grid_from_dense(const float *values, int nx, int ny, int nz,
                                         const double scale[3], const double origin[3],
                                         const char *name, vdb_buffer *out, char *err,
                                         size_t err_size)
{
    if (err && err_size)
        err[0] = '\0';
    *out = vdb_buffer{nullptr, 0, nullptr, 0};
    return guarded(name, err, err_size, [&] {
        nanovdb::GridBuilder<float> builder(0.0f, nanovdb::GridClass::FogVolume);
        auto acc = builder.getAccessor();
        for (int k = 0; k < nz; ++k)
            for (int j = 0; j < ny; ++j)
                for (int i = 0; i < nx; ++i) {
                    float v = values[(size_t(k) * size_t(ny) + size_t(j)) * size_t(nx) + size_t(i)];
                    if (v != 0.0f)
                        acc.setValue(nanovdb::Coord(i, j, k), v);
                }
        builder.setStats(nanovdb::StatsMode::MinMax);
        builder.setChecksum(nanovdb::ChecksumMode::Partial);
        const double mat[3][3] = {{scale[0], 0, 0}, {0, scale[1], 0}, {0, 0, scale[2]}};
        const double inv[3][3] = {{1 / scale[0], 0, 0}, {0, 1 / scale[1], 0}, {0, 0, 1 / scale[2]}};
        nanovdb::Map map;
        map.set(mat, inv, nanovdb::Vec3d(origin[0], origin[1], origin[2]), 1.0);
        auto handle = builder.getHandle(map, name);
        *out = to_buffer(handle);
    });
}
