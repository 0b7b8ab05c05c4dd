// The 3MF writer (mesh_3mf.hpp).
#include "bake/mesh_3mf.hpp"

#include <cstdio>

#include "dqjulia/image.hpp"
#include "dqjulia/version.h"
#include "files/zip_file.hpp"

namespace dqj {
namespace {

const char* unitAttribute(MeshUnit unit) {
    switch (unit) {
        case MeshUnit::Millimeter: return "millimeter";
        case MeshUnit::Centimeter: return "centimeter";
        case MeshUnit::Meter: return "meter";
        case MeshUnit::Inch: return "inch";
    }
    return "millimeter";
}

constexpr const char* kContentTypes =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">"
    "<Default Extension=\"rels\" ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>"
    "<Default Extension=\"model\" ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/>"
    "</Types>\n";

constexpr const char* kRelationships =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">"
    "<Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" "
    "Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/>"
    "</Relationships>\n";

class ThreeMfFormat final : public MeshFormat {
public:
    ThreeMfFormat(AtomicFile& file, bool colors, MeshUnit unit)
        : file_(file), unit_(unit), vertices_(file.path()), triangles_(file.path()) {
        if (colors) colors_ = std::make_unique<ScratchFile>(file.path());
    }

    void add(const Mesh& part, std::uint64_t) override {
        char line[192];
        std::ostream& vertices = vertices_.stream();
        for (const glm::vec3& p : part.positions) {
            const int size =
                std::snprintf(line, sizeof line, "<vertex x=\"%.7g\" y=\"%.7g\" z=\"%.7g\"/>\n", p.x, p.y, p.z);
            vertices.write(line, size);
        }
        if (colors_) {
            std::ostream& colors = colors_->stream();
            for (const glm::vec3& c : part.colors) {
                const int size = std::snprintf(line, sizeof line, "<m:color color=\"#%02X%02X%02X\"/>\n",
                                               unsigned(linearToSrgb8(c.x)), unsigned(linearToSrgb8(c.y)),
                                               unsigned(linearToSrgb8(c.z)));
                colors.write(line, size);
            }
            colors_->checkWrites();
        }
        std::ostream& triangles = triangles_.stream();
        auto triangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
            const int size =
                colors_ ? std::snprintf(
                              line, sizeof line,
                              "<triangle v1=\"%u\" v2=\"%u\" v3=\"%u\" pid=\"1\" p1=\"%u\" p2=\"%u\" p3=\"%u\"/>\n", a,
                              b, c, a, b, c)
                        : std::snprintf(line, sizeof line, "<triangle v1=\"%u\" v2=\"%u\" v3=\"%u\"/>\n", a, b, c);
            triangles.write(line, size);
        };
        for (const auto& t : part.triangles) triangle(t[0], t[1], t[2]);
        for (const auto& q : part.quads) {
            triangle(q[0], q[1], q[2]);
            triangle(q[0], q[2], q[3]);
        }
        vertices_.checkWrites();
        triangles_.checkWrites();
    }

    void finish(const MeshCounts&) override {
        ZipWriter zip(file_);
        zip.begin("[Content_Types].xml");
        zip.write(kContentTypes);
        zip.begin("_rels/.rels");
        zip.write(kRelationships);
        zip.begin("3D/3dmodel.model");
        zip.write(std::string("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"") + unitAttribute(unit_) +
                  "\" xml:lang=\"en-US\" xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\"" +
                  (colors_ ? " xmlns:m=\"http://schemas.microsoft.com/3dmanufacturing/material/2015/02\"" : "") +
                  ">\n<metadata name=\"Application\">dqjulia " + DQJ_VERSION_STRING + "</metadata>\n<resources>\n");
        auto copy = [&zip](ScratchFile& scratch) {
            scratch.readBack([&zip](const char* data, std::size_t size) { zip.write(data, size); });
        };
        if (colors_) {
            zip.write("<m:colorgroup id=\"1\">\n");
            copy(*colors_);
            zip.write("</m:colorgroup>\n");
        }
        zip.write(std::string("<object id=\"2\" type=\"model\"") + (colors_ ? " pid=\"1\" pindex=\"0\"" : "") +
                  ">\n<mesh>\n<vertices>\n");
        copy(vertices_);
        zip.write("</vertices>\n<triangles>\n");
        copy(triangles_);
        zip.write(
            "</triangles>\n</mesh>\n</object>\n</resources>\n<build>\n<item objectid=\"2\"/>\n</build>\n</model>\n");
        zip.finish();
    }

private:
    AtomicFile& file_;
    MeshUnit unit_;
    std::unique_ptr<ScratchFile> colors_;  // with colours
    ScratchFile vertices_, triangles_;
};

}  // namespace

std::unique_ptr<MeshFormat> makeThreeMfFormat(AtomicFile& file, bool colors, MeshUnit unit) {
    return std::make_unique<ThreeMfFormat>(file, colors, unit);
}

}  // namespace dqj
