// platform.hpp on Linux and other POSIX systems. Files: O_TMPFILE, linkat through /proc/self/fd,
// renameat2(RENAME_NOREPLACE), flock; POSIX fallbacks where they are missing. Memory: ulimit, the
// cgroups (v1 and v2) and /proc. Processors: sched_getaffinity.
#include "platform/platform.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <malloc.h>
#include <sched.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <system_error>

namespace dqj::platform {
namespace {

FileError systemError(int error) { return FileError(std::strerror(error), error); }

void closeDescriptor(int& fd) {
    if (fd >= 0) ::close(fd);
    fd = -1;
}

/// A system file whole (at most 1 MiB; nullopt when there is none, as without /proc or a cgroup).
/// Throws std::system_error or std::runtime_error ("cannot read '/proc/...': reason").
std::optional<std::string> readSystemFile(const std::string& path) {
    constexpr std::size_t kLimit = std::size_t(1) << 20;
    std::optional<std::string> text;
    try {
        text = readUpTo(path, kLimit + 1);
    } catch (const FileError& failure) {
        if (failure.error())
            throw std::system_error(failure.error(), std::generic_category(), "cannot read '" + path + "'");
        throw std::runtime_error("cannot read '" + path + "': " + failure.what());
    }
    if (text && text->size() > kLimit)
        throw std::runtime_error("cannot read '" + path + "': it has more than " + std::to_string(kLimit) + " bytes");
    return text;
}

/// The rest of the first line of a system file that starts with `prefix` ("VmSize:" in
/// /proc/self/status), or nullopt when there is no such line or no such file.
std::optional<std::string> lineStartingWith(const std::string& path, const std::string& prefix) {
    const std::optional<std::string> text = readSystemFile(path);
    if (!text) return std::nullopt;
    for (std::size_t start = 0; start < text->size();) {
        const std::size_t end = std::min(text->find('\n', start), text->size());
        if (text->compare(start, prefix.size(), prefix) == 0)
            return text->substr(start + prefix.size(), end - start - prefix.size());
        start = end + 1;
    }
    return std::nullopt;
}

/// The number a file holds ("max", no number and missing files: nullopt; a read error throws).
std::optional<std::uint64_t> readNumberFile(const std::string& path) {
    const std::optional<std::string> text = lineStartingWith(path, "");
    if (!text || text->empty() || !std::isdigit(static_cast<unsigned char>(text->front()))) return std::nullopt;
    return std::strtoull(text->c_str(), nullptr, 10);
}

/// "VmSize:  123 kB" from /proc/self/status, in bytes.
std::uint64_t statusBytes(const std::string& key) {
    const std::optional<std::string> value = lineStartingWith("/proc/self/status", key);
    return value ? std::strtoull(value->c_str(), nullptr, 10) * 1024 : 0;
}

std::uint64_t headroom(std::uint64_t limit, std::uint64_t used) { return limit > used ? limit - used : 0; }

/// The process umask, read without changing it: umask() can only be read by setting it,
/// which would race with other threads creating files. Linux reports it in /proc.
mode_t currentUmask() {
    const std::optional<std::string> umask = lineStartingWith("/proc/self/status", "Umask:");
    return umask ? static_cast<mode_t>(std::strtoul(umask->c_str(), nullptr, 8)) : 022;
}

void (*interruptHandler)() = nullptr;

extern "C" void onSignal(int) {
    if (interruptHandler) interruptHandler();
}

}  // namespace

std::FILE* openFile(const std::string& name, const char* mode) { return std::fopen(name.c_str(), mode); }

int openForReading(const std::string& name) { return ::open(name.c_str(), O_RDONLY | O_CLOEXEC); }

std::int64_t readSome(int fd, char* data, std::size_t size) { return ::read(fd, data, size); }
std::int64_t writeSome(int fd, const char* data, std::size_t size) { return ::write(fd, data, size); }
std::int64_t seekTo(int fd, std::int64_t offset, int whence) { return ::lseek(fd, off_t(offset), whence); }
int closeFile(int fd) { return ::close(fd); }
int processId() { return int(::getpid()); }

std::optional<FileIdentity> fileIdentity(const std::string& path) {
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0) return std::nullopt;
    return FileIdentity{std::uint64_t(info.st_dev), std::uint64_t(info.st_ino)};
}

Found lookUp(const std::string& path) {
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0) {
        const int error = errno;
        if (error != ENOENT) throw systemError(error);
        if (::lstat(path.c_str(), &info) == 0 && S_ISLNK(info.st_mode)) {
            std::vector<char> target(std::size_t(info.st_size > 0 ? info.st_size : 4096) + 1);
            const ssize_t length = ::readlink(path.c_str(), target.data(), target.size());
            return {Found::DanglingLink, 0, std::string(target.data(), length > 0 ? std::size_t(length) : 0)};
        }
        return {Found::Missing, 0};
    }
    if (S_ISDIR(info.st_mode)) return {Found::Folder, 0};
    return {S_ISREG(info.st_mode) ? Found::Regular : Found::Other, int(info.st_mode & 07777)};
}

std::string nameLengthProblem(const std::string& folder, const std::string& name) {
    const long nameLimit = ::pathconf(folder.c_str(), _PC_NAME_MAX);
    if (nameLimit > 0 && name.size() > std::size_t(nameLimit))
        return "the file name is " + std::to_string(name.size()) + " bytes long; this file system allows at most " +
               std::to_string(nameLimit);
    return "";
}

bool folderWritable(const std::string& folder) { return ::access(folder.c_str(), W_OK) == 0; }

void syncFolder(const std::string& folder) {
    const int folderFd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (folderFd >= 0) {
        ::fsync(folderFd);
        ::close(folderFd);
    }
}

void removeStaleTemporaries(const std::string& folder, const std::string& prefix) {
    DIR* directory = ::opendir(folder.c_str());
    if (!directory) return;
    while (const dirent* entry = ::readdir(directory)) {
        const std::string name = entry->d_name;
        if (name.rfind(prefix, 0) != 0 || name.size() != prefix.size() + 6) continue;
        const std::string stale = folder + "/" + name;
        const int fd = ::open(stale.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
        if (fd < 0) continue;
        struct stat info {};
        // A writer locks its file just after creating it: files changed in the last seconds are left.
        if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && info.st_mtime + 5 < std::time(nullptr) &&
            ::flock(fd, LOCK_EX | LOCK_NB) == 0)
            ::unlink(stale.c_str());
        ::close(fd);
    }
    ::closedir(directory);
}

struct PendingFile::State {
    std::string folder;
    std::string prefix;
    int fd = -1;
    std::string tempPath;  // "" with O_TMPFILE: the data has no name until publish()
    bool published = false;
    int pathFd = -1;        // an O_PATH reference to the unnamed file between prepare() and publish()
    int lockFd = -1;        // keeps a named temporary locked between prepare() and publish()
    std::string asidePath;  // the hidden second name of the file this one replaces (setAside), or ""
    int asideFd = -1;       // keeps the file set aside locked
    dev_t device = 0;       // the written file's identity, so withdraw() removes only that file
    ino_t inode = 0;
};

int openScratchFile(const std::string& folder, const std::string& prefix) {
    int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
        // No O_TMPFILE on this file system: a hidden name, gone again at once (the file stays open).
        const std::string pattern = folder + "/" + prefix + "XXXXXX";
        std::vector<char> buffer(pattern.begin(), pattern.end());
        buffer.push_back('\0');
        fd = ::mkostemp(buffer.data(), O_CLOEXEC);
        if (fd >= 0) ::unlink(buffer.data());
    }
    if (fd < 0) throw systemError(errno);
    return fd;
}

PendingFile::PendingFile(const std::string& folder, const std::string& prefix) : state_(std::make_unique<State>()) {
    State& state = *state_;
    state.folder = folder;
    state.prefix = prefix;
    // An unnamed file is linked by its /proc/self/fd name; without /proc, use the fallback.
    const bool unnamed = ::access("/proc/self/fd", X_OK) == 0;
    state.fd = unnamed ? ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0666) : -1;
    if (state.fd < 0 && (!unnamed || errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
        // No O_TMPFILE on this file system: a hidden, locked name (cleaned by the next run if we die).
        const std::string pattern = folder + "/" + prefix + "XXXXXX";
        std::vector<char> buffer(pattern.begin(), pattern.end());
        buffer.push_back('\0');
        state.fd = ::mkostemp(buffer.data(), O_CLOEXEC);
        if (state.fd >= 0) state.tempPath = buffer.data();
    }
    if (state.fd < 0) throw systemError(errno);
    ::flock(state.fd, LOCK_EX | LOCK_NB);
}

PendingFile::~PendingFile() {
    State& state = *state_;
    closeDescriptor(state.fd);
    closeDescriptor(state.pathFd);
    closeDescriptor(state.lockFd);
    closeDescriptor(state.asideFd);
    if (!state.published && !state.tempPath.empty()) ::unlink(state.tempPath.c_str());
}

int PendingFile::descriptor() const { return state_->fd; }

void PendingFile::prepare(int mode) {
    State& state = *state_;
    // A new file gets 0666 minus the umask, as open() would give it (O_TMPFILE already applied the
    // umask, mkstemp did not).
    const mode_t bits = mode >= 0 ? mode_t(mode) : (0666 & ~currentUmask());
    if (::fchmod(state.fd, bits) != 0 || ::fsync(state.fd) != 0) throw systemError(errno);
    struct stat info {};
    if (::fstat(state.fd, &info) != 0) throw systemError(errno);
    state.device = info.st_dev;
    state.inode = info.st_ino;

    // Close the data descriptor (checked: some file systems report write errors only here),
    // keeping an O_PATH reference so an unnamed file can still be linked, or a second descriptor
    // that keeps a named temporary locked.
    if (state.tempPath.empty()) {
        state.pathFd = ::open(("/proc/self/fd/" + std::to_string(state.fd)).c_str(), O_PATH | O_CLOEXEC);
        if (state.pathFd < 0) throw systemError(errno);
    } else {
        state.lockFd = ::fcntl(state.fd, F_DUPFD_CLOEXEC, 0);
        if (state.lockFd < 0) throw systemError(errno);
    }
    const int fd = state.fd;
    state.fd = -1;
    if (::close(fd) != 0) throw systemError(errno);
}

void PendingFile::publish(const std::string& target, bool replace) {
    State& state = *state_;
    int error = 0;
    if (state.pathFd >= 0) {
        const std::string source = "/proc/self/fd/" + std::to_string(state.pathFd);
        if (!replace) {
            if (::linkat(AT_FDCWD, source.c_str(), AT_FDCWD, target.c_str(), AT_SYMLINK_FOLLOW) != 0) error = errno;
        } else {
            // linkat cannot replace: link under a hidden name, then rename over the target.
            std::string hidden;
            for (int attempt = 0; attempt < 100; ++attempt) {
                hidden = state.folder + "/" + state.prefix + randomSuffix();
                if (::linkat(AT_FDCWD, source.c_str(), AT_FDCWD, hidden.c_str(), AT_SYMLINK_FOLLOW) == 0) {
                    error = 0;
                    break;
                }
                error = errno;
                if (error != EEXIST) break;
            }
            if (!error && ::rename(hidden.c_str(), target.c_str()) != 0) {
                error = errno;
                ::unlink(hidden.c_str());
            }
        }
    } else if (!replace) {
        if (::renameat2(AT_FDCWD, state.tempPath.c_str(), AT_FDCWD, target.c_str(), RENAME_NOREPLACE) != 0) {
            error = errno;
            if (error == EINVAL || error == ENOSYS) {  // no RENAME_NOREPLACE here: link fails on an existing name too
                error = ::link(state.tempPath.c_str(), target.c_str()) == 0 ? 0 : errno;
                if (!error) ::unlink(state.tempPath.c_str());
            }
        }
    } else if (::rename(state.tempPath.c_str(), target.c_str()) != 0) {
        error = errno;
    }
    if (error == EEXIST) throw FileError(std::strerror(error), error, true);
    if (error) throw systemError(error);
    state.published = true;
    closeDescriptor(state.pathFd);
    closeDescriptor(state.lockFd);
}

void PendingFile::setAside(const std::string& target) {
    State& state = *state_;
    struct stat info {};
    if (::lstat(target.c_str(), &info) != 0) {
        if (errno == ENOENT) return;  // nothing there
        throw systemError(errno);
    }
    // Locked first (a regular file), so no writer's clean-up removes it under its hidden name.
    if (S_ISREG(info.st_mode)) {
        state.asideFd = ::open(target.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
        if (state.asideFd >= 0) ::flock(state.asideFd, LOCK_EX | LOCK_NB);
    }
    int error = EEXIST;
    for (int attempt = 0; attempt < 100 && error == EEXIST; ++attempt) {
        const std::string aside = state.folder + "/" + state.prefix + randomSuffix();
        error = ::linkat(AT_FDCWD, target.c_str(), AT_FDCWD, aside.c_str(), 0) == 0 ? 0 : errno;
        if (error == EPERM || error == EOPNOTSUPP || error == EMLINK || error == ENOSYS)  // no hard links: move it
            error = ::rename(target.c_str(), aside.c_str()) == 0 ? 0 : errno;
        if (!error) state.asidePath = aside;
    }
    if (error) {
        closeDescriptor(state.asideFd);
        throw systemError(error);
    }
}

void PendingFile::withdraw(const std::string& target) noexcept {
    State& state = *state_;
    if (!state.asidePath.empty()) {
        // Still both names of one file when this member was never published: rename() then does
        // nothing, and the hidden name goes.
        if (::rename(state.asidePath.c_str(), target.c_str()) == 0) {
            ::unlink(state.asidePath.c_str());
            state.asidePath.clear();
        }
    } else if (state.published) {
        struct stat info {};
        if (::lstat(target.c_str(), &info) == 0 && info.st_dev == state.device && info.st_ino == state.inode)
            ::unlink(target.c_str());
    }
    closeDescriptor(state.asideFd);
}

void PendingFile::dropSetAside() noexcept {
    State& state = *state_;
    if (!state.asidePath.empty()) ::unlink(state.asidePath.c_str());
    closeDescriptor(state.asideFd);
    state.asidePath.clear();
}

std::uint64_t memoryHeadroom() {
    std::uint64_t result = UINT64_MAX;
    struct rlimit limit {};
    if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
        result = std::min(result, headroom(limit.rlim_cur, statusBytes("VmSize:")));
    if (::getrlimit(RLIMIT_DATA, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
        result = std::min(result, headroom(limit.rlim_cur, statusBytes("VmData:")));
    // Every cgroup from ours up to the root may cap us ("0::/a/b" for v2, "N:memory:/a/b" for v1).
    const std::string cgroups = readSystemFile("/proc/self/cgroup").value_or("");
    for (std::size_t start = 0, end = 0; start < cgroups.size(); start = end + 1) {
        end = std::min(cgroups.find('\n', start), cgroups.size());
        const std::string line = cgroups.substr(start, end - start);
        const std::size_t first = line.find(':'), second = line.find(':', first + 1);
        if (first == std::string::npos || second == std::string::npos) continue;
        const std::string controllers = line.substr(first + 1, second - first - 1);
        std::string group = line.substr(second + 1);
        const bool v2 = controllers.empty();
        if (!v2 && controllers.find("memory") == std::string::npos) continue;
        const std::string root = v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory";
        for (;;) {
            const std::string folder = root + (group == "/" ? "" : group);
            const auto max = readNumberFile(folder + (v2 ? "/memory.max" : "/memory.limit_in_bytes"));
            const auto used = readNumberFile(folder + (v2 ? "/memory.current" : "/memory.usage_in_bytes"));
            if (max && *max < (std::uint64_t(1) << 60)) result = std::min(result, headroom(*max, used.value_or(0)));
            if (group.empty() || group == "/") break;
            const std::size_t slash = group.rfind('/');
            group = slash == 0 || slash == std::string::npos ? "/" : group.substr(0, slash);
        }
    }
    return result;
}

std::uint64_t availableMemory() {
    const std::optional<std::string> available = lineStartingWith("/proc/meminfo", "MemAvailable:");
    const std::uint64_t bytes = available ? std::strtoull(available->c_str(), nullptr, 10) * 1024 : 0;
    if (bytes != 0) return bytes;
    const long pages = ::sysconf(_SC_AVPHYS_PAGES);
    const long pageSize = ::sysconf(_SC_PAGESIZE);
    return pages > 0 && pageSize > 0 ? std::uint64_t(pages) * std::uint64_t(pageSize) : 0;
}

std::uint64_t peakMemoryBytes() {
    rusage usage{};
    ::getrusage(RUSAGE_SELF, &usage);
    return std::uint64_t(usage.ru_maxrss) * 1024;
}

void releaseFreedMemory() { ::malloc_trim(0); }

int processorCount() {
    cpu_set_t set;
    CPU_ZERO(&set);
    if (::sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
    return 0;
}

void onInterrupt(void (*handler)()) {
    interruptHandler = handler;
    struct sigaction action {};
    action.sa_handler = onSignal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
    sigaction(SIGHUP, &action, nullptr);
}

bool stderrIsTerminal() { return ::isatty(STDERR_FILENO); }

std::string executablePath() {
    std::error_code error;
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
    if (error) throw std::runtime_error("cannot find this dqjulia's path (/proc/self/exe): " + error.message());
    return self.string();
}

std::FILE* openCommand(const std::string& command) { return ::popen((command + " 2>&1").c_str(), "r"); }

int closeCommand(std::FILE* pipe) {
    const int status = ::pclose(pipe);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace dqj::platform
