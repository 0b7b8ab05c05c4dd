// The checked atomic writer (see atomic_file.hpp): the checks and the order of the steps, the same
// on every system. The steps themselves (an unnamed or hidden file, publishing it, setting a
// replaced file aside) are platform::PendingFile's (platform/platform.hpp).
// AtomicFileSet: every member prepared (written, flushed, synced) before the first is published;
// a member that cannot be published withdraws those published before it (the files they replaced,
// kept under a hidden second name until the end, are put back).
#include "files/atomic_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <streambuf>
#include <vector>

#include "platform/platform.hpp"

namespace dqj {
namespace {

std::runtime_error failure(const std::string& path, const std::string& reason) {
    return std::runtime_error(AtomicFile::failureMessage(path, reason));
}
std::runtime_error systemError(const std::string& path, int error) { return failure(path, std::strerror(error)); }

/// step(), with a platform::FileError told as the failure to write `path`.
template <typename Step>
decltype(auto) reported(const std::string& path, Step&& step) {
    try {
        return step();
    } catch (const platform::FileError& error) {
        if (error.exists())
            throw failure(path, "the file appeared while dqjulia worked and is kept (pass --force to overwrite it)");
        throw failure(path, error.what());
    }
}

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
        if (count <= 0) return 0;  // an empty write, whose data may be null (an empty vector's)
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
        const std::int64_t position = platform::seekTo(fd_, offset, whence);
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
            const std::int64_t written = platform::writeSome(fd_, data, size);
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
    const std::filesystem::path folder = platform::pathFromUtf8(path).parent_path();
    return folder.empty() ? "." : platform::utf8FromPath(folder);
}

/// Checks what is at `path` now: nothing or a regular file, and not present at all when
/// `existing` is Keep. Returns the mode of an existing file (0 on Windows, which has none), or -1.
int existingMode(const std::string& path, Existing existing) {
    using platform::Found;
    const Found found = reported(path, [&] { return platform::lookUp(path); });
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
    std::unique_ptr<platform::PendingFile> file;  // the data until it has its name
    bool prepared = false;
    bool committed = false;
    bool withdrawn = false;
    std::unique_ptr<CheckedBuffer> buffer;
    std::unique_ptr<std::ostream> stream;
};

namespace {

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

std::string systemNameProblem(const std::string& path) {
    return platform::kWindows ? windowsNameProblem(path) : std::string();
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
        if (path_.empty() || !platform::pathFromUtf8(path_).has_filename()) throw failure(path_, "not a file name");
        name = platform::utf8FromPath(platform::pathFromUtf8(path_).filename());
    } catch (const std::filesystem::filesystem_error&) {
        throw failure(path_, "the name is not valid UTF-8");
    }
    if (const std::string problem = systemNameProblem(path_); !problem.empty()) throw failure(path_, problem);
    state.folder = folderOf(path_);
    if (const std::string problem = platform::nameLengthProblem(state.folder, name); !problem.empty())
        throw failure(path_, problem);
    existingMode(path_, existing);
    const std::string prefix = platform::hiddenPrefix(path_);
    platform::removeStaleTemporaries(state.folder, prefix);
    state.file = reported(path_, [&] { return std::make_unique<platform::PendingFile>(state.folder, prefix); });
    state.buffer = std::make_unique<CheckedBuffer>(state.file->descriptor());
    state.stream = std::make_unique<std::ostream>(state.buffer.get());
}

AtomicFile::~AtomicFile() = default;  // the pending file, unless published, goes with its state

std::ostream& AtomicFile::stream() { return *state_->stream; }

void AtomicFile::commit() {
    if (state_->committed) return;
    prepare();
    publish();
    platform::syncFolder(state_->folder);
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
    // Keep the mode of a file being replaced (and check it is still no folder there); a new file gets
    // the usual one. (With Keep, a file that appeared meanwhile is found by the no-replace publishing.)
    const int mode = state.existing == Existing::Keep ? -1 : existingMode(path_, Existing::Replace);
    reported(path_, [&] { state.file->prepare(mode); });
    state.prepared = true;
}

void AtomicFile::publish() {
    State& state = *state_;
    if (state.committed) return;
    reported(path_, [&] { state.file->publish(path_, state.existing == Existing::Replace); });
    state.committed = true;
}

void AtomicFile::setAside() {
    reported(path_, [&] { state_->file->setAside(path_); });
}

void AtomicFile::withdraw() noexcept {
    State& state = *state_;
    if (state.withdrawn) return;
    state.file->withdraw(path_);
    state.withdrawn = true;
}

void AtomicFile::dropSetAside() noexcept { state_->file->dropSetAside(); }

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
    for (const std::string& folder : folders) platform::syncFolder(folder);
}

std::string AtomicFile::lowercaseExtension(const std::string& path) {
    std::string extension;
    try {
        extension = platform::utf8FromPath(platform::pathFromUtf8(path).extension());
    } catch (const std::filesystem::filesystem_error&) {
        throw failure(path, "the name is not valid UTF-8");
    }
    for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return extension;
}

struct ScratchFile::State {
    int fd = -1;
    std::unique_ptr<CheckedBuffer> buffer;
    std::unique_ptr<std::ostream> stream;
};

ScratchFile::ScratchFile(const std::string& path) : path_(path), state_(std::make_unique<State>()) {
    State& state = *state_;
    const std::string folder = folderOf(path_), prefix = platform::hiddenPrefix(path_);
    state.fd = reported(path_, [&] { return platform::openScratchFile(folder, prefix); });
    state.buffer = std::make_unique<CheckedBuffer>(state.fd);
    state.stream = std::make_unique<std::ostream>(state.buffer.get());
}

ScratchFile::~ScratchFile() { platform::closeFile(state_->fd); }

std::ostream& ScratchFile::stream() { return *state_->stream; }

void ScratchFile::checkWrites() {
    if (state_->buffer->error()) throw systemError(path_, state_->buffer->error());
}

void ScratchFile::appendTo(AtomicFile& target) {
    std::ostream& out = target.stream();
    readBack([&out](const char* data, std::size_t size) { out.write(data, std::streamsize(size)); });
    target.checkWrites();
}

void ScratchFile::readBack(const std::function<void(const char* data, std::size_t size)>& consume) {
    State& state = *state_;
    if (!state.buffer->drain()) checkWrites();  // throws: the write's reason
    if (platform::seekTo(state.fd, 0, SEEK_SET) < 0) throw systemError(path_, errno);
    std::vector<char> block(std::size_t(1) << 20);
    for (;;) {
        const std::int64_t got = platform::readSome(state.fd, block.data(), block.size());
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) throw systemError(path_, errno);
        if (got == 0) break;
        consume(block.data(), std::size_t(got));
    }
    if (platform::seekTo(state.fd, 0, SEEK_END) < 0) throw systemError(path_, errno);  // later writes append
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
