// Meshes of the baked surface (mesh.hpp): volumeToMesh, clean-up, normals, colours, PLY and OBJ.
#include "dqjulia/mesh.hpp"
#include "dqjulia/version.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <type_traits>

#include <glm/geometric.hpp>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "files/atomic_file.hpp"
#include "dqjulia/batch.hpp"
#include "dqjulia/image.hpp"
#include "dqjulia/coloring.hpp"
#include "bake/level_set.hpp"
#include "bake/memory.hpp"
#include "platform/parallel_progress.hpp"
#include "platform/platform.hpp"
#include "platform/thread_scratch.hpp"

namespace dqj {
namespace {

constexpr std::size_t kVerticesPerTask = 4096;

/// The distinct corners of a polygon in order (a repeated neighbour collapses), or 0 when the
/// polygon is pinched (a corner repeated apart from its neighbours).
int distinctCorners(const std::uint32_t* indices, int count, std::uint32_t* distinct) {
    int size = 0;
    for (int corner = 0; corner < count; ++corner) {
        const std::uint32_t index = indices[corner];
        if (size > 0 && (distinct[size - 1] == index || (corner == count - 1 && distinct[0] == index))) continue;
        if (std::find(distinct, distinct + size, index) != distinct + size) return 0;
        distinct[size++] = index;
    }
    return size;
}

/// True if a face has a repeated vertex or a vertex belongs to no face; in parallel, stopping
/// at the first such face (adaptive meshes have some, and then removeDegenerateFaces does the
/// full pass).
bool hasDegenerateOrUnusedParts(const Mesh& mesh) {
    std::atomic<bool> found{false};
    std::vector<std::atomic<std::uint8_t>> used(mesh.positions.size());  // zeroed (C++20)
    auto check = [&](const auto& faces) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces.size()), [&](const auto& range) {
            if (found.load(std::memory_order_relaxed)) return;
            std::uint32_t distinct[4];
            for (std::size_t index = range.begin(); index < range.end(); ++index) {
                const auto& face = faces[index];
                const int corners = static_cast<int>(face.size());
                if (distinctCorners(face.data(), corners, distinct) != corners) {
                    found.store(true, std::memory_order_relaxed);
                    return;
                }
                for (const std::uint32_t vertex : face) used[vertex].store(1, std::memory_order_relaxed);
            }
        });
        return found.load();
    };
    if (check(mesh.triangles) || check(mesh.quads)) return true;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, used.size()), [&](const auto& range) {
        for (std::size_t index = range.begin(); index < range.end(); ++index)
            if (used[index].load(std::memory_order_relaxed) == 0) found.store(true, std::memory_order_relaxed);
    });
    return found.load();
}

/// Drops faces with fewer than three distinct vertices and turns quads with one repeated vertex
/// into triangles (adaptive meshing collapses vertices), then drops unused vertices. In place:
/// a 512^3 mesh is some 40 MB, and copies would add to the peak.
void removeDegenerateFaces(Mesh& mesh) {
    if (!hasDegenerateOrUnusedParts(mesh)) return;  // nothing would change (OpenVDB's uniform meshes)
    std::uint32_t distinct[4];
    std::size_t kept = 0;
    for (const auto& triangle : mesh.triangles)
        if (distinctCorners(triangle.data(), 3, distinct) == 3)
            mesh.triangles[kept++] = {distinct[0], distinct[1], distinct[2]};
    mesh.triangles.resize(kept);
    kept = 0;
    for (const auto& quad : mesh.quads) {
        const int size = distinctCorners(quad.data(), 4, distinct);
        if (size == 4) mesh.quads[kept++] = {distinct[0], distinct[1], distinct[2], distinct[3]};
        if (size == 3) mesh.triangles.push_back({distinct[0], distinct[1], distinct[2]});
    }
    mesh.quads.resize(kept);
    // Renumber the vertices that faces use, in their original order (so positions compact in place).
    std::vector<std::uint32_t> renumbered(mesh.positions.size(), UINT32_MAX);
    for (const auto& triangle : mesh.triangles)
        for (const std::uint32_t index : triangle) renumbered[index] = 0;
    for (const auto& quad : mesh.quads)
        for (const std::uint32_t index : quad) renumbered[index] = 0;
    std::uint32_t next = 0;
    for (std::size_t index = 0; index < mesh.positions.size(); ++index) {
        if (renumbered[index] == UINT32_MAX) continue;
        renumbered[index] = next;
        mesh.positions[next++] = mesh.positions[index];
    }
    mesh.positions.resize(next);
    for (auto& triangle : mesh.triangles)
        for (std::uint32_t& index : triangle) index = renumbered[index];
    for (auto& quad : mesh.quads)
        for (std::uint32_t& index : quad) index = renumbered[index];
}

/// Vertex normals: the sum of the cross products of the faces around each vertex (normals
/// weighted by area; a quad as the triangles 0-1-2 and 0-2-3), normalised. Summed in place, in
/// float: no per-corner or double-precision copies of the mesh.
std::vector<glm::vec3> vertexNormals(const Mesh& mesh) {
    std::vector<glm::vec3> normals(mesh.positions.size(), glm::vec3(0.0f));
    auto addTriangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        const glm::vec3 normal =
            glm::cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]);
        normals[a] += normal;
        normals[b] += normal;
        normals[c] += normal;
    };
    for (const auto& triangle : mesh.triangles) addTriangle(triangle[0], triangle[1], triangle[2]);
    for (const auto& quad : mesh.quads) {
        addTriangle(quad[0], quad[1], quad[2]);
        addTriangle(quad[0], quad[2], quad[3]);
    }
    for (glm::vec3& normal : normals) {
        const float length = glm::length(normal);
        normal = length > 0.0f ? normal / length : glm::vec3(0.0f);
    }
    return normals;
}

void writePly(const Mesh& mesh, std::ostream& out) {
    static_assert(std::endian::native == std::endian::little, "the PLY writer assumes a little-endian machine");
    const bool colors = !mesh.colors.empty();
    out << "ply\nformat binary_little_endian 1.0\ncomment dqjulia " << DQJ_VERSION_STRING << "\n"
        << "element vertex " << mesh.positions.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n"
        << "property float nx\nproperty float ny\nproperty float nz\n";
    if (colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out << "element face " << mesh.triangles.size() + mesh.quads.size() << "\n"
        << "property list uchar uint vertex_indices\nend_header\n";
    // The body is fixed-size records: each goes into place in a block of about a megabyte,
    // written out a block at a time.
    std::vector<char> block(1u << 20);
    auto records = [&](std::size_t count, std::size_t size, auto encode) {
        const std::size_t perBlock = block.size() / size;
        for (std::size_t first = 0; first < count; first += perBlock) {
            const std::size_t end = std::min(count, first + perBlock);
            char* at = block.data();
            for (std::size_t index = first; index < end; ++index, at += size) encode(index, at);
            out.write(block.data(), std::streamsize(at - block.data()));
        }
    };
    constexpr std::size_t kVec3 = sizeof(glm::vec3);
    records(mesh.positions.size(), 2 * kVec3 + (colors ? 3 : 0), [&](std::size_t index, char* at) {
        std::memcpy(at, &mesh.positions[index], kVec3);
        std::memcpy(at + kVec3, &mesh.normals[index], kVec3);
        if (colors) {
            const glm::vec3& c = mesh.colors[index];
            const std::uint8_t rgb[3] = {linearToSrgb8(c.x), linearToSrgb8(c.y), linearToSrgb8(c.z)};
            std::memcpy(at + 2 * kVec3, rgb, 3);
        }
    });
    auto faces = [&](const auto& list) {
        using Face = std::decay_t<decltype(list[0])>;
        constexpr std::uint8_t corners = std::tuple_size_v<Face>;
        records(list.size(), 1 + sizeof(Face), [&](std::size_t index, char* at) {
            *at = static_cast<char>(corners);
            std::memcpy(at + 1, list[index].data(), sizeof(Face));
        });
    };
    faces(mesh.triangles);
    faces(mesh.quads);
}

void writeObj(const Mesh& mesh, std::ostream& out) {
    const bool colors = !mesh.colors.empty();
    out << "# dqjulia " << DQJ_VERSION_STRING << ": " << mesh.positions.size() << " vertices, "
        << mesh.triangles.size() + mesh.quads.size() << " faces"
        << (colors ? "; vertex colours (sRGB) after x y z" : "") << "\n";
    char line[160];
    for (std::size_t index = 0; index < mesh.positions.size(); ++index) {
        const glm::vec3& p = mesh.positions[index];
        if (colors) {
            const glm::vec3& c = mesh.colors[index];
            std::snprintf(line, sizeof line, "v %.7g %.7g %.7g %.4f %.4f %.4f\n", p.x, p.y, p.z,
                          linearToSrgb8(c.x) / 255.0, linearToSrgb8(c.y) / 255.0, linearToSrgb8(c.z) / 255.0);
        } else {
            std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", p.x, p.y, p.z);
        }
        out << line;
    }
    for (const glm::vec3& n : mesh.normals) {
        std::snprintf(line, sizeof line, "vn %.5f %.5f %.5f\n", n.x, n.y, n.z);
        out << line;
    }
    for (const auto& triangle : mesh.triangles) {  // OBJ counts from 1
        std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", triangle[0] + 1, triangle[0] + 1, triangle[1] + 1,
                      triangle[1] + 1, triangle[2] + 1, triangle[2] + 1);
        out << line;
    }
    for (const auto& quad : mesh.quads) {
        std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u %u//%u\n", quad[0] + 1, quad[0] + 1, quad[1] + 1,
                      quad[1] + 1, quad[2] + 1, quad[2] + 1, quad[3] + 1, quad[3] + 1);
        out << line;
    }
}

}  // namespace

std::vector<std::uint32_t> Mesh::triangulated() const {
    std::vector<std::uint32_t> indices;
    indices.reserve(3 * triangleCount());
    for (const auto& triangle : triangles) indices.insert(indices.end(), triangle.begin(), triangle.end());
    for (const auto& quad : quads) {
        indices.insert(indices.end(), {quad[0], quad[1], quad[2]});
        indices.insert(indices.end(), {quad[0], quad[2], quad[3]});
    }
    return indices;
}

Mesh bakeMesh(const Params& params, const BakeOptions& options, const ProgressCallback& progress, BakeStats* statsOut) {
    const auto start = std::chrono::steady_clock::now();
    validate(params);
    initializeOpenVdb();
    StagedProgress staged(progress, options.monitor);
    // The surface function itself is meshed: the bake's level set is the distance to this very
    // mesh (mesh_distance.hpp), so the mesh and the VDB hold the same surface.
    SampledSurface sampled = sampleSurface(params, options, meshMemoryModel(), staged, 0.05, 0.8);
    BakeStats stats = sampled.stats;

    // OpenVDB's mesher is used directly, not through volumeToMesh(): its point list and polygon
    // pools become the mesh's arrays, each freed once copied (after the grid), so the mesh is
    // never held twice.
    Mesh mesh;
    const double voxel = sampled.grid->voxelSize()[0];
    parallelForWithProgress(1, staged.stage(BakeStage::Meshing, 0.8, 0.9), [&](std::size_t, const std::atomic<bool>&) {
        openvdb::tools::VolumeToMesh mesher(0.0, params.bake.adaptivity);
        mesher(*sampled.grid);
        sampled.grid.reset();
        platform::releaseFreedMemory();
        const openvdb::Vec3s* points = mesher.pointList().get();
        mesh.positions.resize(mesher.pointListSize());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.positions.size()), [&](const auto& range) {
            for (std::size_t index = range.begin(); index < range.end(); ++index)
                mesh.positions[index] = glm::vec3(points[index].x(), points[index].y(), points[index].z());
        });
        mesher.pointList().reset();
        // Faces are counter-clockwise seen from the positive (outside) side. Each pool goes to
        // its place in the face arrays (pool order, as one after another), then is freed.
        const std::size_t pools = mesher.polygonPoolListSize();
        std::vector<std::size_t> quadsBefore(pools + 1, 0), trianglesBefore(pools + 1, 0);
        for (std::size_t pool = 0; pool < pools; ++pool) {
            quadsBefore[pool + 1] = quadsBefore[pool] + mesher.polygonPoolList()[pool].numQuads();
            trianglesBefore[pool + 1] = trianglesBefore[pool] + mesher.polygonPoolList()[pool].numTriangles();
        }
        mesh.quads.resize(quadsBefore[pools]);
        mesh.triangles.resize(trianglesBefore[pools]);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pools), [&](const auto& range) {
            for (std::size_t pool = range.begin(); pool < range.end(); ++pool) {
                openvdb::tools::PolygonPool& polygons = mesher.polygonPoolList()[pool];
                for (std::size_t index = 0; index < polygons.numQuads(); ++index) {
                    const openvdb::Vec4I& quad = polygons.quad(index);
                    mesh.quads[quadsBefore[pool] + index] = {quad[0], quad[1], quad[2], quad[3]};
                }
                for (std::size_t index = 0; index < polygons.numTriangles(); ++index) {
                    const openvdb::Vec3I& triangle = polygons.triangle(index);
                    mesh.triangles[trianglesBefore[pool] + index] = {triangle[0], triangle[1], triangle[2]};
                }
                polygons.clearQuads();
                polygons.clearTriangles();
            }
        });
    });
    removeDegenerateFaces(mesh);
    mesh.normals = vertexNormals(mesh);

    // Colours: the material's colouring of the orbit at each vertex (orbitColour, coloring.hpp), as
    // the renderer's, taken kSurfaceColourOffset voxels outside along the vertex normal.
    if (params.bake.meshColors) {
        mesh.colors.resize(mesh.positions.size());
        const Slice slice = params.slice.effective();
        const std::size_t tasks = (mesh.positions.size() + kVerticesPerTask - 1) / kVerticesPerTask;
        ThreadScratch<BatchBuffer<double>> batches;  // a task's vertices through the SIMD kernel together
        parallelForWithProgress(
            tasks, staged.stage(BakeStage::Meshing, 0.9, 1.0), [&](std::size_t task, const std::atomic<bool>&) {
                const std::size_t first = task * kVerticesPerTask;
                const std::size_t end = std::min(mesh.positions.size(), (task + 1) * kVerticesPerTask);
                BatchBuffer<double>& batch = batches.local();
                batch.clear();
                for (std::size_t index = first; index < end; ++index)
                    batch.add(slice.map(glm::dvec3(mesh.positions[index]) +
                                        kSurfaceColourOffset * voxel * glm::dvec3(mesh.normals[index])));
                batch.evaluate(params.fractal);
                for (std::size_t index = first; index < end; ++index)
                    mesh.colors[index] =
                        glm::vec3(orbitColour(params.material, params.fractal, batch.escape(index - first)));
            });
        stats.evaluated += mesh.positions.size();
    } else if (progress && !progress(1.0)) {
        throw Cancelled();
    }
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (statsOut) *statsOut = stats;
    return mesh;
}

void writeMesh(const Mesh& mesh, const std::string& path, Existing existing) {
    const std::string extension = AtomicFile::lowercaseExtension(path);
    if (extension != ".ply" && extension != ".obj")
        throw ParamError("output.path", "'" + inputExcerpt(path) + "' must end in .ply or .obj");
    AtomicFile file(path, existing);
    if (extension == ".ply")
        writePly(mesh, file.stream());
    else
        writeObj(mesh, file.stream());
    file.commit();
}

}  // namespace dqj
