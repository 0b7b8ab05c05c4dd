// file_names.hpp - file names are UTF-8 everywhere in the toolkit (the C ABI, the parameter file,
// the command's arguments; Blender hands UTF-8 on every platform), and this is where they meet the
// system. On Linux a name is bytes and nothing changes. On Windows, std::filesystem::path's
// char constructor reads the ANSI code page and the CRT's narrow fopen/open do too, so a
// path is made from char8_t and files are opened by their UTF-16 name. Internal to libdqjulia and
// the command. Costs nothing on Linux; a conversion per call on Windows.
#pragma once

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <string>

#include <fcntl.h>
#ifdef _WIN32
#include <io.h>
#endif

namespace dqj {

/// A UTF-8 file name as a path. On Windows, a name that is not valid UTF-8 throws
/// std::filesystem::filesystem_error; on Linux any bytes are a name.
inline std::filesystem::path pathFromUtf8(const std::string& name) {
    return std::filesystem::path(std::u8string(name.begin(), name.end()));
}

/// A path's name in UTF-8.
inline std::string utf8FromPath(const std::filesystem::path& path) {
    const std::u8string name = path.u8string();
    return std::string(name.begin(), name.end());
}

/// std::fopen of a UTF-8 file name (nullptr and errno on failure, an invalid name included).
inline std::FILE* openFile(const std::string& name, const char* mode) {
#ifdef _WIN32
    try {
        const std::wstring wideMode(mode, mode + std::char_traits<char>::length(mode));
        return ::_wfopen(pathFromUtf8(name).c_str(), wideMode.c_str());
    } catch (const std::filesystem::filesystem_error&) {
        errno = EINVAL;
        return nullptr;
    }
#else
    return std::fopen(name.c_str(), mode);
#endif
}

/// A UTF-8 file name opened for reading, as a descriptor for read() and close() (binary, not
/// inherited by child processes); -1 and errno on failure, an invalid name included.
inline int openForReading(const std::string& name) {
#ifdef _WIN32
    try {
        return ::_wopen(pathFromUtf8(name).c_str(), _O_RDONLY | _O_BINARY | _O_NOINHERIT);
    } catch (const std::filesystem::filesystem_error&) {
        errno = EINVAL;
        return -1;
    }
#else
    return ::open(name.c_str(), O_RDONLY | O_CLOEXEC);
#endif
}

}  // namespace dqj
