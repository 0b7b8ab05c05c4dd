// PLY, OBJ and STL files of a mesh, written part by part, placed and scaled (mesh_file.hpp).
#include "bake/mesh_file.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "bake/mesh_3mf.hpp"
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

class PlyFormat final : public MeshFormat {
public:
    PlyFormat(AtomicFile& file, bool colors) : file_(file), colors_(colors), faces_(file.path()) {
        headerRoom_ = headerText(true, colors_, kLargestCount, kLargestCount, 0).size();
        file_.stream() << std::string(headerRoom_, ' ');  // the header's room, written at the end
    }
    void add(const Mesh& part, std::uint64_t) override {
        writePlyVertices(file_.stream(), part, colors_);
        writePlyFaces(faces_.stream(), part.triangles);
        writePlyFaces(faces_.stream(), part.quads);
        faces_.checkWrites();
        file_.checkWrites();
    }
    void finish(const MeshCounts& counts) override {
        // The triangles and quads per part, in the order the parts came.
        faces_.appendTo(file_);
        file_.stream().seekp(0);
        file_.stream() << headerText(true, colors_, counts.vertices, counts.quads + counts.triangles, headerRoom_);
    }

private:
    AtomicFile& file_;
    bool colors_;
    ScratchFile faces_;
    std::size_t headerRoom_ = 0;
};

class ObjFormat final : public MeshFormat {
public:
    ObjFormat(AtomicFile& file, bool colors) : file_(file), colors_(colors) {
        headerRoom_ = headerText(false, colors_, kLargestCount, kLargestCount, 0).size();
        file_.stream() << std::string(headerRoom_, ' ');
    }
    void add(const Mesh& part, std::uint64_t) override {
        writeObjPart(file_.stream(), part, colors_);
        file_.checkWrites();
    }
    void finish(const MeshCounts& counts) override {
        file_.stream().seekp(0);
        file_.stream() << headerText(false, colors_, counts.vertices, counts.quads + counts.triangles, headerRoom_);
    }

private:
    AtomicFile& file_;
    bool colors_;
    std::size_t headerRoom_ = 0;
};

class StlFormat final : public MeshFormat {
public:
    static constexpr std::size_t kHeader = 80, kRecord = 50;

    explicit StlFormat(AtomicFile& file) : file_(file) {
        // Not "solid ...": readers take a header that starts so for an ASCII STL.
        std::string header = "binary STL by dqjulia " + std::string(DQJ_VERSION_STRING);
        header.resize(kHeader + 4, ' ');  // the count, 4 bytes, is written at the end
        file_.stream() << header;
    }
    void add(const Mesh& part, std::uint64_t firstVertex) override {
        static_assert(std::endian::native == std::endian::little, "the STL writer assumes a little-endian machine");
        triangles_ += part.triangleCount();
        if (triangles_ > UINT32_MAX)
            throw std::runtime_error(AtomicFile::failureMessage(
                file_.path(),
                "the mesh has more than 2^32 - 1 triangles, more than a binary STL can hold: lower "
                "the resolution or write a .ply or .3mf"));
        const auto position = [&](std::uint32_t vertex) -> const glm::vec3& {
            if (vertex >= firstVertex) return part.positions[vertex - firstVertex];
            if (vertex >= previousFirst_ && vertex - previousFirst_ < previous_.size())
                return previous_[vertex - previousFirst_];
            throw std::logic_error("StlFormat: a face names a vertex of a part before the previous one");
        };
        const auto record = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, char* at) {
            const glm::vec3 corners[3] = {position(a), position(b), position(c)};
            const glm::dvec3 p0(corners[0]), edge1 = glm::dvec3(corners[1]) - p0, edge2 = glm::dvec3(corners[2]) - p0;
            const glm::dvec3 cross = glm::cross(edge1, edge2);
            const double length = glm::length(cross);
            const glm::vec3 normal = length > 0.0 ? glm::vec3(cross / length) : glm::vec3(0.0f);
            std::memcpy(at, &normal, 12);
            std::memcpy(at + 12, corners, 36);
            at[48] = at[49] = 0;  // the "attribute byte count"
        };
        std::ostream& out = file_.stream();
        writeRecords(out, part.triangles.size(), kRecord, [&](std::size_t index, char* at) {
            const auto& t = part.triangles[index];
            record(t[0], t[1], t[2], at);
        });
        writeRecords(out, 2 * part.quads.size(), kRecord, [&](std::size_t index, char* at) {
            const auto& q = part.quads[index / 2];
            if (index % 2 == 0)
                record(q[0], q[1], q[2], at);
            else
                record(q[0], q[2], q[3], at);
        });
        file_.checkWrites();
        previous_ = part.positions;  // what the next part's faces may name
        previousFirst_ = firstVertex;
    }
    void finish(const MeshCounts&) override {
        const std::uint32_t count = std::uint32_t(triangles_);
        file_.stream().seekp(std::streamoff(kHeader));
        file_.stream().write(reinterpret_cast<const char*>(&count), 4);
    }

private:
    AtomicFile& file_;
    std::uint64_t triangles_ = 0;
    std::vector<glm::vec3> previous_;
    std::uint64_t previousFirst_ = 0;
};

std::unique_ptr<MeshFormat> makeFormat(AtomicFile& file, bool colors, MeshUnit unit) {
    const std::string extension = AtomicFile::lowercaseExtension(file.path());
    if (extension == ".ply") return std::make_unique<PlyFormat>(file, colors);
    if (extension == ".obj") return std::make_unique<ObjFormat>(file, colors);
    if (extension == ".stl") return std::make_unique<StlFormat>(file);
    return makeThreeMfFormat(file, colors, unit);  // checkMeshPath: .3mf
}

// A part set aside (with a size): its byte count, then its counts, then its arrays as they are.
void writeRawPart(std::ostream& out, const Mesh& part) {
    const std::uint64_t counts[4] = {part.positions.size(), part.colors.size(), part.triangles.size(),
                                     part.quads.size()};
    auto bytes = [](const auto& values) { return values.size() * sizeof(values[0]); };
    const std::uint64_t size = sizeof counts + bytes(part.positions) + bytes(part.normals) + bytes(part.colors) +
                               bytes(part.triangles) + bytes(part.quads);
    out.write(reinterpret_cast<const char*>(&size), sizeof size);
    out.write(reinterpret_cast<const char*>(counts), sizeof counts);
    auto put = [&](const auto& values) {
        out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(bytes(values)));
    };
    put(part.positions);
    put(part.normals);
    put(part.colors);
    put(part.triangles);
    put(part.quads);
}

Mesh readRawPart(const char* at) {
    std::uint64_t counts[4];
    std::memcpy(counts, at, sizeof counts);
    at += sizeof counts;
    Mesh part;
    auto take = [&](auto& values, std::uint64_t count) {
        values.resize(count);
        if (count == 0) return;  // data() may be null, which memcpy must not get
        std::memcpy(values.data(), at, count * sizeof(values[0]));
        at += count * sizeof(values[0]);
    };
    take(part.positions, counts[0]);
    take(part.normals, counts[0]);
    take(part.colors, counts[1]);
    take(part.triangles, counts[2]);
    take(part.quads, counts[3]);
    return part;
}

}  // namespace

const char* meshUnitName(MeshUnit unit) {
    switch (unit) {
        case MeshUnit::Millimeter: return "mm";
        case MeshUnit::Centimeter: return "cm";
        case MeshUnit::Meter: return "m";
        case MeshUnit::Inch: return "in";
    }
    return "mm";
}

double meshUnitMetres(MeshUnit unit) {
    switch (unit) {
        case MeshUnit::Millimeter: return 0.001;
        case MeshUnit::Centimeter: return 0.01;
        case MeshUnit::Meter: return 1.0;
        case MeshUnit::Inch: return 0.0254;
    }
    return 0.001;
}

void checkMeshScale(const MeshScale& scale) {
    const double limit = kMaxMeshSizeMetres / meshUnitMetres(scale.unit);
    if (!scale.size) return;  // no size: slice coordinates
    const double size = *scale.size;
    if (!(size > 0.0) || !(size <= limit)) {  // NaN fails both
        char text[200];
        std::snprintf(text, sizeof text,
                      "the size (%g %s) must be above 0 and at most %g %s (1 km): the mesh's largest side", size,
                      meshUnitName(scale.unit), limit, meshUnitName(scale.unit));
        throw ParamError("mesh.size", text);
    }
}

void checkMeshPath(const std::string& path) {
    const std::string extension = AtomicFile::lowercaseExtension(path);
    if (extension != ".ply" && extension != ".obj" && extension != ".stl" && extension != ".3mf")
        throw ParamError("output.path", "'" + inputExcerpt(path) + "' must end in .ply, .obj, .stl or .3mf");
}

MeshPlacement meshPlacement(const MeshScale& scale, const glm::dvec3& least, const glm::dvec3& most) {
    const glm::dvec3 sides = most - least;
    const double largest = std::max({sides.x, sides.y, sides.z});
    if (!scale.size || !(largest > 0.0)) return {};
    return {least, *scale.size / largest};
}

MeshFile::MeshFile(const std::string& path, bool colors, Existing existing, const MeshScale& scale)
    : colors_((checkMeshPath(path), checkMeshScale(scale), colors)),
      scale_(scale),
      file_(path, existing),
      format_(makeFormat(file_, colors, scale.unit)) {
    if (scale_.size) parts_ = std::make_unique<ScratchFile>(path);
    least_ = glm::dvec3(std::numeric_limits<double>::infinity());
    most_ = -least_;
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
    if (parts_) {
        for (const glm::vec3& p : part.positions) {
            least_ = glm::min(least_, glm::dvec3(p));
            most_ = glm::max(most_, glm::dvec3(p));
        }
        writeRawPart(parts_->stream(), part);
        parts_->checkWrites();  // a full disk stops the mesh here, not gigabytes later
    } else {
        write(part);
    }
    counts_.vertices += part.positions.size();
    counts_.quads += part.quads.size();
    counts_.triangles += part.triangles.size();
}

void MeshFile::write(const Mesh& part) {
    if (factor_ == 1.0 && origin_ == glm::dvec3(0.0)) {
        format_->add(part, written_);
    } else {
        Mesh placed;
        placed.positions.reserve(part.positions.size());
        for (const glm::vec3& p : part.positions) placed.positions.emplace_back((glm::dvec3(p) - origin_) * factor_);
        placed.normals = part.normals;  // a uniform scale and a move keep them
        placed.colors = part.colors;
        placed.triangles = part.triangles;
        placed.quads = part.quads;
        format_->add(placed, written_);
    }
    written_ += part.positions.size();
}

void MeshFile::commit() {
    if (parts_) {
        const MeshPlacement placement = meshPlacement(scale_, least_, most_);
        origin_ = placement.origin;
        factor_ = placement.factor;
        std::vector<char> pending;  // the bytes of the part being read back
        parts_->readBack([&](const char* data, std::size_t size) {
            pending.insert(pending.end(), data, data + size);
            std::size_t used = 0;
            std::uint64_t length = 0;
            while (pending.size() - used >= sizeof length &&
                   (std::memcpy(&length, pending.data() + used, sizeof length),
                    pending.size() - used - sizeof length >= length)) {
                write(readRawPart(pending.data() + used + sizeof length));
                used += sizeof length + length;
            }
            pending.erase(pending.begin(), pending.begin() + std::ptrdiff_t(used));
        });
        if (!pending.empty()) throw std::logic_error("MeshFile::commit: a part set aside was cut short");
        parts_.reset();
    }
    format_->finish(counts_);
    format_.reset();  // its scratch files go now
    file_.commit();
}

}  // namespace dqj
