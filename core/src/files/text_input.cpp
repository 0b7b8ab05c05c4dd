// Reading text with read errors told apart from the end of the input (text_input.hpp).
#include "files/text_input.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include "files/message_text.hpp"
#include "platform/platform.hpp"

namespace dqj {
namespace {

[[noreturn]] void throwReadError(const std::string& source, int error) {
    throw std::system_error(error ? error : EIO, std::generic_category(), printableText("cannot read " + source));
}

/// read(): the bytes read, 0 at the end of the input; throws on failure.
std::size_t readSome(int fd, char* data, std::size_t size, const std::string& source) {
    const std::int64_t got = platform::readSome(fd, data, size);
    if (got < 0) throwReadError(source, errno);
    return std::size_t(got);
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

std::optional<bool> fileHolds(const std::string& path, std::string_view text) {
    std::optional<std::string> held;
    try {
        held = platform::readUpTo(path, text.size() + 1);
    } catch (const platform::FileError& failure) {
        std::string source = "'";  // appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) of "'" + ...
        source += inputExcerpt(path);
        source += '\'';
        if (failure.error()) throwReadError(source, failure.error());
        throw std::runtime_error(printableText("cannot read " + source + ": " + failure.what()));
    }
    if (!held) return std::nullopt;
    return *held == text;
}

}  // namespace dqj
