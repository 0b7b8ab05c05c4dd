// What a message may show of a user's input (message_text.hpp).
#include "files/message_text.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace dqj {
namespace {

/// The length of the UTF-8 sequence that starts at `text[at]`, or 1 where none does (a stray
/// continuation byte, a sequence cut short or overlong: shown byte by byte).
std::size_t sequenceLength(std::string_view text, std::size_t at) {
    const auto lead = static_cast<unsigned char>(text[at]);
    const std::size_t length = lead >= 0xF0 && lead <= 0xF4  ? 4
                               : lead >= 0xE0                ? 3
                               : lead >= 0xC2 && lead < 0xE0 ? 2
                                                             : 1;
    if (length == 1 || lead > 0xF4 || at + length > text.size()) return 1;
    for (std::size_t next = at + 1; next < at + length; ++next)
        if ((static_cast<unsigned char>(text[next]) & 0xC0) != 0x80) return 1;
    return length;
}

/// 52428800 -> "52,428,800".
std::string groupedDigits(std::size_t value) {
    std::string digits = std::to_string(value);
    for (std::size_t at = digits.size(); at > 3; at -= 3) digits.insert(at - 3, 1, ',');
    return digits;
}

}  // namespace

std::string printableText(std::string_view text) {
    std::string result;
    result.reserve(text.size());
    for (std::size_t index = 0; index < text.size(); ++index) {
        const auto byte = static_cast<unsigned char>(text[index]);
        const auto next = index + 1 < text.size() ? static_cast<unsigned char>(text[index + 1]) : 0;
        char escaped[16];
        if ((byte < 0x20 && byte != '\n' && byte != '\t') || byte == 0x7f) {
            std::snprintf(escaped, sizeof escaped, "\\x%02x", byte);
            result += escaped;
        } else if (byte == 0xc2 && next >= 0x80 && next <= 0x9f) {  // a C1 control in UTF-8
            std::snprintf(escaped, sizeof escaped, "\\xc2\\x%02x", next);
            result += escaped;
            ++index;
        } else {
            result += text[index];
        }
    }
    return result;
}

std::string inputExcerpt(std::string_view input, bool whole) {
    std::size_t end = 0;
    for (std::size_t characters = 0; end < input.size() && characters < kExcerptCharacters; ++characters)
        end += sequenceLength(input, end);
    // A quoted value stays on its line: its newlines are escaped too.
    const std::string_view shown = input.substr(0, end);
    std::string excerpt;
    for (std::size_t start = 0;;) {
        const std::size_t newline = std::min(shown.find('\n', start), shown.size());
        excerpt += printableText(shown.substr(start, newline - start));
        if (newline == shown.size()) break;
        excerpt += "\\x0a";
        start = newline + 1;
    }
    if (!whole) return excerpt + "...";
    if (end == input.size()) return excerpt;
    return excerpt + "... (" + groupedDigits(input.size()) + " bytes)";
}

std::string exceptionMessage(const std::exception& error) {
    const auto* filesystem = dynamic_cast<const std::filesystem::filesystem_error*>(&error);
    if (!filesystem) return printableText(error.what());
    std::string message = "filesystem error: " + filesystem->code().message();
    for (const std::filesystem::path* path : {&filesystem->path1(), &filesystem->path2()})
        if (!path->empty()) message += " [" + inputExcerpt(path->string()) + "]";
    return message;
}

}  // namespace dqj
