// message_text.hpp - what a message may show of a user's input: never a byte that cuts a C string
// short or drives a terminal, and never more than a short excerpt of a long value (a 50 MB line
// given to `eval`, a 16 MiB key in a parameter file, a 128 kB argument).
//
// Internal to libdqjulia (the command uses it too). Every message that quotes input goes through
// inputExcerpt(); every whole message through printableText() (ParamError's constructor, the
// writers' failureMessage). Cost: one pass over the excerpt, or over the message.
#pragma once

#include <cstddef>
#include <exception>
#include <string>
#include <string_view>

namespace dqj {

/// `text` with NUL and the other control characters except newline and tab written as \xNN (the
/// C1 controls U+0080 to U+009F, which some terminals obey as ESC sequences, as \xc2\xNN), so a
/// message printed through a C string is never cut short and cannot drive a terminal.
std::string printableText(std::string_view text);

/// The characters of input a message shows at most (UTF-8 characters; a byte that is not valid
/// UTF-8 counts as one): a path or a line of numbers whole, a 50 MB line as a few hundred bytes.
inline constexpr std::size_t kExcerptCharacters = 200;

/// `input` as a message quotes it, on one line (newlines too written as \x0a): printableText() of
/// it whole when it has at most kExcerptCharacters characters, else of its first
/// kExcerptCharacters followed by its length, "... (52,428,800 bytes)". At most
/// 4 * kExcerptCharacters + 40 bytes, whatever the input. `whole` false: `input` is only the
/// start of a longer text whose length is not known (a line refused at its limit), and the
/// excerpt ends in "..." alone.
std::string inputExcerpt(std::string_view input, bool whole = true);

/// An exception's message for the user: what() printable; for a std::filesystem::filesystem_error
/// (whose what() holds its paths whole), "filesystem error: REASON [PATH]" with the paths as
/// inputExcerpt() shows them.
std::string exceptionMessage(const std::exception& error);

}  // namespace dqj
