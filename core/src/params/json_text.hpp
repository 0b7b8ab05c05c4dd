// json_text.hpp - the JSON helpers of the parameter file (internal): parsing with the format's
// limits, short previews of values for messages, and the compact pretty printing of toJson.
#pragma once

#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

namespace dqj::json {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

/// Parses JSON with the limits of the format: at most kMaxParamsDepth levels of arrays and
/// objects and no key twice in one object. Throws ParamError naming the dotted path, or
/// nlohmann's parse errors for malformed text (parseDocument turns those into ParamError).
Json parseLimited(const std::string& text, const std::string& source);
/// parseLimited with malformed JSON reported as ParamError ("source: line 3, column 5: ...").
Json parseDocument(const std::string& text, const std::string& source);
/// The type and first characters of a value: "string \"abc\"", "array [1,2,...".
std::string describe(const Json& value);
/// The shortest text that reads back as exactly `value`.
std::string formatNumber(double value);
/// Levenshtein distance, for "did you mean" suggestions.
std::size_t editDistance(const std::string& a, const std::string& b);
/// Puts innermost arrays of numbers on one line: "[\n  1.0,\n  2.0\n]" -> "[1.0, 2.0]".
std::string compactNumberArrays(const std::string& text);

}  // namespace dqj::json
