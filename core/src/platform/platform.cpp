// The parts of platform.hpp that are the same on every system, built on the system's steps of
// platform_posix.cpp or platform_windows.cpp: hidden names, reading a small file, running a command.
#include "platform/platform.hpp"

#include <algorithm>
#include <cerrno>
#include <random>
#include <system_error>

namespace dqj::platform {

std::string hiddenPrefix(const std::string& path) {
    std::string name = utf8FromPath(pathFromUtf8(path).filename());
    std::size_t length = std::min<std::size_t>(name.size(), 200);
    while (length > 0 && length < name.size() && (static_cast<unsigned char>(name[length]) & 0xc0) == 0x80) --length;
    std::string prefix = ".";  // appended, not operator+: GCC 12 warns falsely (-Wrestrict) on the latter
    prefix += name.substr(0, length);
    prefix += ".tmp-";
    return prefix;
}

std::string randomSuffix() {
    // A thread_local, as it is trivially destructible (scripts/check-style.sh): nothing runs at thread exit.
    static thread_local std::mt19937_64 generator{std::random_device{}() ^ (std::uint64_t(processId()) << 32)};
    static constexpr char kLetters[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    std::string suffix(6, 'x');
    for (char& ch : suffix) ch = kLetters[generator() % (sizeof kLetters - 1)];
    return suffix;
}

std::optional<std::string> readUpTo(const std::string& path, std::size_t limit) {
    std::error_code error;
    const auto status = std::filesystem::status(pathFromUtf8(path), error);
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
        throw FileError("not a regular file");  // a FIFO would block
    const int fd = openForReading(path);
    if (fd < 0 && errno == ENOENT) return std::nullopt;
    if (fd < 0) throw FileError(std::generic_category().message(errno), errno);
    std::string text;
    std::vector<char> chunk(std::size_t(1) << 16);
    int failure = 0;
    while (text.size() < limit) {
        const std::int64_t got = readSome(fd, chunk.data(), std::min(chunk.size(), limit - text.size()));
        if (got < 0) failure = errno;
        if (got <= 0) break;
        text.append(chunk.data(), std::size_t(got));
    }
    closeFile(fd);
    if (failure) throw FileError(std::generic_category().message(failure), failure);
    return text;
}

CommandOutput runCommand(const std::string& command) {
    std::FILE* pipe = openCommand(command);
    if (!pipe) throw std::runtime_error("cannot run " + command);
    CommandOutput result;
    char buffer[512];
    while (std::fgets(buffer, sizeof buffer, pipe)) result.output += buffer;
    result.exitCode = closeCommand(pipe);
    return result;
}

}  // namespace dqj::platform
