// The checked atomic writer (see atomic_file.hpp). Linux: O_TMPFILE, linkat through
// /proc/self/fd, renameat2(RENAME_NOREPLACE), flock; POSIX fallbacks where they are missing.
// Windows: the hidden ".name.tmp-XXXXXX", held open without delete sharing (so no other writer's
// clean-up can remove it) and written through a CRT descriptor, is published with MoveFileExW:
// MOVEFILE_REPLACE_EXISTING for Replace, and without it for Keep, where it fails if the name exists.
#include "atomic_file.hpp"

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

#include "file_names.hpp"
#include "text_input.hpp"

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

std::string hiddenPrefix(const std::string& path) {
    std::string prefix = ".";  // appended, not operator+: GCC 12 warns falsely (-Wrestrict) on the latter
    prefix += utf8FromPath(pathFromUtf8(path).filename());
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
    enum Kind { Missing, Folder, Regular, Other } kind;
    int mode;
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
    if (status.type() == fs::file_type::not_found) return {Found::Missing, 0};
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
        if (errno == ENOENT) return {Found::Missing, 0};
        throw systemError(path, errno);
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
    std::string tempPath;  // "" with O_TMPFILE: the data has no name until commit()
    bool committed = false;
    std::unique_ptr<CheckedBuffer> buffer;
    std::unique_ptr<std::ostream> stream;
};

std::string AtomicFile::failureMessage(const std::string& path, const std::string& reason) {
    return printableText("cannot write '" + inputExcerpt(path) + "': " + reason);
}

AtomicFile::AtomicFile(std::string path, Existing existing)
    : path_(std::move(path)), state_(std::make_unique<State>()) {
    State& state = *state_;
    state.existing = existing;
    if (path_.find('\0') != std::string::npos) throw failure(path_, "the name holds a NUL byte");
    try {
        if (path_.empty() || !pathFromUtf8(path_).has_filename()) throw failure(path_, "not a file name");
    } catch (const std::filesystem::filesystem_error&) {
        throw failure(path_, "the name is not valid UTF-8");
    }
    existingMode(path_, existing);
    state.folder = folderOf(path_);
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
        std::vector<char> name(pattern.begin(), pattern.end());
        name.push_back('\0');
        state.fd = ::mkostemp(name.data(), O_CLOEXEC);
        if (state.fd >= 0) state.tempPath = name.data();
    }
    if (state.fd < 0) throw systemError(path_, errno);
    ::flock(state.fd, LOCK_EX | LOCK_NB);
#endif
    state.buffer = std::make_unique<CheckedBuffer>(state.fd);
    state.stream = std::make_unique<std::ostream>(state.buffer.get());
}

AtomicFile::~AtomicFile() {
#ifdef _WIN32
    if (state_->fd >= 0) ::_close(state_->fd);
    if (!state_->committed && !state_->tempPath.empty()) ::DeleteFileW(pathFromUtf8(state_->tempPath).c_str());
#else
    if (state_->fd >= 0) ::close(state_->fd);
    if (!state_->committed && !state_->tempPath.empty()) ::unlink(state_->tempPath.c_str());
#endif
}

std::ostream& AtomicFile::stream() { return *state_->stream; }

void AtomicFile::commit() {
    State& state = *state_;
    if (state.committed) return;
    state.stream->flush();
    if (!state.buffer->drain() || state.buffer->error() || !*state.stream)
        throw systemError(path_, state.buffer->error() ? state.buffer->error() : EIO);
#ifdef _WIN32
    // Flush to the disk and close (both checked), then give the file its name.
    if (state.existing == Existing::Replace) existingMode(path_, Existing::Replace);  // still no folder there
    if (::_commit(state.fd) != 0) throw systemError(path_, errno);
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
    // Keep the mode of a file being replaced; a new file gets 0666 minus the umask, as open()
    // would give it (O_TMPFILE already applied the umask, mkstemp did not).
    // (With Keep, a file that appeared meanwhile is found by the no-replace publishing below.)
    const int oldMode = state.existing == Existing::Keep ? -1 : existingMode(path_, Existing::Replace);
    const mode_t mode = oldMode >= 0 ? mode_t(oldMode) : (0666 & ~currentUmask());
    if (::fchmod(state.fd, mode) != 0 || ::fsync(state.fd) != 0) throw systemError(path_, errno);

    // Close the data descriptor (checked: some file systems report write errors only here),
    // keeping an O_PATH reference so an unnamed file can still be linked.
    int pathFd = -1;
    if (state.tempPath.empty()) {
        pathFd = ::open(("/proc/self/fd/" + std::to_string(state.fd)).c_str(), O_PATH | O_CLOEXEC);
        if (pathFd < 0) throw systemError(path_, errno);
    }
    const int fd = state.fd;
    state.fd = -1;
    if (::close(fd) != 0) {
        const int error = errno;
        if (pathFd >= 0) ::close(pathFd);
        throw systemError(path_, error);
    }

    int error = 0;
    if (pathFd >= 0) {
        const std::string source = "/proc/self/fd/" + std::to_string(pathFd);
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
        ::close(pathFd);
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
    // Make the new name durable; best effort, since the data is already in place.
    const int folderFd = ::open(state.folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (folderFd >= 0) {
        ::fsync(folderFd);
        ::close(folderFd);
    }
#endif
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
