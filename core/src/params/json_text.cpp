// json_text.cpp - see json_text.hpp.
#include "params/json_text.hpp"

#include <algorithm>
#include <charconv>
#include <set>
#include <vector>

#include "dqjulia/param_file.hpp"
#include "files/message_text.hpp"

namespace dqj::json {

namespace {

/// "line 3, column 5" for a byte offset into the text.
std::string lineAndColumn(const std::string& text, std::size_t offset) {
    std::size_t line = 1, column = 1;
    for (std::size_t index = 0; index < std::min(offset, text.size()); ++index) {
        if (text[index] == '\n') {
            ++line;
            column = 1;
        } else {
            ++column;
        }
    }
    return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

/// The first characters of `value` as JSON, written without recursion (a value may be nested
/// as deep as the parser allows) and without serialising more than is shown.
std::string preview(const Json& value, std::size_t limit) {
    struct Frame {
        const Json* node;
        Json::const_iterator next;
    };
    std::string text;
    std::vector<Frame> stack;
    auto open = [&](const Json& node) {
        if (!node.is_structured()) {
            text += node.dump();
            return;
        }
        text += node.is_object() ? '{' : '[';
        stack.push_back({&node, node.begin()});
    };
    open(value);
    while (!stack.empty() && text.size() <= limit) {
        Frame& frame = stack.back();
        if (frame.next == frame.node->end()) {
            text += frame.node->is_object() ? '}' : ']';
            stack.pop_back();
            continue;
        }
        if (frame.next != frame.node->begin()) text += ',';
        const auto item = frame.next++;
        if (frame.node->is_object()) text += Json(item.key()).dump() + ":";
        open(*item);  // may invalidate `frame`
    }
    if (text.size() > limit) text = text.substr(0, limit - 3) + "...";
    return text;
}

}  // namespace

std::size_t editDistance(const std::string& a, const std::string& b) {
    std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        current[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j)
            current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(previous, current);
    }
    return previous[b.size()];
}

std::string describe(const Json& value) {
    if (value.is_string()) return "string \"" + inputExcerpt(value.get_ref<const std::string&>()) + "\"";
    return std::string(value.type_name()) + " " + preview(value, 40);
}

/// Parses JSON with the limits of the format: at most kMaxParamsDepth levels of arrays and
/// objects (deeper documents are refused before they can exhaust a stack) and no key twice in
/// one object (nlohmann keeps the last silently). Errors name the dotted path of the key.
Json parseLimited(const std::string& text, const std::string& source) {
    struct Frame {
        bool object = false;
        std::size_t elements = 0;  // arrays: elements started so far
        std::string key;           // objects: the current key
        std::set<std::string> keys;
    };
    std::vector<Frame> frames;
    auto path = [&](const std::string& last) {
        std::string result;
        for (const Frame& frame : frames) {
            if (&frame == &frames.back() && frame.object) break;
            // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) of "[" + ...
            if (frame.object) {
                if (!result.empty()) result += '.';
                result += inputExcerpt(frame.key);
            } else if (frame.elements > 0) {
                result += '[';
                result += std::to_string(frame.elements - 1);
                result += ']';
            }
        }
        return result.empty() ? inputExcerpt(last) : last.empty() ? result : result + "." + inputExcerpt(last);
    };
    auto elementStarts = [&] {
        if (!frames.empty() && !frames.back().object) ++frames.back().elements;
    };
    using Event = Json::parse_event_t;
    return Json::parse(text, [&](int, Event event, Json& parsed) {
        switch (event) {
            case Event::object_start:
            case Event::array_start:
                elementStarts();
                if (frames.size() >= std::size_t(kMaxParamsDepth))
                    throw ParamError("", source + ": arrays and objects nested deeper than " +
                                             std::to_string(kMaxParamsDepth) +
                                             " levels; a parameter file needs at most 4");
                frames.emplace_back();
                frames.back().object = event == Event::object_start;
                break;
            case Event::key: {
                Frame& frame = frames.back();
                frame.key = parsed.get<std::string>();
                if (!frame.keys.insert(frame.key).second) {
                    const std::string key = path(frame.key);
                    throw ParamError(key,
                                     source + ": " + key + ": duplicate key \"" + inputExcerpt(frame.key) +
                                         "\" (a key may appear once in an object; the second would replace the first)");
                }
                break;
            }
            case Event::object_end:
            case Event::array_end: frames.pop_back(); break;
            case Event::value: elementStarts(); break;
        }
        return true;
    });
}

/// The shortest text that reads back as exactly `value`, so a message never shows a value
/// rounded onto its limit ("must be at most 1, got 1" for 1.0000001).
std::string formatNumber(double value) {
    char text[64];
    const auto result = std::to_chars(text, text + sizeof text, value);
    std::string number(text, result.ptr);
    // "1e+09" -> "1e9", "1e-07" -> "1e-7": as people (and the README) write limits.
    const std::size_t e = number.find('e');
    if (e != std::string::npos) {
        std::size_t digits = e + 1;
        if (number[digits] == '+') number.erase(digits, 1);
        if (number[digits] == '-') ++digits;
        while (digits + 1 < number.size() && number[digits] == '0') number.erase(digits, 1);
    }
    return number;
}

namespace {

/// The parser's reason with the document's text it quotes ("last read: '...'", "parsing '1e999'":
/// up to the rest of the document, for a string never closed) cut to an excerpt.
std::string boundedReason(std::string reason) {
    const std::size_t open = reason.find('\''), close = reason.rfind('\'');
    if (open == std::string::npos || close <= open) return reason;
    return reason.substr(0, open + 1) + inputExcerpt(std::string_view(reason).substr(open + 1, close - open - 1)) +
           reason.substr(close);
}

}  // namespace

Json parseDocument(const std::string& text, const std::string& source) {
    try {
        return parseLimited(text, source);
    } catch (const Json::parse_error& error) {
        std::string reason = error.what();
        const std::size_t colon = reason.find(": ");  // drop "[json.exception.parse_error.101] parse error at ...: "
        if (colon != std::string::npos) reason = reason.substr(colon + 2);
        throw ParamError("", source + ": " + lineAndColumn(text, error.byte == 0 ? 0 : error.byte - 1) +
                                 ": malformed JSON: " + boundedReason(reason));
    } catch (const Json::exception& error) {  // e.g. "number overflow parsing '1e999'"
        std::string reason = error.what();
        const std::size_t bracket = reason.find("] ");
        if (bracket != std::string::npos) reason = reason.substr(bracket + 2);
        throw ParamError("", source + ": malformed JSON: " + boundedReason(reason));
    }
}

/// Puts innermost arrays of numbers (vectors, colours) on one line: "[\n  1.0,\n  2.0\n]" -> "[1.0, 2.0]".
/// Strings are copied untouched.
std::string compactNumberArrays(const std::string& text) {
    std::string result;
    result.reserve(text.size());
    bool inString = false;
    for (std::size_t index = 0; index < text.size(); ++index) {
        const char ch = text[index];
        if (inString || ch != '[') {
            if (ch == '"' && (!inString || text[index - 1] != '\\')) inString = !inString;
            result += ch;
            continue;
        }
        const std::size_t close = text.find_first_of("[]{\"", index + 1);
        if (close == std::string::npos || text[close] != ']') {
            result += ch;
            continue;
        }
        result += '[';
        for (std::size_t inner = index + 1; inner < close; ++inner) {
            if (text[inner] == '\n' || text[inner] == ' ') continue;
            result += text[inner];
            if (text[inner] == ',') result += ' ';
        }
        result += ']';
        index = close;
    }
    return result;
}

}  // namespace dqj::json
