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
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

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

// Copies the handle's bytes into memory that C owns and frees with free() (one
// C library serves haze and the module, so either side may free it).
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
