// The checked atomic writer (see atomic_file.hpp). Linux: O_TMPFILE, linkat through
// /proc/self/fd, renameat2(RENAME_NOREPLACE), flock; POSIX fallbacks where they are missing.
// Windows: the hidden ".name.tmp-XXXXXX", held open without delete sharing (so no other writer's
// clean-up can remove it) and written through a CRT descriptor, is published with MoveFileExW:
// MOVEFILE_REPLACE_EXISTING for Replace, and without it for Keep, where it fails if the name exists.
// AtomicFileSet: every member prepared (written, flushed, synced) before the first is published;
// a member that cannot be published withdraws those published before it (the files they replaced,
// kept under a hidden second name until the end, are put back).
#include "files/atomic_file.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <optional>
#include <random>
#include <stdexcept>
#include <streambuf>
#include <vector>

#ifdef _WIN32
#include <fcntl.h>
#include <io.h>
#include <process.h>
#include <windows.h>
#else
#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

#include "files/file_names.hpp"
#include "files/text_input.hpp"

namespace dqj {
namespace {

std::runtime_error failure(const std::string& path, const std::string& reason) {
    return std::runtime_error(AtomicFile::failureMessage(path, reason));
}
std::runtime_error systemError(const std::string& path, int error) { return failure(path, std::strerror(error)); }

#ifdef _WIN32
/// A Win32 error code's text, in UTF-8.
std::string windowsMessage(DWORD error) {
    wchar_t* text = nullptr;
    const DWORD length =
        ::FormatMessageW(FORMAT_MESSAGE_ALLOCATE_BUFFER | FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS,
                         nullptr, error, 0, reinterpret_cast<wchar_t*>(&text), 0, nullptr);
    std::string message = length ? utf8FromPath(std::filesystem::path(std::wstring(text, length)))
                                 : "Windows error " + std::to_string(error);
    if (text) ::LocalFree(text);
    while (!message.empty() && (message.back() == '\n' || message.back() == '\r' || message.back() == '.'))
        message.pop_back();
    return message;
}
std::runtime_error windowsError(const std::string& path, DWORD error) { return failure(path, windowsMessage(error)); }

/// The descriptor calls CheckedBuffer makes: the Windows CRT's, with 64-bit offsets.
std::int64_t writeSome(int fd, const char* data, std::size_t size) {
    return ::_write(fd, data, unsigned(std::min<std::size_t>(size, std::size_t(1) << 30)));
}
std::int64_t seekTo(int fd, std::int64_t offset, int whence) { return ::_lseeki64(fd, offset, whence); }
int processId() { return ::_getpid(); }
#else
/// The descriptor calls CheckedBuffer makes: POSIX's.
std::int64_t writeSome(int fd, const char* data, std::size_t size) { return ::write(fd, data, size); }
std::int64_t seekTo(int fd, std::int64_t offset, int whence) { return ::lseek(fd, off_t(offset), whence); }
int processId() { return int(::getpid()); }

/// The process umask, read without changing it: umask() can only be read by setting it,
/// which would race with other threads creating files. Linux reports it in /proc.
mode_t currentUmask() {
    const std::optional<std::string> umask = lineStartingWith("/proc/self/status", "Umask:");
    return umask ? static_cast<mode_t>(std::strtoul(umask->c_str(), nullptr, 8)) : 022;
}
#endif

/// A buffered, seekable stream buffer over a file descriptor that checks every write (short
/// writes are continued, EINTR retried) and keeps the first error's errno.
class CheckedBuffer : public std::streambuf {
public:
    explicit CheckedBuffer(int fd) : fd_(fd), buffer_(1 << 16) {
        setp(buffer_.data(), buffer_.data() + buffer_.size());
    }
    int error() const { return error_; }
    /// Writes out what is buffered; false (and error()) on failure.
    bool drain() {
        const char* data = pbase();
        std::size_t size = std::size_t(pptr() - pbase());
        setp(buffer_.data(), buffer_.data() + buffer_.size());
        return writeAll(data, size);
    }

protected:
    int_type overflow(int_type ch) override {
        if (!drain()) return traits_type::eof();
        if (!traits_type::eq_int_type(ch, traits_type::eof())) {
            *pptr() = traits_type::to_char_type(ch);
            pbump(1);
        }
        return traits_type::not_eof(ch);
    }
    std::streamsize xsputn(const char* data, std::streamsize count) override {
        if (count <= epptr() - pptr()) {
            std::memcpy(pptr(), data, std::size_t(count));
            pbump(int(count));
            return count;
        }
        if (!drain() || !writeAll(data, std::size_t(count))) return 0;
        return count;
    }
    int sync() override { return drain() ? 0 : -1; }
    pos_type seekoff(off_type offset, std::ios_base::seekdir direction, std::ios_base::openmode) override {
        if (!drain()) return pos_type(off_type(-1));
        const int whence = direction == std::ios_base::beg   ? SEEK_SET
                           : direction == std::ios_base::cur ? SEEK_CUR
                                                             : SEEK_END;
        const std::int64_t position = seekTo(fd_, offset, whence);
        if (position < 0) {
            if (!error_) error_ = errno;
            return pos_type(off_type(-1));
        }
        return pos_type(off_type(position));
    }
    pos_type seekpos(pos_type position, std::ios_base::openmode mode) override {
        return seekoff(off_type(position), std::ios_base::beg, mode);
    }

private:
    bool writeAll(const char* data, std::size_t size) {
        if (error_) return false;
        while (size > 0) {
            const std::int64_t written = writeSome(fd_, data, size);
            if (written < 0 && errno == EINTR) continue;
            if (written <= 0) {
                error_ = written < 0 ? errno : EIO;
                return false;
            }
            data += written;
            size -= std::size_t(written);
        }
        return true;
    }

    int fd_;
    std::vector<char> buffer_;
    int error_ = 0;
};

std::string folderOf(const std::string& path) {
    const std::filesystem::path folder = pathFromUtf8(path).parent_path();
    return folder.empty() ? "." : utf8FromPath(folder);
}

/// The hidden names' start for `path`: ".NAME.tmp-", where NAME is the file's name cut to 200 bytes
/// (at a character's start), so a hidden name fits every file system's limit (255) whenever the
/// name itself does.
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

/// What is at a path: nothing, a folder, a regular file (with its permission bits) or another kind.
struct Found {
    enum Kind { Missing, Folder, Regular, Other, DanglingLink } kind = Missing;
    int mode = 0;
    std::string linkTarget = {};  // of a DanglingLink
};

#ifdef _WIN32
/// Removes ".name.tmp-*" files in the folder that no live writer holds open: what a writer killed
/// between creating and publishing its file left behind (a live writer's file cannot be deleted:
/// it is open without delete sharing). Files changed in the last few seconds are left alone.
void removeStaleTemporaries(const std::string& folder, const std::string& prefix) {
    namespace fs = std::filesystem;
    std::error_code error;
    const auto now = fs::file_time_type::clock::now();
    for (const auto& entry : fs::directory_iterator(pathFromUtf8(folder), error)) {
        const std::string name = utf8FromPath(entry.path().filename());
        if (name.rfind(prefix, 0) != 0 || name.size() != prefix.size() + 6) continue;
        std::error_code entryError;
        if (!entry.is_regular_file(entryError)) continue;
        const auto changed = entry.last_write_time(entryError);
        if (!entryError && changed + std::chrono::seconds(5) < now) ::DeleteFileW(entry.path().c_str());
    }
}

/// What is at `path` now (through symbolic links); Windows has no modes (0).
Found lookUp(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code error;
    const fs::file_status status = fs::status(pathFromUtf8(path), error);
    if (status.type() == fs::file_type::not_found) {
        std::error_code linkError;
        if (fs::is_symlink(fs::symlink_status(pathFromUtf8(path), linkError)))
            return {Found::DanglingLink, 0, utf8FromPath(fs::read_symlink(pathFromUtf8(path), linkError))};
        return {Found::Missing, 0};
    }
    if (error) throw failure(path, error.message());
    if (status.type() == fs::file_type::directory) return {Found::Folder, 0};
    return {status.type() == fs::file_type::regular ? Found::Regular : Found::Other, 0};
}
#else

/// Removes ".name.tmp-*" files in the folder that no live writer holds locked: what a writer
/// killed between creating and publishing its hidden file left behind. Files changed in the last
/// few seconds are left alone: a writer locks its file just after creating it.
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
        if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && info.st_mtime + 5 < std::time(nullptr) &&
            ::flock(fd, LOCK_EX | LOCK_NB) == 0)
            ::unlink(stale.c_str());
        ::close(fd);
    }
    ::closedir(directory);
}

/// What is at `path` now (through symbolic links), with the permission bits of a file.
Found lookUp(const std::string& path) {
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0) {
        const int error = errno;
        if (error != ENOENT) throw systemError(path, error);
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
#endif

/// Checks what is at `path` now: nothing or a regular file, and not present at all when
/// `existing` is Keep. Returns the mode of an existing file, or -1.
int existingMode(const std::string& path, Existing existing) {
    const Found found = lookUp(path);
    if (found.kind == Found::Missing) return -1;
    if (found.kind == Found::DanglingLink)
        throw failure(path, "it is a symbolic link to '" + found.linkTarget +
                                "', which does not exist; dqjulia replaces a link with its file rather than write "
                                "through it: remove the link, or give the name the file should have");
    if (found.kind == Found::Folder) throw failure(path, "it is a folder; give a file name");
    if (found.kind != Found::Regular)
        throw failure(path, "it is not a regular file (a device, FIFO or socket); dqjulia writes only regular files");
    if (existing == Existing::Keep) throw failure(path, "the file exists and is kept (pass --force to overwrite it)");
    return found.mode;
}

}  // namespace

struct AtomicFile::State {
    Existing existing = Existing::Replace;
    std::string folder;
    int fd = -1;
    std::string tempPath;  // "" with O_TMPFILE: the data has no name until publish()
    bool prepared = false;
    bool committed = false;
    bool withdrawn = false;
    std::unique_ptr<CheckedBuffer> buffer;
    std::unique_ptr<std::ostream> stream;
    std::string asidePath;  // the hidden second name of the file this one replaces (setAside), or ""
#ifdef _WIN32
    HANDLE asideHandle = INVALID_HANDLE_VALUE;  // holds the file set aside: no other writer deletes it
#else
    int pathFd = -1;   // an O_PATH reference to the unnamed file between prepare() and publish()
    int lockFd = -1;   // keeps a named temporary locked between prepare() and publish()
    int asideFd = -1;  // keeps the file set aside locked
    dev_t device = 0;  // the written file's identity, so withdraw() removes only that file
    ino_t inode = 0;
#endif
};

namespace {

#ifdef _WIN32
void closeHandle(HANDLE& handle) {
    if (handle != INVALID_HANDLE_VALUE) ::CloseHandle(handle);
    handle = INVALID_HANDLE_VALUE;
}
/// Windows writes a folder's entries through with MOVEFILE_WRITE_THROUGH; nothing to do.
void syncFolder(const std::string&) {}
#else
void closeDescriptor(int& fd) {
    if (fd >= 0) ::close(fd);
    fd = -1;
}
/// Makes a folder's new names durable; best effort, since the data is already in place.
void syncFolder(const std::string& folder) {
    const int folderFd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (folderFd >= 0) {
        ::fsync(folderFd);
        ::close(folderFd);
    }
}
#endif

bool asciiEqualIgnoringCase(const std::string& text, const char* expected) {
    const std::size_t length = std::strlen(expected);
    if (text.size() != length) return false;
    for (std::size_t index = 0; index < length; ++index)
        if (std::toupper(static_cast<unsigned char>(text[index])) != expected[index]) return false;
    return true;
}

/// Whether `base` (a name before its first dot, trailing spaces removed) is one of Windows' device names.
bool isWindowsDeviceName(const std::string& base) {
    for (const char* name : {"CON", "PRN", "AUX", "NUL", "CONIN$", "CONOUT$"})
        if (asciiEqualIgnoringCase(base, name)) return true;
    if (base.size() < 4) return false;
    const std::string prefix = base.substr(0, 3), rest = base.substr(3);
    if (!asciiEqualIgnoringCase(prefix, "COM") && !asciiEqualIgnoringCase(prefix, "LPT")) return false;
    // COM1-COM9, LPT1-LPT9, and the superscripts 1, 2, 3 (U+00B9, U+00B2, U+00B3) Windows counts as digits.
    return (rest.size() == 1 && rest[0] >= '1' && rest[0] <= '9') || rest == "\xc2\xb9" || rest == "\xc2\xb2" ||
           rest == "\xc2\xb3";
}

/// What is wrong with one component of a path for Windows, or "".
std::string windowsComponentProblem(const std::string& name) {
    for (const char ch : name) {
        const auto byte = static_cast<unsigned char>(ch);
        if (byte < 0x20 || std::strchr("<>:\"|?*", ch)) {
            const std::string shown = byte < 0x20 ? printableText(std::string(1, ch)) : std::string(1, ch);
            return "the name '" + name + "' holds '" + shown + "', which Windows does not allow in file names" +
                   (ch == ':' ? " (a colon names a data stream of another file)" : "");
        }
    }
    if (name.back() == '.' || name.back() == ' ') {
        std::string kept = name;
        while (!kept.empty() && (kept.back() == '.' || kept.back() == ' ')) kept.pop_back();
        return "the name '" + name + "' ends in a dot or a space, which Windows removes (the file would be '" + kept +
               "'); give the name without them";
    }
    std::string base = name.substr(0, name.find('.'));
    while (!base.empty() && base.back() == ' ') base.pop_back();
    if (isWindowsDeviceName(base))
        return "'" + name +
               "' is a name Windows reserves for a device (CON, PRN, AUX, NUL, COM1-COM9, LPT1-LPT9; in any case, "
               "with any extension), not a file; give another name";
    return "";
}

}  // namespace

std::optional<FileIdentity> fileIdentity(const std::string& path) {
#ifdef _WIN32
    HANDLE handle = INVALID_HANDLE_VALUE;
    try {
        handle = ::CreateFileW(pathFromUtf8(path).c_str(), 0, FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE,
                               nullptr, OPEN_EXISTING, FILE_FLAG_BACKUP_SEMANTICS, nullptr);
    } catch (const std::filesystem::filesystem_error&) {
        return std::nullopt;  // not UTF-8: no file has that name
    }
    if (handle == INVALID_HANDLE_VALUE) return std::nullopt;
    BY_HANDLE_FILE_INFORMATION information{};
    const bool known = ::GetFileInformationByHandle(handle, &information);
    closeHandle(handle);
    if (!known) return std::nullopt;
    return FileIdentity{information.dwVolumeSerialNumber,
                        (std::uint64_t(information.nFileIndexHigh) << 32) | information.nFileIndexLow};
#else
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0) return std::nullopt;
    return FileIdentity{std::uint64_t(info.st_dev), std::uint64_t(info.st_ino)};
#endif
}

std::string windowsNameProblem(const std::string& path) {
    auto separator = [](char ch) { return ch == '/' || ch == '\\'; };
    // The components after the root: "\\?\" (and "\\?\UNC\server\share"), "\\server\share", a drive "C:".
    std::vector<std::string> components;
    std::string component;
    for (const char ch : path) {
        if (separator(ch)) {
            components.push_back(component);
            component.clear();
        } else {
            component += ch;
        }
    }
    components.push_back(component);
    std::size_t first = 0;
    if (components.size() >= 3 && components[0].empty() && components[1].empty()) {
        if (components[2] == ".") return "it is in Windows' device namespace (\\\\.\\), which names devices, not files";
        if (components[2] == "?") {
            first = 3;
            if (components.size() > first && asciiEqualIgnoringCase(components[first], "UNC")) first += 3;
        } else {
            first = 4;  // \\server\share
        }
    }
    if (components.size() > first && components[first].size() >= 2 && components[first][1] == ':' &&
        std::isalpha(static_cast<unsigned char>(components[first][0]))) {
        components[first].erase(0, 2);  // "C:" or a drive-relative "C:name"
    }
    for (std::size_t index = first; index < components.size(); ++index) {
        const std::string& name = components[index];
        if (name.empty() || name == "." || name == "..") continue;
        std::string problem = windowsComponentProblem(name);
        if (!problem.empty()) return problem;
    }
    return "";
}

std::string AtomicFile::failureMessage(const std::string& path, const std::string& reason) {
    return printableText("cannot write '" + inputExcerpt(path) + "': " + reason);
}

AtomicFile::AtomicFile(std::string path, Existing existing)
    : path_(std::move(path)), state_(std::make_unique<State>()) {
    State& state = *state_;
    state.existing = existing;
    if (path_.find('\0') != std::string::npos) throw failure(path_, "the name holds a NUL byte");
    std::string name;
    try {
        if (path_.empty() || !pathFromUtf8(path_).has_filename()) throw failure(path_, "not a file name");
        name = utf8FromPath(pathFromUtf8(path_).filename());
    } catch (const std::filesystem::filesystem_error&) {
        throw failure(path_, "the name is not valid UTF-8");
    }
#ifdef _WIN32
    if (const std::string problem = windowsNameProblem(path_); !problem.empty()) throw failure(path_, problem);
    if (pathFromUtf8(name).wstring().size() > 255)
        throw failure(path_, "the file name is longer than Windows allows (255 characters)");
#endif
    state.folder = folderOf(path_);
#ifndef _WIN32
    const long nameLimit = ::pathconf(state.folder.c_str(), _PC_NAME_MAX);
    if (nameLimit > 0 && name.size() > std::size_t(nameLimit))
        throw failure(path_, "the file name is " + std::to_string(name.size()) +
                                 " bytes long; this file system allows at most " + std::to_string(nameLimit));
#endif
    existingMode(path_, existing);
    removeStaleTemporaries(state.folder, hiddenPrefix(path_));
#ifdef _WIN32
    // A new hidden name (CREATE_NEW never opens an existing file), open for this writer alone.
    HANDLE handle = INVALID_HANDLE_VALUE;
    DWORD error = ERROR_FILE_EXISTS;
    for (int attempt = 0; attempt < 100 && handle == INVALID_HANDLE_VALUE && error == ERROR_FILE_EXISTS; ++attempt) {
        state.tempPath = utf8FromPath(pathFromUtf8(state.folder) / pathFromUtf8(hiddenPrefix(path_) + randomSuffix()));
        handle = ::CreateFileW(pathFromUtf8(state.tempPath).c_str(), GENERIC_READ | GENERIC_WRITE, FILE_SHARE_READ,
                               nullptr, CREATE_NEW, FILE_ATTRIBUTE_NORMAL, nullptr);
        if (handle == INVALID_HANDLE_VALUE) error = ::GetLastError();
    }
    if (handle == INVALID_HANDLE_VALUE) {
        state.tempPath.clear();
        throw windowsError(path_, error);
    }
    state.fd = ::_open_osfhandle(reinterpret_cast<intptr_t>(handle), _O_BINARY);
    if (state.fd < 0) {
        ::CloseHandle(handle);
        ::DeleteFileW(pathFromUtf8(state.tempPath).c_str());
        state.tempPath.clear();
        throw failure(path_, "cannot open the temporary file");
    }
#else
    // An unnamed file is linked by its /proc/self/fd name; without /proc, use the fallback.
    const bool unnamed = ::access("/proc/self/fd", X_OK) == 0;
    state.fd = unnamed ? ::open(state.folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0666) : -1;
    if (state.fd < 0 && (!unnamed || errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
        // No O_TMPFILE on this file system: a hidden, locked name (cleaned by the next run if we die).
        const std::string pattern = state.folder + "/" + hiddenPrefix(path_) + "XXXXXX";
        std::vector<char> buffer(pattern.begin(), pattern.end());
        buffer.push_back('\0');
        state.fd = ::mkostemp(buffer.data(), O_CLOEXEC);
        if (state.fd >= 0) state.tempPath = buffer.data();
    }
    if (state.fd < 0) throw systemError(path_, errno);
    ::flock(state.fd, LOCK_EX | LOCK_NB);
#endif
    state.buffer = std::make_unique<CheckedBuffer>(state.fd);
    state.stream = std::make_unique<std::ostream>(state.buffer.get());
}

AtomicFile::~AtomicFile() {
    State& state = *state_;
#ifdef _WIN32
    if (state.fd >= 0) ::_close(state.fd);
    if (!state.committed && !state.tempPath.empty()) ::DeleteFileW(pathFromUtf8(state.tempPath).c_str());
    closeHandle(state.asideHandle);
#else
    closeDescriptor(state.fd);
    closeDescriptor(state.pathFd);
    closeDescriptor(state.lockFd);
    closeDescriptor(state.asideFd);
    if (!state.committed && !state.tempPath.empty()) ::unlink(state.tempPath.c_str());
#endif
}

std::ostream& AtomicFile::stream() { return *state_->stream; }

void AtomicFile::commit() {
    if (state_->committed) return;
    prepare();
    publish();
    syncFolder(state_->folder);
}

void AtomicFile::checkWrites() {
    State& state = *state_;
    state.stream->flush();
    if (!state.buffer->drain() || state.buffer->error() || !*state.stream)
        throw systemError(path_, state.buffer->error() ? state.buffer->error() : EIO);
}

void AtomicFile::prepare() {
    State& state = *state_;
    if (state.prepared) return;
    checkWrites();
#ifdef _WIN32
    // Flush to the disk (checked); publish() closes the file (checked) and names it.
    if (state.existing == Existing::Replace) existingMode(path_, Existing::Replace);  // still no folder there
    if (::_commit(state.fd) != 0) throw systemError(path_, errno);
#else
    // Keep the mode of a file being replaced; a new file gets 0666 minus the umask, as open()
    // would give it (O_TMPFILE already applied the umask, mkstemp did not).
    // (With Keep, a file that appeared meanwhile is found by the no-replace publishing.)
    const int oldMode = state.existing == Existing::Keep ? -1 : existingMode(path_, Existing::Replace);
    const mode_t mode = oldMode >= 0 ? mode_t(oldMode) : (0666 & ~currentUmask());
    if (::fchmod(state.fd, mode) != 0 || ::fsync(state.fd) != 0) throw systemError(path_, errno);
    struct stat info {};
    if (::fstat(state.fd, &info) != 0) throw systemError(path_, errno);
    state.device = info.st_dev;
    state.inode = info.st_ino;

    // Close the data descriptor (checked: some file systems report write errors only here),
    // keeping an O_PATH reference so an unnamed file can still be linked, or a second descriptor
    // that keeps a named temporary locked.
    if (state.tempPath.empty()) {
        state.pathFd = ::open(("/proc/self/fd/" + std::to_string(state.fd)).c_str(), O_PATH | O_CLOEXEC);
        if (state.pathFd < 0) throw systemError(path_, errno);
    } else {
        state.lockFd = ::fcntl(state.fd, F_DUPFD_CLOEXEC, 0);
        if (state.lockFd < 0) throw systemError(path_, errno);
    }
    const int fd = state.fd;
    state.fd = -1;
    if (::close(fd) != 0) throw systemError(path_, errno);
#endif
    state.prepared = true;
}

void AtomicFile::publish() {
    State& state = *state_;
    if (state.committed) return;
#ifdef _WIN32
    const int fd = state.fd;
    state.fd = -1;
    if (::_close(fd) != 0) throw systemError(path_, errno);
    const DWORD flags = MOVEFILE_WRITE_THROUGH | (state.existing == Existing::Replace ? MOVEFILE_REPLACE_EXISTING : 0);
    if (!::MoveFileExW(pathFromUtf8(state.tempPath).c_str(), pathFromUtf8(path_).c_str(), flags)) {
        const DWORD error = ::GetLastError();
        if (error == ERROR_ALREADY_EXISTS || error == ERROR_FILE_EXISTS)
            throw failure(path_, "the file appeared while dqjulia worked and is kept (pass --force to overwrite it)");
        throw windowsError(path_, error);
    }
    state.committed = true;
#else
    int error = 0;
    if (state.pathFd >= 0) {
        const std::string source = "/proc/self/fd/" + std::to_string(state.pathFd);
        if (state.existing == Existing::Keep) {
            if (::linkat(AT_FDCWD, source.c_str(), AT_FDCWD, path_.c_str(), AT_SYMLINK_FOLLOW) != 0) error = errno;
        } else {
            // linkat cannot replace: link under a hidden name, then rename over the target.
            std::string hidden;
            for (int attempt = 0; attempt < 100; ++attempt) {
                hidden = state.folder + "/" + hiddenPrefix(path_) + randomSuffix();
                if (::linkat(AT_FDCWD, source.c_str(), AT_FDCWD, hidden.c_str(), AT_SYMLINK_FOLLOW) == 0) {
                    error = 0;
                    break;
                }
                error = errno;
                if (error != EEXIST) break;
            }
            if (!error && ::rename(hidden.c_str(), path_.c_str()) != 0) {
                error = errno;
                ::unlink(hidden.c_str());
            }
        }
    } else if (state.existing == Existing::Keep) {
        if (::renameat2(AT_FDCWD, state.tempPath.c_str(), AT_FDCWD, path_.c_str(), RENAME_NOREPLACE) != 0) {
            error = errno;
            if (error == EINVAL || error == ENOSYS) {  // no RENAME_NOREPLACE here: link fails on an existing name too
                error = ::link(state.tempPath.c_str(), path_.c_str()) == 0 ? 0 : errno;
                if (!error) ::unlink(state.tempPath.c_str());
            }
        }
    } else if (::rename(state.tempPath.c_str(), path_.c_str()) != 0) {
        error = errno;
    }
    if (error == EEXIST)
        throw failure(path_, "the file appeared while dqjulia worked and is kept (pass --force to overwrite it)");
    if (error) throw systemError(path_, error);
    state.committed = true;
    closeDescriptor(state.pathFd);
    closeDescriptor(state.lockFd);
#endif
}

void AtomicFile::setAside() {
    State& state = *state_;
#ifdef _WIN32
    const std::filesystem::path target = pathFromUtf8(path_);
    if (::GetFileAttributesW(target.c_str()) == INVALID_FILE_ATTRIBUTES) return;  // nothing there
    DWORD error = ERROR_FILE_EXISTS;
    for (int attempt = 0; attempt < 100 && error == ERROR_FILE_EXISTS; ++attempt) {
        const std::string aside =
            utf8FromPath(pathFromUtf8(state.folder) / pathFromUtf8(hiddenPrefix(path_) + randomSuffix()));
        if (::MoveFileExW(target.c_str(), pathFromUtf8(aside).c_str(), MOVEFILE_WRITE_THROUGH)) {
            state.asidePath = aside;
            // Open without delete sharing: no other writer's clean-up removes it meanwhile.
            state.asideHandle = ::CreateFileW(pathFromUtf8(aside).c_str(), GENERIC_READ, FILE_SHARE_READ, nullptr,
                                              OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
            return;
        }
        error = ::GetLastError();
        if (error == ERROR_ALREADY_EXISTS) error = ERROR_FILE_EXISTS;
    }
    throw windowsError(path_, error);
#else
    struct stat info {};
    if (::lstat(path_.c_str(), &info) != 0) {
        if (errno == ENOENT) return;  // nothing there
        throw systemError(path_, errno);
    }
    // Locked first (a regular file), so no writer's clean-up removes it under its hidden name.
    if (S_ISREG(info.st_mode)) {
        state.asideFd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
        if (state.asideFd >= 0) ::flock(state.asideFd, LOCK_EX | LOCK_NB);
    }
    int error = EEXIST;
    for (int attempt = 0; attempt < 100 && error == EEXIST; ++attempt) {
        const std::string aside = state.folder + "/" + hiddenPrefix(path_) + randomSuffix();
        error = ::linkat(AT_FDCWD, path_.c_str(), AT_FDCWD, aside.c_str(), 0) == 0 ? 0 : errno;
        if (error == EPERM || error == EOPNOTSUPP || error == EMLINK || error == ENOSYS)  // no hard links: move it
            error = ::rename(path_.c_str(), aside.c_str()) == 0 ? 0 : errno;
        if (!error) state.asidePath = aside;
    }
    if (error) {
        closeDescriptor(state.asideFd);
        throw systemError(path_, error);
    }
#endif
}

void AtomicFile::withdraw() noexcept {
    State& state = *state_;
    if (state.withdrawn) return;
#ifdef _WIN32
    const std::filesystem::path target = pathFromUtf8(path_);
    closeHandle(state.asideHandle);
    if (!state.asidePath.empty()) {
        if (::MoveFileExW(pathFromUtf8(state.asidePath).c_str(), target.c_str(),
                          MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH))
            state.asidePath.clear();
    } else if (state.committed) {
        ::DeleteFileW(target.c_str());
    }
#else
    if (!state.asidePath.empty()) {
        // Still both names of one file when this member was never published: rename() then does
        // nothing, and the hidden name goes.
        if (::rename(state.asidePath.c_str(), path_.c_str()) == 0) {
            ::unlink(state.asidePath.c_str());
            state.asidePath.clear();
        }
    } else if (state.committed) {
        struct stat info {};
        if (::lstat(path_.c_str(), &info) == 0 && info.st_dev == state.device && info.st_ino == state.inode)
            ::unlink(path_.c_str());
    }
    closeDescriptor(state.asideFd);
#endif
    state.withdrawn = true;
}

void AtomicFile::dropSetAside() noexcept {
    State& state = *state_;
#ifdef _WIN32
    closeHandle(state.asideHandle);
    if (!state.asidePath.empty()) ::DeleteFileW(pathFromUtf8(state.asidePath).c_str());
#else
    if (!state.asidePath.empty()) ::unlink(state.asidePath.c_str());
    closeDescriptor(state.asideFd);
#endif
    state.asidePath.clear();
}

AtomicFileSet::AtomicFileSet(Existing existing) : existing_(existing) {}

AtomicFileSet::~AtomicFileSet() = default;

AtomicFile& AtomicFileSet::add(const std::string& path) {
    for (const auto& file : files_)
        if (file->path() == path) throw failure(path, "the run writes this file twice");
    files_.push_back(std::make_unique<AtomicFile>(path, existing_));
    return *files_.back();
}

std::vector<std::string> AtomicFileSet::paths() const {
    std::vector<std::string> result;
    for (const auto& file : files_) result.push_back(file->path());
    return result;
}

void AtomicFileSet::commit() {
    std::size_t published = 0;
    try {
        for (const auto& file : files_) file->prepare();  // a full disk fails here, before any name changes
        for (; published < files_.size(); ++published) {
            AtomicFile& file = *files_[published];
            if (existing_ == Existing::Replace) file.setAside();
            file.publish();
        }
    } catch (...) {
        // Withdrawn newest first; the member that failed may have set its old file aside already.
        for (std::size_t index = std::min(published + 1, files_.size()); index-- > 0;) files_[index]->withdraw();
        if (files_.size() < 2) throw;
        try {
            throw;
        } catch (const std::runtime_error& error) {
            throw std::runtime_error(std::string(error.what()) + " (none of the " + std::to_string(files_.size()) +
                                     " files of this run was written)");
        }
    }
    std::vector<std::string> folders;
    for (const auto& file : files_) {
        file->dropSetAside();
        if (std::find(folders.begin(), folders.end(), file->state_->folder) == folders.end())
            folders.push_back(file->state_->folder);
    }
    for (const std::string& folder : folders) syncFolder(folder);
}

std::string AtomicFile::lowercaseExtension(const std::string& path) {
    std::string extension;
    try {
        extension = utf8FromPath(pathFromUtf8(path).extension());
    } catch (const std::filesystem::filesystem_error&) {
        throw failure(path, "the name is not valid UTF-8");
    }
    for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return extension;
}

void checkWritable(const std::string& path, Existing existing) {
    AtomicFile probe(path, existing);  // creates (and on destruction discards) a real temporary file there
}

void writeTextFile(const std::string& path, const std::string& text, Existing existing) {
    AtomicFile file(path, existing);
    file.stream() << text;
    file.commit();
}

}  // namespace dqj
