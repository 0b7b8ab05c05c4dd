// compare_outputs: a file the Windows build wrote against the same file from the Linux build, for
// the Windows build's tests (tests/windows/cli_test.py). Built and run on Linux: it reads PNGs with
// the core's reader and VDBs with the Linux OpenVDB, so a file that passes is one Linux programs read.
//
//   compare_outputs png A.png B.png   the same size; fails if a channel differs by more than 1/255
//   compare_outputs vdb A.vdb B.vdb   the same file metadata and grids (names, types, classes,
//                                     transforms, active voxels), values equal within float rounding
//   compare_outputs ply A.ply B.ply   the same header and faces, vertex data within float rounding
//
// Prints what it compared and the largest differences; exit status 0 when equal, 1 if not, 2 on
// a file it cannot read.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "dqjulia/image.hpp"

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
    if (!ok) {
        ++failures;
        std::cout << "FAIL: " << what << "\n";
    }
}

/// Values equal within float rounding: a few units in the last place of the larger, and an
/// absolute floor for values near 0 (the level set's zero crossing, a fog's edge).
bool closeFloats(double a, double b, double scale) { return std::abs(a - b) <= 1e-5 * std::max(scale, std::abs(a)); }

/// A pixel channel of an 8-bit PNG as its code: sRGB colour, linear alpha (readPng decodes both).
int code(const dqj::Image& image, std::size_t index) {
    const float value = image.rgba[index];
    return index % 4 == 3 ? int(std::lround(value * 255.0f)) : int(dqj::linearToSrgb8(value));
}

void comparePng(const std::string& first, const std::string& second) {
    const dqj::Image a = dqj::readPng(first), b = dqj::readPng(second);
    check(a.width == b.width && a.height == b.height, "sizes differ");
    if (a.width != b.width || a.height != b.height || a.rgba.size() != b.rgba.size()) return;
    int largest = 0;
    std::size_t differing = 0;
    for (std::size_t index = 0; index < a.rgba.size(); ++index) {
        const int difference = std::abs(code(a, index) - code(b, index));
        largest = std::max(largest, difference);
        differing += difference > 0;
    }
    std::cout << a.width << "x" << a.height << ": largest channel difference " << largest << "/255, " << differing
              << " of " << a.rgba.size() << " channels differ\n";
    check(largest <= 1, "a channel differs by more than 1/255");
}

float component(float value, int) { return value; }
float component(const openvdb::Vec3s& value, int index) { return value[index]; }

/// The values of `a`'s active voxels in `b` (the same topology is checked by the counts and here).
template <typename GridType>
void compareValues(const GridType& a, const GridType& b, double scale) {
    constexpr int kComponents = openvdb::VecTraits<typename GridType::ValueType>::Size;
    double largest = 0.0;
    std::size_t far = 0, inactive = 0;
    typename GridType::ConstAccessor accessor = b.getConstAccessor();
    for (auto voxel = a.cbeginValueOn(); voxel; ++voxel) {
        inactive += !accessor.isValueOn(voxel.getCoord());
        const auto other = accessor.getValue(voxel.getCoord());
        for (int index = 0; index < kComponents; ++index) {
            const double x = component(*voxel, index), y = component(other, index);
            largest = std::max(largest, std::abs(x - y));
            far += !closeFloats(x, y, scale);
        }
    }
    std::cout << "  largest value difference " << largest << " (" << far << " beyond float rounding)\n";
    check(inactive == 0, "grid " + a.getName() + ": " + std::to_string(inactive) + " voxels active in one file only");
    check(far == 0, "grid " + a.getName() + ": values differ beyond float rounding");
}

openvdb::GridPtrVecPtr readVdb(const std::string& path, openvdb::MetaMap::Ptr& metadata) {
    openvdb::io::File file(path);
    file.open(false);
    openvdb::GridPtrVecPtr grids = file.getGrids();
    metadata = file.getMetadata();
    file.close();
    return grids;
}

void compareVdb(const std::string& first, const std::string& second) {
    openvdb::initialize();
    openvdb::MetaMap::Ptr metaA, metaB;
    const openvdb::GridPtrVecPtr a = readVdb(first, metaA), b = readVdb(second, metaB);
    std::cout << "file metadata: " << metaA->metaCount() << " entries\n";
    for (auto entry = metaA->beginMeta(); entry != metaA->endMeta(); ++entry) {
        const openvdb::Metadata::Ptr other = (*metaB)[entry->first];
        check(other && other->str() == entry->second->str(), "file metadata " + entry->first + " differs");
    }
    check(metaA->metaCount() == metaB->metaCount(), "file metadata counts differ");
    check(a->size() == b->size(), "grid counts differ");
    for (std::size_t index = 0; index < std::min(a->size(), b->size()); ++index) {
        const openvdb::GridBase& gridA = *(*a)[index];
        const openvdb::GridBase& gridB = *(*b)[index];
        std::cout << "grid " << gridA.getName() << " (" << gridA.valueType() << ", " << gridA.getGridClass()
                  << "): " << gridA.activeVoxelCount() << " and " << gridB.activeVoxelCount()
                  << " active voxels, voxel size " << gridA.voxelSize()[0] << "\n";
        check(gridA.getName() == gridB.getName(), "grid " + gridA.getName() + " is " + gridB.getName() + " there");
        check(gridA.type() == gridB.type() && gridA.getGridClass() == gridB.getGridClass(),
              "grid " + gridA.getName() + ": types or classes differ");
        check(gridA.transform() == gridB.transform(), "grid " + gridA.getName() + ": transforms differ");
        check(gridA.activeVoxelCount() == gridB.activeVoxelCount(),
              "grid " + gridA.getName() + ": active voxels differ");
        const double scale = gridA.voxelSize()[0];
        if (gridA.isType<openvdb::FloatGrid>() && gridB.isType<openvdb::FloatGrid>())
            compareValues(static_cast<const openvdb::FloatGrid&>(gridA), static_cast<const openvdb::FloatGrid&>(gridB),
                          scale);
        else if (gridA.isType<openvdb::Vec3SGrid>() && gridB.isType<openvdb::Vec3SGrid>())
            compareValues(static_cast<const openvdb::Vec3SGrid&>(gridA), static_cast<const openvdb::Vec3SGrid&>(gridB),
                          scale);
        else
            check(false, "grid " + gridA.getName() + ": a value type this tool does not compare");
    }
}

/// A binary PLY as the mesh writer makes it: the header's text, then vertex records of floats
/// (and colour bytes), then faces (a count byte and 32-bit indices).
struct Ply {
    std::string header;
    std::size_t vertices = 0, faces = 0, vertexBytes = 0;
    std::vector<char> body;
};

Ply readPly(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read '" + path + "'");
    Ply ply;
    std::string line;
    while (std::getline(in, line) && line != "end_header") {
        if (line.rfind("comment", 0) != 0) ply.header += line + "\n";  // the comment names the version
        std::istringstream words(line);
        std::string word, kind;
        words >> word;
        if (word == "element" && words >> kind) (kind == "vertex" ? words >> ply.vertices : words >> ply.faces);
        if (word == "property" && words >> kind) ply.vertexBytes += kind == "float" ? 4 : kind == "uchar" ? 1 : 0;
    }
    if (line != "end_header") throw std::runtime_error("'" + path + "' is not a PLY file");
    ply.body.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return ply;
}

void comparePly(const std::string& first, const std::string& second) {
    const Ply a = readPly(first), b = readPly(second);
    std::cout << a.vertices << " and " << b.vertices << " vertices, " << a.faces << " and " << b.faces << " faces\n";
    check(a.header == b.header, "the headers differ (counts or properties)");
    const std::size_t vertexData = a.vertices * a.vertexBytes;
    if (a.header != b.header || a.body.size() < vertexData || b.body.size() < vertexData) return;
    check(std::equal(a.body.begin() + long(vertexData), a.body.end(), b.body.begin() + long(vertexData), b.body.end()),
          "the faces differ");
    double largest = 0.0;
    std::size_t far = 0, colors = 0;
    for (std::size_t vertex = 0; vertex < a.vertices; ++vertex) {
        const char* recordA = a.body.data() + vertex * a.vertexBytes;
        const char* recordB = b.body.data() + vertex * a.vertexBytes;
        for (std::size_t field = 0; field < 6; ++field) {  // position and normal
            float x = 0.0f, y = 0.0f;
            std::memcpy(&x, recordA + 4 * field, 4);
            std::memcpy(&y, recordB + 4 * field, 4);
            largest = std::max(largest, double(std::abs(x - y)));
            far += !closeFloats(x, y, 1e-3);
        }
        colors += std::memcmp(recordA + 24, recordB + 24, a.vertexBytes - 24) != 0;
    }
    std::cout << "largest vertex difference " << largest << " (" << far << " beyond float rounding), " << colors
              << " vertex colours differ\n";
    check(far == 0, "vertex positions or normals differ beyond float rounding");
    check(colors == 0, "vertex colours differ");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::cerr << "usage: compare_outputs png|vdb|ply A B\n";
        return 2;
    }
    const std::string kind = argv[1];
    try {
        if (kind == "png")
            comparePng(argv[2], argv[3]);
        else if (kind == "vdb")
            compareVdb(argv[2], argv[3]);
        else if (kind == "ply")
            comparePly(argv[2], argv[3]);
        else
            throw std::runtime_error("unknown kind '" + kind + "'");
    } catch (const std::exception& error) {
        std::cout << "FAIL: " << error.what() << "\n";
        return 2;
    }
    std::cout << (failures ? "the files differ\n" : "the files are equal\n");
    return failures ? 1 : 0;
}
