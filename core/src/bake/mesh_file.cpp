// PLY and OBJ files of a mesh, written part by part (mesh_file.hpp).
#include "bake/mesh_file.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "dqjulia/image.hpp"
#include "dqjulia/version.h"

namespace dqj {
namespace {

constexpr std::uint64_t kLargestCount = UINT64_MAX;  // the widest count a header may have to hold

/// The header, its first comment padded with spaces to make it `room` bytes long (0: unpadded).
std::string headerText(bool ply, bool colors, std::uint64_t vertices, std::uint64_t faces, std::size_t room) {
    std::string first, rest;
    if (ply) {
        first = "ply\nformat binary_little_endian 1.0\ncomment dqjulia " + std::string(DQJ_VERSION_STRING);
        rest = "\nelement vertex " + std::to_string(vertices) +
               "\nproperty float x\nproperty float y\nproperty float z\n"
               "property float nx\nproperty float ny\nproperty float nz\n";
        if (colors) rest += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        rest += "element face " + std::to_string(faces) + "\nproperty list uchar uint vertex_indices\nend_header\n";
    } else {
        first = "# dqjulia " + std::string(DQJ_VERSION_STRING) + ": " + std::to_string(vertices) + " vertices, " +
                std::to_string(faces) + " faces" + (colors ? "; vertex colours (sRGB) after x y z" : "");
        rest.push_back('\n');  // not rest = "\n": GCC 12 warns falsely (-Wrestrict) on that
    }
    const std::size_t size = first.size() + rest.size();
    if (room > size) first.append(room - size, ' ');
    return first + rest;
}

/// Fixed-size records into a block of about a megabyte, written out a block at a time.
template <typename Encode>
void writeRecords(std::ostream& out, std::size_t count, std::size_t size, Encode encode) {
    std::vector<char> block(std::max<std::size_t>(size, std::min<std::size_t>(count * size, 1u << 20)));
    const std::size_t perBlock = block.size() / size;
    for (std::size_t first = 0; first < count; first += perBlock) {
        const std::size_t end = std::min(count, first + perBlock);
        char* at = block.data();
        for (std::size_t index = first; index < end; ++index, at += size) encode(index, at);
        out.write(block.data(), std::streamsize(at - block.data()));
    }
}

template <typename Face>
void writePlyFaces(std::ostream& out, const std::vector<Face>& faces) {
    constexpr std::uint8_t corners = std::tuple_size_v<Face>;
    writeRecords(out, faces.size(), 1 + sizeof(Face), [&](std::size_t index, char* at) {
        *at = static_cast<char>(corners);
        std::memcpy(at + 1, faces[index].data(), sizeof(Face));
    });
}

void writePlyVertices(std::ostream& out, const Mesh& part, bool colors) {
    static_assert(std::endian::native == std::endian::little, "the PLY writer assumes a little-endian machine");
    constexpr std::size_t kVec3 = sizeof(glm::vec3);
    writeRecords(out, part.positions.size(), 2 * kVec3 + (colors ? 3 : 0), [&](std::size_t index, char* at) {
        std::memcpy(at, &part.positions[index], kVec3);
        std::memcpy(at + kVec3, &part.normals[index], kVec3);
        if (colors) {
            const glm::vec3& c = part.colors[index];
            const std::uint8_t rgb[3] = {linearToSrgb8(c.x), linearToSrgb8(c.y), linearToSrgb8(c.z)};
            std::memcpy(at + 2 * kVec3, rgb, 3);
        }
    });
}

void writeObjPart(std::ostream& out, const Mesh& part, bool colors) {
    char line[160];
    for (std::size_t index = 0; index < part.positions.size(); ++index) {
        const glm::vec3& p = part.positions[index];
        if (colors) {
            const glm::vec3& c = part.colors[index];
            std::snprintf(line, sizeof line, "v %.7g %.7g %.7g %.4f %.4f %.4f\n", p.x, p.y, p.z,
                          linearToSrgb8(c.x) / 255.0, linearToSrgb8(c.y) / 255.0, linearToSrgb8(c.z) / 255.0);
        } else {
            std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", p.x, p.y, p.z);
        }
        out << line;
    }
    for (const glm::vec3& n : part.normals) {
        std::snprintf(line, sizeof line, "vn %.5f %.5f %.5f\n", n.x, n.y, n.z);
        out << line;
    }
    // OBJ counts from 1; a vertex and its normal share their number.
    for (const auto& t : part.triangles) {
        const unsigned long long a = t[0] + 1ull, b = t[1] + 1ull, c = t[2] + 1ull;
        std::snprintf(line, sizeof line, "f %llu//%llu %llu//%llu %llu//%llu\n", a, a, b, b, c, c);
        out << line;
    }
    for (const auto& q : part.quads) {
        const unsigned long long a = q[0] + 1ull, b = q[1] + 1ull, c = q[2] + 1ull, d = q[3] + 1ull;
        std::snprintf(line, sizeof line, "f %llu//%llu %llu//%llu %llu//%llu %llu//%llu\n", a, a, b, b, c, c, d, d);
        out << line;
    }
}

bool isPly(const std::string& path) {
    const std::string extension = AtomicFile::lowercaseExtension(path);
    if (extension != ".ply" && extension != ".obj")
        throw ParamError("output.path", "'" + inputExcerpt(path) + "' must end in .ply or .obj");
    return extension == ".ply";
}

}  // namespace

MeshFile::MeshFile(const std::string& path, bool colors, Existing existing)
    : ply_(isPly(path)), colors_(colors), file_(path, existing) {
    if (ply_) faces_ = std::make_unique<ScratchFile>(path);
    headerRoom_ = headerText(ply_, colors_, kLargestCount, kLargestCount, 0).size();
    file_.stream() << std::string(headerRoom_, ' ');  // the header's room, written at the end
}

MeshFile::~MeshFile() = default;

void MeshFile::add(const Mesh& part) {
    if (counts_.vertices + part.positions.size() > std::uint64_t(UINT32_MAX) + 1)
        throw std::runtime_error(AtomicFile::failureMessage(
            file_.path(),
            "the mesh has more than 2^32 vertices, more than its 32-bit indices can name: lower the "
            "resolution or mesh a smaller region (bake.bounds)"));
    if (colors_ && part.colors.size() != part.positions.size())
        throw std::logic_error("MeshFile::add: a part without its colours");
    if (ply_) {
        writePlyVertices(file_.stream(), part, colors_);
        writePlyFaces(faces_->stream(), part.triangles);
        writePlyFaces(faces_->stream(), part.quads);
        faces_->checkWrites();
    } else {
        writeObjPart(file_.stream(), part, colors_);
    }
    file_.checkWrites();  // a full disk stops the mesh here, not gigabytes later
    counts_.vertices += part.positions.size();
    counts_.quads += part.quads.size();
    counts_.triangles += part.triangles.size();
}

void MeshFile::commit() {
    // PLY keeps its triangles and quads per part, in the order the parts came.
    if (ply_) faces_->appendTo(file_);
    faces_.reset();
    std::ostream& out = file_.stream();
    out.seekp(0);
    out << headerText(ply_, colors_, counts_.vertices, counts_.quads + counts_.triangles, headerRoom_);
    file_.commit();
}

}  // namespace dqj
