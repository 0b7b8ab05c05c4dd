// The names of the parameter set's choices (from the schema) and small queries on its values.
#include "dqjulia/param_types.hpp"

#include <algorithm>
#include <cctype>

#include "dqjulia/schema.hpp"

namespace dqj {

std::string_view coloringName(Coloring coloring) { return schema::choiceName("material.coloring", int(coloring)); }
std::string_view normalMethodName(NormalMethod method) { return schema::choiceName("render.normals", int(method)); }
std::string_view imageFormatName(ImageFormat format) { return schema::choiceName("output.format", int(format)); }

ImageFormat formatFor(const OutputSettings& output) {
    if (output.format) return *output.format;
    std::string extension;
    const std::size_t dot = output.path.rfind('.');
    if (dot != std::string::npos) extension = output.path.substr(dot + 1);
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char ch) { return std::tolower(ch); });
    return extension == "exr" ? ImageFormat::Exr : ImageFormat::Png8;
}

std::string_view bakeGridName(BakeGrid grid) { return schema::choiceName("bake.grids", int(grid)); }

bool hasGrid(const BakeSettings& bake, BakeGrid grid) {
    return std::find(bake.grids.begin(), bake.grids.end(), grid) != bake.grids.end();
}

}  // namespace dqj
