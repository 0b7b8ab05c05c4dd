// dqjulia/files.hpp - how the toolkit's writers treat the files they write.
// Code: core/src/files/atomic_file.cpp (checkWritable).
#pragma once

#include <string>

#include "dqjulia/export.h"

namespace dqj {

/// What a writer does with an existing file at its path: replace it atomically, or keep it
/// and fail (also when the file appears while the work runs; the CLI without --force).
enum class Existing { Replace, Keep };

/// Checks, before long work, that `path` can be written: a new or regular file (not a folder,
/// device, FIFO or socket), not existing when `existing` is Keep, in a folder where a file can
/// really be created (tried, so read-only and special file systems fail now). Throws
/// std::runtime_error ("cannot write 'path': reason").
DQJ_API void checkWritable(const std::string& path, Existing existing = Existing::Replace);

/// Writes `text` to `path` as every writer does (a temporary file, published when complete).
/// Throws std::runtime_error ("cannot write 'path': reason").
DQJ_API void writeTextFile(const std::string& path, const std::string& text, Existing existing = Existing::Replace);

}  // namespace dqj
