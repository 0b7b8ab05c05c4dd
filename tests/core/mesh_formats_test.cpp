// The mesh files for printing (bake/mesh_file.hpp): binary STL read back by the test's own reader
// (one piece and streamed in the thinnest slabs), the size and units (MeshScale) and their errors.
// tests/core/mesh_files_test.py reads every format, 3MF too, with trimesh and lib3mf.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "bake/mesh_file.hpp"
#include "bake/mesh_stream.hpp"
#include "bake_fixture.hpp"
#include "files/zip_file.hpp"
#include "dqjulia/mesh.hpp"
#include "test_support.hpp"

using namespace dqj;

namespace {

using MeshFormats = dqj::test::BakeFolder;

using dqj::test::defaultAt;

struct StlTriangle {
    glm::vec3 normal;
    std::array<glm::vec3, 3> corners;
};

/// A binary STL read back: the header, the count and the records, checked against the file's size.
std::vector<StlTriangle> readStl(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_GE(bytes.size(), 84u);
    if (bytes.size() < 84) return {};
    EXPECT_NE(bytes.rfind("solid", 0), 0u) << "a binary STL must not start like an ASCII one";
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    EXPECT_EQ(bytes.size(), 84 + 50 * std::size_t(count)) << path;
    std::vector<StlTriangle> triangles(std::min<std::size_t>(count, (bytes.size() - 84) / 50));
    for (std::size_t index = 0; index < triangles.size(); ++index) {
        const char* at = bytes.data() + 84 + 50 * index;
        std::memcpy(&triangles[index].normal, at, 12);
        std::memcpy(triangles[index].corners.data(), at + 12, 36);
        EXPECT_EQ(at[48], 0);
        EXPECT_EQ(at[49], 0);
    }
    return triangles;
}

/// The triangles as sorted keys (corners rotated to start at the least): the same set whatever the
/// order of triangles.
std::vector<std::array<float, 9>> triangleKeys(const std::vector<StlTriangle>& triangles) {
    std::vector<std::array<float, 9>> keys;
    for (const StlTriangle& t : triangles) {
        std::array<std::array<float, 3>, 3> c;
        for (int k = 0; k < 3; ++k) c[k] = {t.corners[k].x, t.corners[k].y, t.corners[k].z};
        const int first = int(std::min_element(c.begin(), c.end()) - c.begin());
        std::array<float, 9> key;
        for (int k = 0; k < 3; ++k)
            for (int axis = 0; axis < 3; ++axis) key[3 * k + axis] = c[(first + k) % 3][axis];
        keys.push_back(key);
    }
    std::sort(keys.begin(), keys.end());
    return keys;
}

TEST_F(MeshFormats, BinaryStlHoldsEveryTriangleWithItsFaceNormal) {
    const Mesh mesh = bakeMesh(defaultAt(48));
    ASSERT_GT(mesh.quads.size(), 1000u);
    writeMesh(mesh, path("m.stl"));
    const std::vector<StlTriangle> triangles = readStl(path("m.stl"));
    ASSERT_EQ(triangles.size(), mesh.triangleCount());
    const std::vector<std::uint32_t> indices = mesh.triangulated();  // the same split, the same order
    for (std::size_t index = 0; index < triangles.size(); ++index) {
        const StlTriangle& t = triangles[index];
        for (int k = 0; k < 3; ++k) ASSERT_EQ(t.corners[k], mesh.positions[indices[3 * index + k]]) << index;
        const glm::vec3 cross = glm::cross(t.corners[1] - t.corners[0], t.corners[2] - t.corners[0]);
        if (glm::length(cross) == 0.0f) continue;
        EXPECT_NEAR(glm::length(t.normal), 1.0f, 1e-5f) << index;
        EXPECT_GT(glm::dot(t.normal, glm::normalize(cross)), 0.9999f) << index;  // counter-clockwise from outside
    }
    EXPECT_EQ(files(), std::vector<std::string>{"m.stl"});
}

// A streamed STL (the thinnest slabs: each part's faces name the previous part's vertices) holds
// the same triangles as the one-piece one.
TEST_F(MeshFormats, StreamedStlEqualsTheMeshInOnePiece) {
    const Params params = defaultAt(96);
    writeMesh(bakeMesh(params), path("whole.stl"));
    for (const int slab : {8, 16}) {
        MeshFile file(path("slabs.stl"), false, Existing::Replace);
        BakeStats stats;
        meshSurface(
            params, {}, {}, [&file](Mesh&& part) { file.add(part); }, stats, slab);
        file.commit();
        EXPECT_GE(stats.slabs, 96u / slab - 1) << slab;
        EXPECT_EQ(triangleKeys(readStl(path("slabs.stl"))), triangleKeys(readStl(path("whole.stl")))) << slab;
    }
}

TEST_F(MeshFormats, SizeScalesTheLargestSideAndMovesTheMeshIntoThePositiveOctant) {
    const Mesh mesh = bakeMesh(defaultAt(48));
    glm::vec3 least(std::numeric_limits<float>::max()), most(-std::numeric_limits<float>::max());
    for (const glm::vec3& p : mesh.positions) {
        least = glm::min(least, p);
        most = glm::max(most, p);
    }
    const glm::vec3 sides = most - least;
    const float largest = std::max({sides.x, sides.y, sides.z});
    for (const auto& [unit, size] : {std::pair{MeshUnit::Millimeter, 120.0}, std::pair{MeshUnit::Inch, 4.5}}) {
        writeMesh(mesh, path("s.stl"), Existing::Replace, MeshScale{unit, size});
        const std::vector<StlTriangle> triangles = readStl(path("s.stl"));
        ASSERT_EQ(triangles.size(), mesh.triangleCount());
        glm::vec3 low(std::numeric_limits<float>::max()), high(-std::numeric_limits<float>::max());
        for (const StlTriangle& t : triangles)
            for (const glm::vec3& c : t.corners) {
                low = glm::min(low, c);
                high = glm::max(high, c);
            }
        EXPECT_EQ(low, glm::vec3(0.0f));
        EXPECT_NEAR(std::max({high.x, high.y, high.z}), size, size * 1e-6);
        for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(high[axis], sides[axis] / largest * size, size * 1e-5);
        // The same scale streamed: parts set aside until the bounds are known.
        MeshFile file(path("slabs.stl"), false, Existing::Replace, MeshScale{unit, size});
        BakeStats stats;
        meshSurface(
            defaultAt(48), {}, {}, [&file](Mesh&& part) { file.add(part); }, stats, 8);
        file.commit();
        EXPECT_EQ(triangleKeys(readStl(path("slabs.stl"))), triangleKeys(triangles));
    }
    EXPECT_EQ(files(), (std::vector<std::string>{"s.stl", "slabs.stl"}));  // nothing set aside is left
}

TEST_F(MeshFormats, NonsenseSizesAndExtensionsAreRefusedBeforeAnyFile) {
    const Mesh mesh = bakeMesh(defaultAt(24));
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (const double size : {0.0, -1.0, -0.0001, nan, inf, -inf, 1e6 + 1, 1e300}) {
        EXPECT_THROW(checkMeshScale({MeshUnit::Millimeter, size}), ParamError) << size;
        EXPECT_THROW(writeMesh(mesh, path("m.stl"), Existing::Replace, {MeshUnit::Millimeter, size}), ParamError);
    }
    EXPECT_THROW(checkMeshScale({MeshUnit::Meter, 1000.5}), ParamError);
    EXPECT_THROW(checkMeshScale({MeshUnit::Inch, 40000}), ParamError);  // 1016 m
    EXPECT_NO_THROW(checkMeshScale({MeshUnit::Meter, 1000}));
    EXPECT_NO_THROW(checkMeshScale({MeshUnit::Millimeter, 0.01}));
    EXPECT_NO_THROW(checkMeshScale({MeshUnit::Millimeter, std::nullopt}));  // no size
    try {
        checkMeshScale({MeshUnit::Centimeter, -5});
        ADD_FAILURE();
    } catch (const ParamError& error) {
        EXPECT_NE(std::string(error.what()).find("the size (-5 cm) must be above 0 and at most 100000 cm"),
                  std::string::npos)
            << error.what();
    }
    for (const char* name : {"m.stlx", "m.3mf.txt", "m", "m.amf"})
        EXPECT_THROW(writeMesh(mesh, path(name)), ParamError);
    EXPECT_NO_THROW(writeMesh(mesh, path("M.STL")));
    EXPECT_NO_THROW(writeMesh(mesh, path("M.3MF")));
    EXPECT_EQ(files(), (std::vector<std::string>{"M.3MF", "M.STL"}));
}

}  // namespace

namespace {

// ZIP64 (a 3MF's model past 4 GB): an entry of 4.3 GB of zeros (a few MB deflated) and an entry
// after it, whose offset passes 4 GB too, read back by Python's zipfile, which checks every CRC.
TEST_F(MeshFormats, ZipEntriesAndOffsetsPast4GbAreZip64) {
    {
        AtomicFile file(path("big.zip"));
        ZipWriter zip(file);
        zip.begin("big.bin");
        const std::vector<char> zeros(std::size_t(1) << 24, 0);
        const std::uint64_t size = (std::uint64_t(1) << 32) + (std::uint64_t(1) << 28);  // 4.25 GiB
        for (std::uint64_t written = 0; written < size; written += zeros.size()) zip.write(zeros.data(), zeros.size());
        zip.write("end");
        zip.begin("after.txt");
        zip.write("after 4 GB");
        zip.finish();
        file.commit();
    }
    const auto read = dqj::test::runCommand(
        "/usr/bin/python3",
        "-c \"import sys, zipfile; z = zipfile.ZipFile(sys.argv[1]); assert z.testzip() is None; "
        "print([(i.filename, i.file_size) for i in z.infolist()], z.read('after.txt').decode())\" '" +
            path("big.zip") + "'",
        dir_);
    ASSERT_EQ(read.exitCode, 0) << read.err;
    EXPECT_NE(read.out.find("[('big.bin', 4563402755), ('after.txt', 10)] after 4 GB"), std::string::npos) << read.out;
}

}  // namespace
