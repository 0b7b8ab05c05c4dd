// contact_sheet.hpp - lays images out in a labelled grid (contact sheets for
// `dqjulia explore` and the paper's figures).
//
// Each tile is drawn at its own size in a grid cell, with its label (one or more lines,
// wrapped to the cell width) in a strip below it, rendered with FreeType from a system font
// (DejaVu Sans, Debian's fonts-dejavu-core). Cost: one pass over the output pixels plus the
// glyphs of the labels.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "dqjulia/image.hpp"

namespace dqj {

struct SheetTile {
    Image image;        ///< rgba is used; tiles may differ in size (columns take the widest, rows their tallest)
    std::string label;  ///< "\n" separates lines; long lines wrap
};

/// The most columns and label lines a sheet takes (dqjulia sheet and explore check them).
inline constexpr int kMaxSheetColumns = 20;
inline constexpr int kMaxLabelLines = 20;

struct SheetLayout {
    int columns = 3;
    int padding = 8;                           ///< pixels around and between cells
    int fontPixels = 13;                       ///< label text height
    int labelLines = 3;                        ///< lines reserved under each tile
    glm::dvec3 background{0.02, 0.02, 0.025};  ///< linear RGB
    glm::dvec3 text{0.85, 0.85, 0.85};
};

/// The sheet as one image. Throws std::runtime_error if no font can be loaded or `tiles` is empty.
Image composeSheet(const std::vector<SheetTile>& tiles, const SheetLayout& layout = {});

/// The font used for labels (the first that exists of a list of system fonts; the environment
/// variable DQJ_FONT overrides it). Empty if none is found.
std::string labelFontPath();

}  // namespace dqj
