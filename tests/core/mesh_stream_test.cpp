// Streamed meshing (bake/mesh_stream.hpp): the mesh made slab by slab against the mesh made in
// one piece (the same faces over the same vertex positions, to the bit), closed and
// edge-manifold across the seams; the memory limit choosing the slabs; the file written as the
// slabs come; a limit no slab fits refused before any sampling; a cancel at any slab leaving
// nothing behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <unordered_map>

#include <glm/geometric.hpp>

#include "dqjulia/bake.hpp"
#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "bake/memory.hpp"
#include "bake/mesh_stream.hpp"
#include "bake/sparse_sampler.hpp"
#include "bake_fixture.hpp"
#include "test_support.hpp"

using namespace dqj;

namespace {

using MeshStream = dqj::test::BakeFolder;

using dqj::test::defaultAt;

/// A mesh gathered from meshSurface's parts, checking as they come that each part's faces name
/// only vertices of it and the parts before it.
Mesh gather(const Params& params, int slabVoxels, const BakeOptions& options = {}, BakeStats* statsOut = nullptr,
            std::size_t* parts = nullptr) {
    Mesh mesh;
    std::size_t count = 0;
    BakeStats stats;
    meshSurface(
        params, options, {},
        [&](Mesh&& part) {
            ++count;
            const std::size_t vertices = mesh.positions.size() + part.positions.size();
            for (const auto& quad : part.quads)
                for (const std::uint32_t index : quad) EXPECT_LT(index, vertices);
            for (const auto& triangle : part.triangles)
                for (const std::uint32_t index : triangle) EXPECT_LT(index, vertices);
            EXPECT_EQ(part.normals.size(), part.positions.size());
            mesh.positions.insert(mesh.positions.end(), part.positions.begin(), part.positions.end());
            mesh.normals.insert(mesh.normals.end(), part.normals.begin(), part.normals.end());
            mesh.colors.insert(mesh.colors.end(), part.colors.begin(), part.colors.end());
            mesh.quads.insert(mesh.quads.end(), part.quads.begin(), part.quads.end());
            mesh.triangles.insert(mesh.triangles.end(), part.triangles.begin(), part.triangles.end());
        },
        stats, slabVoxels);
    if (statsOut) *statsOut = stats;
    if (parts) *parts = count;
    return mesh;
}

using Bits = std::array<std::uint32_t, 3>;
Bits bitsOf(const glm::vec3& p) {
    Bits bits;
    std::memcpy(bits.data(), &p, sizeof bits);
    return bits;
}

/// Every face as its corners' positions (bits), each turned to start at its least corner
/// (orientation kept), all sorted: the mesh's faces whatever the vertices' order.
std::vector<std::vector<Bits>> facesByPosition(const Mesh& mesh) {
    std::vector<std::vector<Bits>> faces;
    auto add = [&](const auto& face) {
        std::vector<Bits> corners;
        corners.reserve(face.size());
        for (const std::uint32_t index : face) corners.push_back(bitsOf(mesh.positions[index]));
        std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
        faces.push_back(std::move(corners));
    };
    for (const auto& triangle : mesh.triangles) add(triangle);
    for (const auto& quad : mesh.quads) add(quad);
    std::sort(faces.begin(), faces.end());
    return faces;
}

/// Closed and edge-manifold, consistently oriented: every directed edge once, and its reverse
/// once; no two vertices at one position (a crack would repeat them); every vertex used.
void expectClosedManifold(const Mesh& mesh, const std::string& what) {
    std::unordered_map<std::uint64_t, int> directed;
    std::vector<char> used(mesh.positions.size(), 0);
    auto add = [&](const auto& face) {
        for (std::size_t corner = 0; corner < face.size(); ++corner) {
            const std::uint32_t a = face[corner], b = face[(corner + 1) % face.size()];
            ++directed[(std::uint64_t(a) << 32) | b];
            used[a] = 1;
        }
    };
    for (const auto& triangle : mesh.triangles) add(triangle);
    for (const auto& quad : mesh.quads) add(quad);
    std::size_t bad = 0;
    for (const auto& [edge, count] : directed) {
        const std::uint64_t reverse = (edge << 32) | (edge >> 32);
        const auto found = directed.find(reverse);
        if (count != 1 || found == directed.end() || found->second != 1) ++bad;
    }
    EXPECT_EQ(bad, 0u) << what << ": directed edges not used once each way";
    EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << what << ": unused vertices";
    std::vector<Bits> positions;
    for (const glm::vec3& p : mesh.positions) positions.push_back(bitsOf(p));
    std::sort(positions.begin(), positions.end());
    EXPECT_EQ(std::adjacent_find(positions.begin(), positions.end()), positions.end())
        << what << ": two vertices at one position";
}

/// The same faces over the same positions, and per position the same normal (to rounding: the
/// sums run in another order) and colour.
void expectSameMesh(const Mesh& streamed, const Mesh& whole, const std::string& what) {
    ASSERT_EQ(streamed.positions.size(), whole.positions.size()) << what;
    ASSERT_EQ(streamed.quads.size(), whole.quads.size()) << what;
    ASSERT_EQ(streamed.triangles.size(), whole.triangles.size()) << what;
    EXPECT_TRUE(facesByPosition(streamed) == facesByPosition(whole)) << what << ": the faces differ";
    std::map<Bits, std::size_t> wholeIndex;
    for (std::size_t index = 0; index < whole.positions.size(); ++index)
        wholeIndex[bitsOf(whole.positions[index])] = index;
    double worstNormal = 0.0, worstColour = 0.0;
    for (std::size_t index = 0; index < streamed.positions.size(); ++index) {
        const auto found = wholeIndex.find(bitsOf(streamed.positions[index]));
        ASSERT_NE(found, wholeIndex.end()) << what;
        worstNormal =
            std::max(worstNormal, double(glm::length(streamed.normals[index] - whole.normals[found->second])));
        if (!whole.colors.empty())
            worstColour =
                std::max(worstColour, double(glm::length(streamed.colors[index] - whole.colors[found->second])));
    }
    EXPECT_LT(worstNormal, 1e-5) << what;
    EXPECT_LT(worstColour, 1e-3) << what;
}

TEST_F(MeshStream, SlabsOfAnyThicknessGiveTheMeshMadeInOnePiece) {
    const Params params = defaultAt(64);
    BakeStats wholeStats;
    std::size_t parts = 0;
    const Mesh whole = gather(params, 0, {}, &wholeStats, &parts);
    EXPECT_EQ(parts, 1u);
    EXPECT_EQ(wholeStats.slabs, 1u);
    ASSERT_GT(whole.quads.size(), 5000u);
    expectClosedManifold(whole, "one piece");
    // bakeMesh is that one piece, vertex for vertex.
    const Mesh baked = bakeMesh(params);
    EXPECT_TRUE(baked.positions == whole.positions && baked.quads == whole.quads);
    for (const int slab : {8, 16, 24, 40}) {
        const std::string what = "slabs of " + std::to_string(slab) + " voxels";
        BakeStats stats;
        const Mesh streamed = gather(params, slab, {}, &stats, &parts);
        EXPECT_EQ(parts, stats.slabs) << what;
        EXPECT_GE(stats.slabs, std::size_t(64 / slab)) << what;
        expectClosedManifold(streamed, what);
        expectSameMesh(streamed, whole, what);
    }
}

TEST_F(MeshStream, TheBallStreamedIsAClosedSphere) {
    const Params params = dqj::test::ballAt(40);
    const Mesh whole = gather(params, 0);
    const Mesh streamed = gather(params, 8);
    expectClosedManifold(streamed, "ball");
    expectSameMesh(streamed, whole, "ball");
    // Euler characteristic 2: V - E + F, with E = half the directed edges.
    const long edges = long(2 * streamed.quads.size() + 3 * streamed.triangles.size() / 2);
    EXPECT_EQ(long(streamed.positions.size()) - edges + long(streamed.quads.size() + streamed.triangles.size()), 2);
}

/// A PLY file as bakeMeshFile writes it, read back.
Mesh readPly(const std::string& path, bool colors) {
    std::ifstream in(path, std::ios::binary);
    std::string line, header;
    std::size_t vertices = 0, faces = 0;
    while (std::getline(in, line) && line != "end_header") {
        std::istringstream words(line);
        std::string word, element;
        words >> word;
        if (word == "element") {
            words >> element;
            (element == "vertex" ? vertices : faces) = std::stoul(line.substr(line.rfind(' ') + 1));
        }
    }
    Mesh mesh;
    for (std::size_t index = 0; index < vertices; ++index) {
        glm::vec3 p, n;
        in.read(reinterpret_cast<char*>(&p), sizeof p);
        in.read(reinterpret_cast<char*>(&n), sizeof n);
        mesh.positions.push_back(p);
        mesh.normals.push_back(n);
        if (colors) {
            unsigned char rgb[3];
            in.read(reinterpret_cast<char*>(rgb), 3);
        }
    }
    for (std::size_t index = 0; index < faces; ++index) {
        const int corners = in.get();
        if (corners == 4) {
            std::array<std::uint32_t, 4> quad;
            in.read(reinterpret_cast<char*>(quad.data()), sizeof quad);
            mesh.quads.push_back(quad);
        } else {
            std::array<std::uint32_t, 3> triangle;
            in.read(reinterpret_cast<char*>(triangle.data()), sizeof triangle);
            mesh.triangles.push_back(triangle);
        }
    }
    EXPECT_TRUE(in.good()) << path << " is shorter than its header says";
    EXPECT_EQ(in.peek(), std::char_traits<char>::eof()) << path << " is longer than its header says";
    return mesh;
}

/// A limit that lets about half of the one-piece mesh's leaves be sampled at once (a slab also
/// samples 16 voxels on either side).
std::uint64_t halfOf(const BakeStats& whole) {
    const std::uint64_t fixed = samplingEstimate(meshMemoryModel(), 0, false);
    return fixed + (whole.estimatedBytes - fixed) / 2;
}

TEST_F(MeshStream, TheLimitChoosesTheSlabsAndTheFileHoldsTheMeshMadeInOnePiece) {
    Params params = defaultAt(128);
    BakeStats wholeStats;
    const Mesh whole = bakeMesh(params, {}, {}, &wholeStats);
    writeMesh(whole, path("whole.ply"));
    BakeOptions options;
    options.memoryLimit = halfOf(wholeStats);
    BakeStats stats;
    const MeshCounts counts = bakeMeshFile(params, path("m.ply"), options, {}, &stats);
    EXPECT_GE(stats.slabs, 2u);
    EXPECT_LE(stats.estimatedBytes, options.memoryLimit);
    EXPECT_EQ(counts.vertices, whole.positions.size());
    EXPECT_EQ(counts.quads, whole.quads.size());
    EXPECT_EQ(files(), (std::vector<std::string>{"m.ply", "whole.ply"}));  // nothing else left
    const Mesh streamed = readPly(path("m.ply"), true);
    expectClosedManifold(streamed, "file");
    Mesh wholeRead = readPly(path("whole.ply"), true);
    expectSameMesh(streamed, wholeRead, "file");
    // The same size as the one-piece file: only the order differs.
    EXPECT_EQ(std::filesystem::file_size(path("m.ply")), std::filesystem::file_size(path("whole.ply")));
    // bakeMesh (the C ABI's and Blender's) streams the same way under the limit.
    BakeStats heldStats;
    const Mesh held = bakeMesh(params, options, {}, &heldStats);
    EXPECT_EQ(heldStats.slabs, stats.slabs);
    expectSameMesh(held, whole, "bakeMesh in slabs");

    // OBJ: each slab's v, vn and f lines in turn, the counts in the first line.
    params.bake.meshColors = false;
    const MeshCounts objCounts = bakeMeshFile(params, path("m.obj"), options);
    std::ifstream obj(path("m.obj"));
    std::string first, line;
    std::getline(obj, first);
    EXPECT_EQ(first.rfind("# dqjulia ", 0), 0u) << first;
    EXPECT_NE(first.find(": " + std::to_string(objCounts.vertices) + " vertices, " +
                         std::to_string(objCounts.quads + objCounts.triangles) + " faces"),
              std::string::npos)
        << first;
    std::size_t v = 0, vn = 0, f = 0;
    while (std::getline(obj, line)) {
        const std::string tag = line.substr(0, line.find(' '));
        if (tag == "v") ++v;
        if (tag == "vn") ++vn;
        if (tag == "f") {
            ++f;
            std::istringstream corners(line.substr(2));
            std::string corner;
            while (corners >> corner) EXPECT_LE(std::stoul(corner), v) << "a face before its vertex: " << line;
        }
    }
    EXPECT_EQ(v, whole.positions.size());
    EXPECT_EQ(vn, v);
    EXPECT_EQ(f, whole.quads.size() + whole.triangles.size());
}

TEST_F(MeshStream, ALimitNoSlabFitsIsRefusedBeforeAnySampling) {
    const Params params = defaultAt(256);
    std::ofstream(path("m.ply")) << "previous";
    BakeMonitor monitor;
    BakeOptions options;
    options.monitor = &monitor;
    options.memoryLimit = samplingEstimate(meshMemoryModel(), 300, false);  // 300 leaves: no slab of 256^3
    bool sampled = false;
    const ProgressCallback watch = [&](double) {
        sampled = sampled || monitor.stage.load() != BakeStage::Classifying;
        return true;
    };
    try {
        bakeMeshFile(params, path("m.ply"), options, watch);
        FAIL() << "not refused";
    } catch (const MemoryLimitError& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find("even meshed slab by slab"), std::string::npos) << message;
        EXPECT_NE(message.find("--max-memory"), std::string::npos) << message;
        EXPECT_EQ(error.limit(), options.memoryLimit);
    }
    EXPECT_FALSE(sampled) << "refused only after sampling";
    EXPECT_EQ(monitor.slab.load(), 0u);
    EXPECT_EQ(files(), std::vector<std::string>{"m.ply"});
    EXPECT_EQ(dqj::test::readFile(path("m.ply")), "previous");
}

TEST_F(MeshStream, ThePlanBoundsWhatEverySlabSamples) {
    // The slab plan counts each window's first wave from the classification alone; the sampler,
    // given the window, must never find more (the counts of a default limit's plan came out
    // under it once, and its one slab was refused at run time). Every slab of 1, 2 and 5 layers.
    for (const bool rotated : {false, true}) {
        Params params = defaultAt(96);
        if (rotated) params.slice.rotations = {PlaneRotation{2, 4, 30.0}};  // a.j towards b.s
        const LeafLayers layers = countLeafLayers(params, {}, {});
        const openvdb::CoordBBox full = bakeIndexBox(params);
        constexpr std::size_t kHalo = kSlabHalo / 8;
        std::size_t slabs = 0, exact = 0;
        for (const std::size_t thickness : {1u, 2u, 5u}) {
            for (std::size_t first = 0; first < layers.sampled.size(); first += thickness) {
                const std::size_t end = std::min(layers.sampled.size(), first + thickness);
                const int x0 = (layers.first + int(first)) * 8, x1 = (layers.first + int(end)) * 8;
                const openvdb::CoordBBox window(openvdb::Coord(x0 - kSlabHalo, full.min().y(), full.min().z()),
                                                openvdb::Coord(x1 + kSlabHalo - 1, full.max().y(), full.max().z()));
                StagedProgress staged({}, nullptr);
                const SampledSurface sampled = sampleSurface(params, {}, meshMemoryModel(), staged, 0.05, 0.8, &window);
                const std::uint64_t planned =
                    samplingEstimate(meshMemoryModel(), slabLeaves(layers, first, end, kHalo), false);
                EXPECT_LE(sampled.stats.estimatedBytes, planned)
                    << (rotated ? "rotated: " : "") << "layers " << first << " to " << end;
                exact += sampled.stats.estimatedBytes == planned;
                ++slabs;
            }
        }
        EXPECT_GT(exact, 0u) << "the bound is never reached: is it counting the first wave?";
        EXPECT_GT(slabs, 20u);
    }
}

TEST_F(MeshStream, ASlabOverTheLimitWhenSampledIsSplitNotRefused) {
    // Slabs forced 64 voxels thick under a limit that only thinner ones fit: each is found over
    // the limit by its sampler (before sampling) and split in two until it fits, and the mesh is
    // still the one made in one piece.
    const Params params = defaultAt(128);
    const Mesh whole = gather(params, 0);
    const LeafLayers layers = countLeafLayers(params, {}, {});
    BakeOptions options;
    options.memoryLimit =
        samplingEstimate(meshMemoryModel(), slabLeaves(layers, 0, layers.sampled.size(), 0) / 2, false);
    BakeStats stats;
    std::size_t parts = 0;
    const Mesh streamed = gather(params, 64, options, &stats, &parts);
    EXPECT_GT(stats.slabs, layers.sampled.size() / 8 + 1) << "no slab was split";
    EXPECT_EQ(parts, stats.slabs);
    EXPECT_LE(stats.estimatedBytes, options.memoryLimit);
    expectClosedManifold(streamed, "split slabs");
    expectSameMesh(streamed, whole, "split slabs");
    // A slab of one layer over the limit is refused, with the reason.
    options.memoryLimit = samplingEstimate(meshMemoryModel(), 10, false);
    try {
        gather(params, 64, options);
        FAIL() << "not refused";
    } catch (const MemoryLimitError& error) {
        EXPECT_NE(std::string(error.what()).find("even meshed slab by slab: the thinnest slab"), std::string::npos)
            << error.what();
    }
}

TEST_F(MeshStream, AnAdaptiveMeshOverTheLimitIsRefusedWithTheReason) {
    Params params = defaultAt(96);
    BakeStats wholeStats;
    bakeMesh(params, {}, {}, &wholeStats);
    params.bake.adaptivity = 0.3;
    BakeOptions options;
    options.memoryLimit = halfOf(wholeStats);
    try {
        bakeMeshFile(params, path("m.ply"), options);
        FAIL() << "not refused";
    } catch (const MemoryLimitError& error) {
        EXPECT_NE(std::string(error.what()).find("bake.adaptivity above 0 is made in one piece"), std::string::npos)
            << error.what();
    }
    EXPECT_TRUE(files().empty());
}

TEST_F(MeshStream, ACancelAtAnySlabLeavesNothingAndKeepsTheFileThere) {
    const Params params = defaultAt(128);
    BakeStats wholeStats;
    bakeMesh(params, {}, {}, &wholeStats);
    BakeOptions options;
    options.memoryLimit = halfOf(wholeStats);
    BakeStats stats;
    bakeMeshFile(params, path("count.ply"), options, {}, &stats);
    std::filesystem::remove(path("count.ply"));
    ASSERT_GE(stats.slabs, 2u);
    for (const std::string name : {"m.ply", "m.obj"}) {
        for (std::uint32_t slab = 1; slab <= stats.slabs; ++slab) {
            SCOPED_TRACE(name + ", slab " + std::to_string(slab));
            std::ofstream(path(name)) << "previous";
            BakeMonitor monitor;
            options.monitor = &monitor;
            // Cancelled once the slab is being meshed: the slabs before it are in the file by then.
            const ProgressCallback cancel = [&](double) {
                return !(monitor.slab.load() == slab && monitor.stage.load() == BakeStage::Meshing);
            };
            EXPECT_THROW(bakeMeshFile(params, path(name), options, cancel), Cancelled);
            EXPECT_EQ(files(), std::vector<std::string>{name});
            EXPECT_EQ(dqj::test::readFile(path(name)), "previous");
            std::filesystem::remove(path(name));
        }
    }
    options.monitor = nullptr;
    // At the very end, just before the file is published: nothing either.
    EXPECT_THROW(bakeMeshFile(params, path("m.ply"), options, [](double fraction) { return fraction < 1.0; }),
                 Cancelled);
    EXPECT_TRUE(files().empty());
}

}  // namespace
