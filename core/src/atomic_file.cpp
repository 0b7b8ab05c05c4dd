// Temporary file + rename (see atomic_file.hpp). POSIX only: mkstemp, fsync, rename.
#include "atomic_file.hpp"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace dqj {
namespace {

std::runtime_error systemError(const std::string& path, int error) {
    return std::runtime_error(AtomicFile::failureMessage(path, std::strerror(error)));
}

/// The process umask, read without changing it: umask() can only be read by setting it,
/// which would race with other threads creating files. Linux reports it in /proc.
mode_t currentUmask() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("Umask:", 0) == 0) return static_cast<mode_t>(std::stoul(line.substr(6), nullptr, 8));
    }
    return 022;
}

}  // namespace

std::string AtomicFile::failureMessage(const std::string& path, const std::string& reason) {
    return "cannot write '" + path + "': " + reason;
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
    const std::filesystem::path target(path_);
    if (path_.empty() || !target.has_filename()) throw std::runtime_error(failureMessage(path_, "not a file name"));
    const std::filesystem::path folder = target.parent_path();
    std::string hidden = ".";  // appended, not operator+: GCC 12 warns falsely (-Wrestrict) on the latter
    hidden += target.filename().string();
    hidden += ".tmp-XXXXXX";
    const std::string pattern = (folder / hidden).string();
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    const int fd = ::mkstemp(name.data());
    if (fd < 0) throw systemError(path_, errno);
    ::close(fd);
    tempPath_ = name.data();
}

AtomicFile::~AtomicFile() {
    if (!committed_) ::unlink(tempPath_.c_str());
}

void AtomicFile::commit() {
    if (committed_) return;
    const int fd = ::open(tempPath_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw systemError(path_, errno);
    // mkstemp makes the file 0600; a user's output should be as readable as any other file.
    // If the file is replaced, keep the existing file's mode instead.
    struct stat existing {};
    const mode_t mode = ::stat(path_.c_str(), &existing) == 0 ? (existing.st_mode & 07777) : (0666 & ~currentUmask());
    if (::fchmod(fd, mode) != 0 || ::fsync(fd) != 0) {
        const int error = errno;
        ::close(fd);
        throw systemError(path_, error);
    }
    ::close(fd);
    if (::rename(tempPath_.c_str(), path_.c_str()) != 0) throw systemError(path_, errno);
    committed_ = true;
    // Make the rename itself durable; best effort, since the data is already in place.
    const std::filesystem::path folder = std::filesystem::path(path_).parent_path();
    const int folderFd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (folderFd >= 0) {
        ::fsync(folderFd);
        ::close(folderFd);
    }
}

std::string AtomicFile::lowercaseExtension(const std::string& path) {
    std::string extension = std::filesystem::path(path).extension().string();
    for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return extension;
}

}  // namespace dqj
