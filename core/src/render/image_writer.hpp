// image_writer.hpp - an image written into an AtomicFile the caller publishes, alone or with the
// other files of its run (AtomicFileSet). Internal to libdqjulia and the command; writeImage()
// (dqjulia/image.hpp) is this and commit().
// Code: image.cpp.
#pragma once

#include "files/atomic_file.hpp"
#include "dqjulia/image.hpp"

namespace dqj {

/// Writes `image` in `format` into `target`'s temporary file. Throws std::runtime_error
/// ("cannot write 'path': reason") for an image that cannot be written or a failed write.
void writeImage(const Image& image, AtomicFile& target, ImageFormat format);

}  // namespace dqj
