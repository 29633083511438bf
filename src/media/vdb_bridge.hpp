// What the two halves of the C++ bridge share: haze's own NanoVDB reader
// (vdb_load.cpp, linked into haze) and the OpenVDB module (openvdb_module.cpp,
// the dlopen'ed libhaze_openvdb.so). Error plumbing (a user-facing exception
// type, one-line messages, the exception-to-hz_status guard) and the copy of a
// NanoVDB grid into a C-owned buffer. Everything here has internal linkage, so
// haze and the module each carry their own copy and never bind to each other's.
#ifndef HAZE_MEDIA_VDB_BRIDGE_HPP
#define HAZE_MEDIA_VDB_BRIDGE_HPP

#include "core/error.h"
#include "media/vdb_grid.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/mman.h>
#include <unistd.h>

namespace haze_vdb
{
namespace
{

// A failure with a message meant for the user (already one line, already naming
// the file), as opposed to exceptions from the libraries, which get the path
// prepended.
struct load_error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

inline void set_error(char *err, size_t err_size, const std::string &msg)
{
    if (!err || err_size == 0)
        return;
    // Library messages can span lines; the user gets one.
    std::string line = msg;
    std::replace(line.begin(), line.end(), '\n', ' ');
    std::snprintf(err, err_size, "%s", line.c_str());
}

// A library's message as plain text: without ANSI escape sequences (the
// colours of OpenVDB's log lines) and with other control bytes as spaces.
// Only for the libraries' own text: names from files keep their bytes, which
// the error line shows escaped (core/text.h).
inline std::string plain_text(const std::string &msg)
{
    std::string out;
    for (size_t i = 0; i < msg.size(); ++i) {
        unsigned char c = static_cast<unsigned char>(msg[i]);
        if (c == 0x1b && i + 1 < msg.size() && msg[i + 1] == '[') {
            // CSI: parameters and intermediates up to a final byte in @..~.
            for (i += 2; i < msg.size() && !(msg[i] >= '@' && msg[i] <= '~'); ++i)
                ;
            continue;
        }
        out += c < 0x20 || c == 0x7f ? ' ' : msg[i];
    }
    return out;
}

inline std::string join(const std::vector<std::string> &names)
{
    if (names.empty())
        return "none";
    std::string s;
    for (size_t i = 0; i < names.size(); ++i)
        s += (i ? ", " : "") + ("\"" + names[i] + "\"");
    return s;
}

// A NanoVDB buffer type (what GridHandle and the converters allocate through)
// whose memory is the vdb_buffer C will own: 32-byte aligned, freed with
// free() (one C library serves haze and the module, so either side may free
// it). A grid built into it is handed over without a copy. Built with an
// allocator from in_file(fd) (the converters pass theirs to create), the
// memory is the file fd instead (a memfd the renderer holds too), mapped
// shared: the grid is built where the renderer will map it, and the
// vdb_buffer it releases is that mapping.
class c_buffer
{
  public:
    c_buffer() = default;
    c_buffer(const c_buffer &) = delete;
    c_buffer &operator=(const c_buffer &) = delete;
    c_buffer(c_buffer &&o) noexcept
        : data_(o.data_), size_(o.size_), mapped_(o.mapped_), fd_(o.fd_)
    {
        o.data_ = nullptr;
        o.size_ = 0;
        o.mapped_ = 0;
    }
    c_buffer &operator=(c_buffer &&o) noexcept
    {
        if (this != &o) {
            clear();
            data_ = o.data_;
            size_ = o.size_;
            mapped_ = o.mapped_;
            fd_ = o.fd_;
            o.data_ = nullptr;
            o.size_ = 0;
            o.mapped_ = 0;
        }
        return *this;
    }
    ~c_buffer() { clear(); }

    // An allocator (no memory) whose buffers live in file fd.
    static c_buffer in_file(int fd)
    {
        c_buffer b;
        b.fd_ = fd;
        return b;
    }

    // What NanoVDB calls (the second argument is its context).
    static c_buffer create(uint64_t size, const c_buffer *context = nullptr)
    {
        // aligned_alloc needs a multiple of the alignment; the tail is zeroed.
        if (size > std::numeric_limits<size_t>::max() - 32)
            throw std::bad_alloc();
        const uint64_t alloc = std::max<uint64_t>(32, (size + 31) / 32 * 32);
        c_buffer b;
        if (context && context->fd_ >= 0) {
            // A fresh file's bytes read 0: the tail is zeroed already.
            if (ftruncate(context->fd_, off_t(alloc)) != 0)
                throw std::bad_alloc();
            void *m = mmap(nullptr, size_t(alloc), PROT_READ | PROT_WRITE, MAP_SHARED,
                           context->fd_, 0);
            if (m == MAP_FAILED)
                throw std::bad_alloc();
            b.data_ = static_cast<uint8_t *>(m);
            b.mapped_ = alloc;
            b.size_ = size;
            return b;
        }
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
        if (mapped_)
            munmap(data_, size_t(mapped_));
        else
            std::free(data_);
        data_ = nullptr;
        size_ = 0;
        mapped_ = 0;
    }
    // Hands the memory to C (vdb_buffer_free releases it).
    vdb_buffer release()
    {
        vdb_buffer b{data_, size_t(size_), mapped_ ? data_ : nullptr, size_t(mapped_)};
        data_ = nullptr;
        size_ = 0;
        mapped_ = 0;
        return b;
    }

  private:
    uint8_t *data_ = nullptr;
    uint64_t size_ = 0;
    uint64_t mapped_ = 0; /* bytes mapped from an allocator's file (0: malloc'd) */
    int fd_ = -1;         /* an allocator's file (in_file); -1: malloc */
};

// Copies the handle's bytes into memory that C owns.
template <typename HandleT> vdb_buffer to_buffer(const HandleT &handle)
{
    c_buffer b = c_buffer::create(handle.size());
    std::memcpy(b.data(), handle.data(), size_t(handle.size()));
    return b.release();
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
        set_error(err, err_size, std::string(path) + ": " + plain_text(e.what()));
    } catch (...) {
        set_error(err, err_size, std::string(path) + ": unknown error while reading");
    }
    return HZ_ERROR;
}

} // namespace
} // namespace haze_vdb

#endif
