// Contact sheets (contact_sheet.hpp): grid layout and FreeType labels.
#include "contact_sheet.hpp"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "platform/platform.hpp"

namespace dqj {
namespace {

/// Owns a FreeType library and face for the duration of one sheet.
class Font {
public:
    Font(const std::string& path, int pixels) {
        if (FT_Init_FreeType(&library_) != 0) throw std::runtime_error("cannot start FreeType");
        if (FT_New_Face(library_, path.c_str(), 0, &face_) != 0) {
            FT_Done_FreeType(library_);
            throw std::runtime_error("cannot load the label font '" + path + "'");
        }
        FT_Set_Pixel_Sizes(face_, 0, static_cast<FT_UInt>(pixels));
    }
    ~Font() {
        FT_Done_Face(face_);
        FT_Done_FreeType(library_);
    }
    Font(const Font&) = delete;
    Font& operator=(const Font&) = delete;

    /// Width in pixels of `text` on one line.
    int width(const std::string& text) {
        int pen = 0;
        for (unsigned char ch : text)
            if (FT_Load_Char(face_, ch, FT_LOAD_DEFAULT) == 0) pen += static_cast<int>(face_->glyph->advance.x >> 6);
        return pen;
    }

    /// Draws `text` with its baseline at (x, baseline), blending `colour` by glyph coverage.
    void draw(Image& image, const std::string& text, int x, int baseline, const glm::dvec3& colour) {
        int pen = x;
        for (unsigned char ch : text) {
            if (FT_Load_Char(face_, ch, FT_LOAD_RENDER) != 0) continue;
            const FT_GlyphSlot glyph = face_->glyph;
            const FT_Bitmap& bitmap = glyph->bitmap;
            for (unsigned row = 0; row < bitmap.rows; ++row) {
                const int y = baseline - glyph->bitmap_top + static_cast<int>(row);
                if (y < 0 || y >= image.height) continue;
                for (unsigned column = 0; column < bitmap.width; ++column) {
                    const int px = pen + glyph->bitmap_left + static_cast<int>(column);
                    if (px < 0 || px >= image.width) continue;
                    const float coverage = bitmap.buffer[row * bitmap.pitch + column] / 255.0f;
                    float* pixel = &image.rgba[4 * (static_cast<std::size_t>(y) * image.width + px)];
                    for (int channel = 0; channel < 3; ++channel)
                        pixel[channel] =
                            pixel[channel] * (1.0f - coverage) + static_cast<float>(colour[channel]) * coverage;
                }
            }
            pen += static_cast<int>(glyph->advance.x >> 6);
        }
    }

private:
    FT_Library library_ = nullptr;
    FT_Face face_ = nullptr;
};

/// Splits at "\n" and wraps at spaces (or anywhere, for long words) to `maxWidth` pixels.
std::vector<std::string> wrap(Font& font, const std::string& label, int maxWidth) {
    std::vector<std::string> lines;
    // badbit: memory running out ends these loops with bad_alloc, not as the text's end.
    std::istringstream paragraphs(label);
    paragraphs.exceptions(std::ios::badbit);
    std::string paragraph;
    while (std::getline(paragraphs, paragraph)) {
        std::string line;
        std::istringstream words(paragraph);
        words.exceptions(std::ios::badbit);
        std::string word;
        while (words >> word) {
            const std::string candidate = line.empty() ? word : line + " " + word;
            if (font.width(candidate) <= maxWidth || line.empty()) {
                line = candidate;
            } else {
                lines.push_back(line);
                line = word;
            }
            while (font.width(line) > maxWidth && line.size() > 1) {  // a word wider than the cell
                std::size_t fit = line.size() - 1;
                while (fit > 1 && font.width(line.substr(0, fit)) > maxWidth) --fit;
                lines.push_back(line.substr(0, fit));
                line = line.substr(fit);
            }
        }
        lines.push_back(line);
    }
    return lines;
}

}  // namespace

std::string labelFontPath() {
    if (const char* chosen = std::getenv("DQJ_FONT"); chosen && std::filesystem::exists(chosen)) return chosen;
    if (platform::kWindows) {
        const char* windows = std::getenv("WINDIR");
        const std::string fonts = std::string(windows ? windows : "C:\\Windows") + "\\Fonts\\";
        for (const std::string& candidate : {fonts + "segoeui.ttf", fonts + "arial.ttf", fonts + "tahoma.ttf"})
            if (std::filesystem::exists(candidate)) return candidate;
    }
    for (const char* candidate :
         {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "/usr/share/fonts/TTF/DejaVuSans.ttf",
          "/usr/share/fonts/dejavu/DejaVuSans.ttf", "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf"})
        if (std::filesystem::exists(candidate)) return candidate;
    return "";
}

Image composeSheet(const std::vector<SheetTile>& tiles, const SheetLayout& layout) {
    if (tiles.empty()) throw std::runtime_error("a contact sheet needs at least one tile");
    const std::string fontPath = labelFontPath();
    if (fontPath.empty())
        throw std::runtime_error("no font for the labels: install fonts-dejavu-core or set DQJ_FONT to a .ttf file");
    Font font(fontPath, layout.fontPixels);

    // Columns share the widest tile's width; each row is as tall as its tallest tile.
    const int columns = std::max(1, std::min<int>(layout.columns, static_cast<int>(tiles.size())));
    const int rows = (static_cast<int>(tiles.size()) + columns - 1) / columns;
    int cellWidth = 0;
    std::vector<int> rowHeights(rows, 0);
    for (std::size_t index = 0; index < tiles.size(); ++index) {
        cellWidth = std::max(cellWidth, tiles[index].image.width);
        int& rowHeight = rowHeights[index / columns];
        rowHeight = std::max(rowHeight, tiles[index].image.height);
    }
    const int lineHeight = layout.fontPixels + layout.fontPixels / 3;
    const int labelHeight = layout.labelLines * lineHeight + layout.padding / 2;
    std::vector<int> rowTops(rows, layout.padding);
    for (int row = 1; row < rows; ++row)
        rowTops[row] = rowTops[row - 1] + rowHeights[row - 1] + labelHeight + layout.padding;

    Image sheet;
    sheet.width = layout.padding + columns * (cellWidth + layout.padding);
    sheet.height = rowTops.back() + rowHeights.back() + labelHeight + layout.padding;
    sheet.rgba.resize(4 * static_cast<std::size_t>(sheet.width) * sheet.height);
    for (std::size_t pixel = 0; pixel < sheet.rgba.size() / 4; ++pixel) {
        for (int channel = 0; channel < 3; ++channel)
            sheet.rgba[4 * pixel + channel] = static_cast<float>(layout.background[channel]);
        sheet.rgba[4 * pixel + 3] = 1.0f;
    }

    for (std::size_t index = 0; index < tiles.size(); ++index) {
        const Image& image = tiles[index].image;
        const int column = static_cast<int>(index) % columns;
        const int row = static_cast<int>(index) / columns;
        const int left = layout.padding + column * (cellWidth + layout.padding);
        const int top = rowTops[row];
        const int cellHeight = rowHeights[row];
        const int x0 = left + (cellWidth - image.width) / 2;
        const int y0 = top + (cellHeight - image.height) / 2;
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x)
                for (int channel = 0; channel < 4; ++channel)
                    sheet.rgba[4 * (static_cast<std::size_t>(y0 + y) * sheet.width + x0 + x) + channel] =
                        channel == 3 ? 1.0f : image.rgba[4 * (static_cast<std::size_t>(y) * image.width + x) + channel];
        const std::vector<std::string> lines = wrap(font, tiles[index].label, cellWidth);
        for (int line = 0; line < std::min<int>(layout.labelLines, static_cast<int>(lines.size())); ++line)
            font.draw(sheet, lines[line], left, top + cellHeight + (line + 1) * lineHeight, layout.text);
    }
    return sheet;
}

}  // namespace dqj
