#include "job_files.hpp"

#include <cstdint>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <vector>

#include "dqjulia/params.hpp"

namespace dqj::cli {
namespace {

/// "a line break (U+000A)": a character as a message names it.
std::string characterName(std::uint32_t code) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "U+%04X", static_cast<unsigned>(code));
    switch (code) {
        case 0x00: return "a NUL byte";
        case 0x09: return std::string("a tab (") + hex + ")";
        case 0x0a: return std::string("a line break (") + hex + ")";
        case 0x0d: return std::string("a carriage return (") + hex + ")";
        default: return std::string("a control character (") + hex + ")";
    }
}

/// `text` as Unicode code points, or nothing if it is not UTF-8 (overlong forms, surrogates and
/// values above U+10FFFF are not).
std::optional<std::vector<std::uint32_t>> decodeUtf8(std::string_view text) {
    std::vector<std::uint32_t> codes;
    for (std::size_t at = 0; at < text.size();) {
        const auto lead = static_cast<unsigned char>(text[at]);
        const int length = lead < 0x80                   ? 1
                           : lead >= 0xc2 && lead < 0xe0 ? 2
                           : lead >= 0xe0 && lead < 0xf0 ? 3
                           : lead >= 0xf0 && lead < 0xf5 ? 4
                                                         : 0;
        if (length == 0 || at + length > text.size()) return std::nullopt;
        std::uint32_t code = length == 1 ? lead : lead & (0x7fu >> length);
        for (int index = 1; index < length; ++index) {
            const auto next = static_cast<unsigned char>(text[at + index]);
            if ((next & 0xc0) != 0x80) return std::nullopt;
            code = code << 6 | (next & 0x3f);
        }
        constexpr std::uint32_t kSmallest[] = {0, 0, 0x80, 0x800, 0x10000};
        if (code < kSmallest[length] || code > 0x10ffff || (code >= 0xd800 && code < 0xe000)) return std::nullopt;
        codes.push_back(code);
        at += length;
    }
    return codes;
}

std::vector<std::uint32_t> utf8OrRefuse(std::string_view text, std::string_view flag) {
    auto codes = decodeUtf8(text);
    if (!codes)
        throw ParamError("farm", std::string(flag) +
                                     ": not UTF-8 text, which an Open Job Description template (JSON) cannot hold");
    return std::move(*codes);
}

/// Refuses what no #SBATCH line can carry: a line break ends the line (and what follows it would
/// be a command), a NUL ends the text.
void refuseLineEnds(std::string_view value, std::string_view flag) {
    for (std::size_t at = 0; at < value.size(); ++at)
        if (value[at] == '\n' || value[at] == '\0')
            throw ParamError("farm", std::string(flag) + ": " + characterName(static_cast<unsigned char>(value[at])) +
                                         " at byte " + std::to_string(at + 1) +
                                         ", which an #SBATCH line of a Slurm script cannot carry (sbatch reads a "
                                         "directive to the end of its line); remove it");
}

/// Whether get_argument reads `text` as it is: printable ASCII without its quotes, escape,
/// comment sign and white space, and not empty.
bool sbatchPlain(std::string_view text) {
    if (text.empty()) return false;
    for (const char ch : text) {
        const auto byte = static_cast<unsigned char>(ch);
        if (byte <= 0x20 || byte >= 0x7f || ch == '"' || ch == '\'' || ch == '\\' || ch == '#') return false;
    }
    return true;
}

/// `text` as get_argument reads it back: as it is where plain, else in double quotes with the
/// backslash and the double quote escaped.
std::string sbatchWord(std::string_view text) {
    if (sbatchPlain(text)) return std::string(text);
    std::string quoted = "\"";
    for (const char ch : text) {
        if (ch == '"' || ch == '\\') quoted += '\\';
        quoted += ch;
    }
    return quoted + "\"";
}

}  // namespace

std::string shellWord(std::string_view text) {
    std::string quoted = "'";
    for (const char ch : text) quoted += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return quoted + "'";
}

SlurmScript::SlurmScript() : text_("#!/bin/bash\n") {}

void SlurmScript::comment(std::string_view text) {
    std::string line(text);
    for (char& ch : line)
        if (ch == '\n' || ch == '\r' || ch == '\0') ch = ' ';
    text_ += "# " + line + "\n";
}

void SlurmScript::directive(std::string_view option, std::string_view value, std::string_view flag) {
    refuseLineEnds(value, flag);
    if (commands_) throw std::logic_error("an #SBATCH line after the script's first command");
    // "--option=" is plain, so the argument's quotes (if any) open after it.
    text_ += "#SBATCH " + std::string(option) + "=" + sbatchWord(value) + "\n";
}

void SlurmScript::argument(std::string_view argument, std::string_view flag) {
    refuseLineEnds(argument, flag);
    if (argument.size() < 2 || argument[0] != '-')
        throw ParamError("farm", std::string(flag) + " \"" + std::string(argument) +
                                     "\": expected one option of sbatch's, starting with -, e.g. --sbatch=--qos=low");
    if (commands_) throw std::logic_error("an #SBATCH line after the script's first command");
    text_ += "#SBATCH " + sbatchWord(argument) + "\n";
}

void SlurmScript::command(std::string_view line) {
    commands_ = true;
    text_ += std::string(line) + "\n";
}

void SlurmScript::checkJobName(std::string_view name, std::string_view flag) {
    refuseLineEnds(name, flag);
    constexpr std::size_t kMaxBytes = 1024;  // slurmctld's limit on a job's name
    if (name.size() > kMaxBytes)
        throw ParamError("farm", std::string(flag) + ": the job's name is " + std::to_string(name.size()) +
                                     " bytes; Slurm keeps at most " + std::to_string(kMaxBytes) +
                                     " (give a shorter --name)");
}

std::string SlurmScript::logPattern(std::string_view literal, std::string_view patterns, std::string_view flag) {
    refuseLineEnds(literal, flag);
    std::string pattern;
    for (const char ch : literal) {
        if (ch == '\\')
            throw ParamError("farm", std::string(flag) + " '" + std::string(literal) +
                                         "': a backslash in the log's path would turn off Slurm's patterns that "
                                         "name each task's log (%A_%a), and Slurm drops it; choose a path without "
                                         "one");
        pattern += ch == '%' ? std::string("%%") : std::string(1, ch);
    }
    pattern += patterns;
    constexpr std::size_t kMaxBytes = 4096;  // slurmctld's limit on --output (MAXPATHLEN)
    if (pattern.size() > kMaxBytes)
        throw ParamError("farm", std::string(flag) + ": the log's path is " + std::to_string(pattern.size()) +
                                     " bytes in Slurm's --output; Slurm keeps at most " + std::to_string(kMaxBytes));
    return pattern;
}

std::string OpenJd::parameterValue(const std::string& value, std::string_view flag) {
    const std::size_t characters = utf8OrRefuse(value, flag).size();
    if (characters > std::size_t(kMaxParameterCharacters))
        throw ParamError("farm", std::string(flag) + ": " + std::to_string(characters) +
                                     " characters; an Open Job Description job parameter holds at most " +
                                     std::to_string(kMaxParameterCharacters));
    return value;
}

std::string OpenJd::jobName(const std::string& name, std::string_view flag) {
    const std::vector<std::uint32_t> codes = utf8OrRefuse(name, flag);
    for (std::size_t index = 0; index < codes.size(); ++index)
        if (codes[index] < 0x20 || (codes[index] >= 0x7f && codes[index] < 0xa0))
            throw ParamError("farm", std::string(flag) + ": " + characterName(codes[index]) + " at character " +
                                         std::to_string(index + 1) +
                                         ", which an Open Job Description job name cannot hold (no control "
                                         "characters); give another --name");
    if (codes.empty() || codes.size() > std::size_t(kMaxNameCharacters))
        throw ParamError("farm", std::string(flag) + ": the job's name has " + std::to_string(codes.size()) +
                                     " characters; an Open Job Description job name has 1 to " +
                                     std::to_string(kMaxNameCharacters));
    return name;
}

std::string OpenJd::shortenedName(const std::string& name) {
    const auto codes = decodeUtf8(name);
    if (!codes || codes->size() <= std::size_t(kMaxNameCharacters)) return name;
    std::size_t at = 0;
    for (int count = 0; count < kMaxNameCharacters; ++count) {
        const auto lead = static_cast<unsigned char>(name[at]);
        at += lead < 0x80 ? 1 : lead < 0xe0 ? 2 : lead < 0xf0 ? 3 : 4;
    }
    return name.substr(0, at);
}

}  // namespace dqj::cli
