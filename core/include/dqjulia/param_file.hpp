// dqjulia/param_file.hpp - the parameter file: JSON in, validated Params out, and back.
// Code: core/src/params/param_read.cpp (ParamError, parseParams, loadParams), param_validate.cpp
// (validate) and param_write.cpp (toJson, saveParams).
//
// One format for the CLI, the Blender add-on and the POV-Ray writer, described key by key by
// the schema (schema.hpp, docs/parameter-file.md). Loading validates every value and throws
// ParamError naming the key, what was wrong and what is allowed.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

#include "dqjulia/export.h"
#include "dqjulia/files.hpp"
#include "dqjulia/param_types.hpp"

namespace dqj {

/// A bad parameter: `key` is the dotted path ("fractal.iterations"), `what()` the full message.
class DQJ_API ParamError : public std::runtime_error {
public:
    ParamError(std::string key, const std::string& message);
    const std::string& key() const { return key_; }

private:
    std::string key_;
};

enum class Validation { Full, TypesOnly };

/// The largest parameter document read (16 MiB) and the deepest nesting of arrays and objects
/// in it (64 levels; the format needs 4).
inline constexpr std::size_t kMaxParamsBytes = 16u << 20;
inline constexpr int kMaxParamsDepth = 64;

/// Parses a parameter document: types, ranges and key names always; the cross-field rules of
/// validate() too unless `validation` is TypesOnly (for callers that override values first,
/// such as the CLI's flags, and validate afterwards). `source` names the document in messages.
/// Missing keys keep their defaults. Throws ParamError.
DQJ_API Params parseParams(const std::string& jsonText, const std::string& source = "parameters",
                           Validation validation = Validation::Full);
/// Reads and parses a file. Throws ParamError (also for a missing or unreadable file).
DQJ_API Params loadParams(const std::string& path, Validation validation = Validation::Full);
/// The complete document for `params` (every key written), which parseParams reads back.
DQJ_API std::string toJson(const Params& params);
/// Writes toJson(params) to `path` through a temporary file in the same folder, so a failure
/// never leaves a partial file. Throws std::runtime_error naming the path.
DQJ_API void saveParams(const Params& params, const std::string& path, Existing existing = Existing::Replace);
/// Checks the cross-field rules (bailout >= r_K, non-degenerate slice, camera, ...). Throws ParamError.
DQJ_API void validate(const Params& params);

}  // namespace dqj
