// text_input.hpp - reading text: lines of at most a given length from a file descriptor, and
// whether a small file holds a text, with a read error always reported as one (never taken for the
// end of the input) and a line or file over its limit refused before more than the limit is held
// in memory.
//
// Internal to libdqjulia (the command uses it too): `eval`'s points on standard input, the include
// file `povray` compares. Reads go through platform::readSome (read(); Windows: _read), one 64 kB
// buffer per reader; a line is copied once.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dqj {

class LineReader {
public:
    /// Reads the descriptor `fd` (not owned: standard input is 0), named `source` in messages
    /// ("standard input", "'/proc/self/status'").
    LineReader(int fd, std::string source, std::size_t maxLineBytes);

    enum class Result { Line, End, TooLong };
    /// The next line, without its "\n" or "\r\n" (the last may lack its "\n"): Line; End after
    /// the last; TooLong when it has more than maxLineBytes bytes (then `line` holds its first
    /// maxLineBytes and the rest is not read). Throws std::system_error ("cannot read SOURCE:
    /// reason") when a read fails, EINTR included (a signal: the caller sees interrupted()).
    Result next(std::string& line);

    /// The number of the line next() returned last (from 1).
    std::size_t lineNumber() const { return lineNumber_; }

private:
    bool refill();
    int fd_;
    std::string source_;
    std::size_t maxLineBytes_;
    std::vector<char> buffer_;
    std::size_t begin_ = 0, end_ = 0;
    std::size_t lineNumber_ = 0;
    bool ended_ = false;
};

/// Whether the file at `path` (UTF-8, platform.hpp) holds exactly `text` (nullopt: there is no such
/// file), read no further than one byte beyond it. Throws std::system_error when it cannot be
/// opened or read, and std::runtime_error when it is not a regular file (a FIFO would block).
std::optional<bool> fileHolds(const std::string& path, std::string_view text);

}  // namespace dqj
