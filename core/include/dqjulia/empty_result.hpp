// dqjulia/empty_result.hpp - the one wording of an empty result: a render that hit nothing, a
// bake or mesh without a surface, a POV-Ray scene without the fractal. The command and the C ABI
// print this sentence; the reason comes from inspect.hpp (RenderResult carries the render's).
// Cost: string building only.
#pragma once

#include <string>
#include <string_view>

#include "dqjulia/export.h"

namespace dqj {

/// What came out empty.
enum class EmptyResult {
    Render,  ///< an image without a pixel on the surface
    Bake,    ///< a volume (VDB) without active voxels
    Mesh,    ///< a mesh without vertices
    Povray   ///< a POV-Ray scene that draws no fractal (its slice proven empty)
};

/// "the image shows no surface: <reason>": the result (`name`, e.g. its file, or the kind's own
/// words: the image, the volume, the mesh, the scene), that it is empty, and why: `reason`
/// (provenEmptyReason, InspectReport::emptyReason, RenderResult::emptyReason), or, when no
/// reason is known (""), what to try for this kind of result.
DQJ_API std::string emptyResultMessage(EmptyResult kind, std::string_view reason, std::string_view name = {});

}  // namespace dqj
