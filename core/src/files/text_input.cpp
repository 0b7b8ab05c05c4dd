// Reading text with read errors told apart from the end of the input (text_input.hpp).
#include "files/text_input.hpp"

#ifdef _WIN32
#include <io.h>
#else
#include <unistd.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "files/file_names.hpp"
#include "files/message_text.hpp"

namespace dqj {
namespace {

[[noreturn]] void throwReadError(const std::string& source, int error) {
    throw std::system_error(error ? error : EIO, std::generic_category(), printableText("cannot read " + source));
}

/// read(): the bytes read, 0 at the end of the input; throws on failure.
std::size_t readSome(int fd, char* data, std::size_t size, const std::string& source) {
#ifdef _WIN32
    const int got = ::_read(fd, data, unsigned(std::min<std::size_t>(size, std::size_t(1) << 30)));
#else
    const ssize_t got = ::read(fd, data, size);
#endif
    if (got < 0) throwReadError(source, errno);
    return std::size_t(got);
}

/// A descriptor closed when it goes.
struct Descriptor {
    int fd;
    ~Descriptor() {
        if (fd >= 0) {
#ifdef _WIN32
            ::_close(fd);
#else
            ::close(fd);
#endif
        }
    }
};

/// Up to `limit` bytes of the file at `path`; nullopt when there is none (ENOENT).
std::optional<std::string> readUpTo(const std::string& path, std::size_t limit) {
    std::string source = "'";  // appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) of "'" + ...
    source += inputExcerpt(path);
    source += '\'';
    std::error_code error;
    const auto status = std::filesystem::status(pathFromUtf8(path), error);
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
        throw std::runtime_error(
            printableText("cannot read " + source + ": not a regular file"));  // a FIFO would block
    const Descriptor file{openForReading(path)};
    if (file.fd < 0 && errno == ENOENT) return std::nullopt;
    if (file.fd < 0) throwReadError(source, errno);
    std::string text;
    std::vector<char> chunk(std::size_t(1) << 16);
    while (text.size() < limit) {
        const std::size_t got = readSome(file.fd, chunk.data(), std::min(chunk.size(), limit - text.size()), source);
        if (got == 0) break;
        text.append(chunk.data(), got);
    }
    return text;
}

}  // namespace

LineReader::LineReader(int fd, std::string source, std::size_t maxLineBytes)
    : fd_(fd), source_(std::move(source)), maxLineBytes_(maxLineBytes), buffer_(std::size_t(1) << 16) {}

bool LineReader::refill() {
    if (ended_) return false;
    begin_ = 0;
    end_ = readSome(fd_, buffer_.data(), buffer_.size(), source_);
    ended_ = end_ == 0;
    return !ended_;
}

LineReader::Result LineReader::next(std::string& line) {
    line.clear();
    bool any = false;
    for (;;) {
        if (begin_ == end_ && !refill()) {
            if (!any) return Result::End;
            break;  // a last line without "\n"
        }
        any = true;
        const char* start = buffer_.data() + begin_;
        const auto* newline = static_cast<const char*>(std::memchr(start, '\n', end_ - begin_));
        const std::size_t take = newline ? std::size_t(newline - start) : end_ - begin_;
        if (line.size() + take > maxLineBytes_) {
            line.append(start, maxLineBytes_ - line.size());
            ++lineNumber_;
            return Result::TooLong;
        }
        line.append(start, take);
        begin_ += take;
        if (newline) {
            ++begin_;
            break;
        }
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    ++lineNumber_;
    return Result::Line;
}

std::optional<std::string> readSmallFile(const std::string& path, std::size_t maxBytes) {
    std::optional<std::string> text = readUpTo(path, maxBytes + 1);
    if (text && text->size() > maxBytes)
        throw std::runtime_error(printableText("cannot read '" + inputExcerpt(path) + "': it has more than " +
                                               std::to_string(maxBytes) + " bytes"));
    return text;
}

std::optional<bool> fileHolds(const std::string& path, std::string_view text) {
    const std::optional<std::string> held = readUpTo(path, text.size() + 1);
    if (!held) return std::nullopt;
    return *held == text;
}

std::optional<std::string> lineStartingWith(const std::string& path, const std::string& prefix) {
    const std::optional<std::string> text = readSmallFile(path, std::size_t(1) << 20);
    if (!text) return std::nullopt;
    for (std::size_t start = 0; start < text->size();) {
        const std::size_t end = std::min(text->find('\n', start), text->size());
        if (text->compare(start, prefix.size(), prefix) == 0)
            return text->substr(start + prefix.size(), end - start - prefix.size());
        start = end + 1;
    }
    return std::nullopt;
}

}  // namespace dqj
