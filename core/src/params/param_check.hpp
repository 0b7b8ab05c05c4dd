// param_check.hpp - a JSON value checked against its schema field (internal): the one place a
// parameter's type and range are enforced, by the file's reader and by validate() alike; and the
// rules between the values keyframes animate.
#pragma once

#include <string>

#include "dqjulia/schema.hpp"
#include "params/json_text.hpp"

namespace dqj {
struct Params;
}

namespace dqj::detail {

/// Checks `value` at `key` ("lights[1].color") against `field`: its JSON type and, for numbers,
/// vectors, colours and lists, its range or item count. Objects, axes, rotation planes and the
/// animation are shaped by their readers and pass unchecked. Throws ParamError(key, prefix +
/// key + ": " + what is wrong and what is allowed).
void checkValue(const schema::Field& field, const json::Json& value, const std::string& key, const std::string& prefix);

/// Checks that `value` is a finite number within the field's range (a whole number for an
/// Integer field); for a vector field, one of its components.
void checkNumber(const schema::Field& field, const json::Json& value, const std::string& key,
                 const std::string& prefix);

/// Checks that `value` is an array of `size` numbers, each within the field's range.
void checkVector(const schema::Field& field, const json::Json& value, const std::string& key, const std::string& prefix,
                 std::size_t size);

/// Checks that `value` is the name of one of the field's choices.
void checkChoice(const schema::Field& field, const json::Json& value, const std::string& key,
                 const std::string& prefix);

/// checkValue for every key of a whole document, as toJson writes it.
void checkDocument(const json::Json& document);

/// The rules of validate() that relate values keyframes animate, what checkFrames runs frame by
/// frame (no JSON). Each throws ParamError as validate() does.
/// The bailout at least r_K of the constant (and variant): about 0.2 microseconds.
void checkBailoutRule(const Params& params);
/// The slice 3-D after its rotations: about 0.06 microseconds a rotation.
void checkSliceRule(const Params& params);

}  // namespace dqj::detail
