// Whether a mesh can be printed (print_check.hpp): edges, islands, the thinnest wall.
#include "bake/print_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "bake/level_set.hpp"
#include "bake/mesh_stream.hpp"
#include "bake/sparse_sampler.hpp"
#include "bake/mesh_file.hpp"
#include "files/atomic_file.hpp"

namespace dqj {
namespace {

/// Calls `visit(corners, count)` for each face, triangles first.
template <typename Visit>
void forEachFace(const Mesh& mesh, Visit visit) {
    for (const auto& triangle : mesh.triangles) visit(triangle.data(), 3);
    for (const auto& quad : mesh.quads) visit(quad.data(), 4);
}

/// Union-find over the vertices, with path halving.
struct VertexSets {
    std::vector<std::uint32_t> parent;
    explicit VertexSets(std::size_t size) : parent(size) { std::iota(parent.begin(), parent.end(), 0u); }
    std::uint32_t find(std::uint32_t vertex) {
        while (parent[vertex] != vertex) vertex = parent[vertex] = parent[parent[vertex]];
        return vertex;
    }
    void join(std::uint32_t a, std::uint32_t b) {
        a = find(a), b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

/// The faces of each island (`labels` from vertexIslands).
std::vector<std::uint64_t> islandFaces(const Mesh& mesh, const std::vector<std::uint32_t>& labels,
                                       std::uint32_t count) {
    std::vector<std::uint64_t> faces(count, 0);
    forEachFace(mesh, [&](const std::uint32_t* corners, int) { ++faces[labels[corners[0]]]; });
    return faces;
}

/// Appends the edges of `mesh`'s faces, one key a face side: lesser vertex << 32 | greater.
void appendEdges(const Mesh& mesh, std::vector<std::uint64_t>& edges) {
    edges.reserve(edges.size() + 3 * mesh.triangles.size() + 4 * mesh.quads.size());
    forEachFace(mesh, [&](const std::uint32_t* corners, int count) {
        for (int corner = 0; corner < count; ++corner) {
            const std::uint64_t a = corners[corner], b = corners[(corner + 1) % count];
            edges.push_back(std::min(a, b) << 32 | std::max(a, b));
        }
    });
}

/// Sorts `edges` and calls visit(key, faces) for each distinct edge, with the faces it is in.
template <typename Visit>
void forEachEdge(std::vector<std::uint64_t>& edges, Visit visit) {
    tbb::parallel_sort(edges.begin(), edges.end());
    for (std::size_t first = 0; first < edges.size();) {
        std::size_t end = first + 1;
        while (end < edges.size() && edges[end] == edges[first]) ++end;
        visit(edges[first], end - first);
        first = end;
    }
}

/// Counts an edge in `faces` faces into the report.
void countEdge(std::size_t faces, PrintReport& report) {
    ++report.edges;
    if (faces == 1) ++report.boundaryEdges;
    if (faces > 2) ++report.nonManifoldEdges;
}

/// Counts the edges and marks the islands with a boundary edge open.
void checkEdges(const Mesh& mesh, const std::vector<std::uint32_t>& labels, std::vector<bool>& open,
                PrintReport& report) {
    std::vector<std::uint64_t> edges;
    appendEdges(mesh, edges);
    forEachEdge(edges, [&](std::uint64_t edge, std::size_t faces) {
        countEdge(faces, report);
        if (faces == 1) open[labels[std::uint32_t(edge >> 32)]] = true;
    });
}

/// The mesh for meshToVolume (its MeshDataAdapter): triangles, then quads, in index space.
struct VoxelMesh {
    const Mesh& mesh;
    double perVoxel;  // index units per mesh unit
    std::size_t polygonCount() const { return mesh.triangles.size() + mesh.quads.size(); }
    std::size_t pointCount() const { return mesh.positions.size(); }
    std::size_t vertexCount(std::size_t polygon) const { return polygon < mesh.triangles.size() ? 3 : 4; }
    void getIndexSpacePoint(std::size_t polygon, std::size_t corner, openvdb::Vec3d& position) const {
        const std::size_t triangles = mesh.triangles.size();
        const std::uint32_t vertex =
            polygon < triangles ? mesh.triangles[polygon][corner] : mesh.quads[polygon - triangles][corner];
        const glm::vec3& p = mesh.positions[vertex];
        position = openvdb::Vec3d(p.x, p.y, p.z) * perVoxel;
    }
};

/// The thinnest wall under `limit` voxels, in mesh units (+infinity when none is), and where:
/// from each face's centre along its inward normal to where the distance field turns positive
/// (print_check.hpp).
double thinnestWall(const Mesh& mesh, double voxel, double limit, glm::dvec3& where) {
    initializeOpenVdb();
    // Deeper inside than the band, the field holds -band voxels: still a step that cannot pass
    // the far side, so a narrow band serves walls of any thickness (a few steps more).
    const float band = 2.0f;
    const auto transform = openvdb::math::Transform::createLinearTransform(voxel);
    const openvdb::FloatGrid::Ptr grid =
        openvdb::tools::meshToVolume<openvdb::FloatGrid>(VoxelMesh{mesh, 1.0 / voxel}, *transform, 1.0f, band);
    const double longest = limit * voxel, least = voxel / 4.0;
    struct Thinnest {
        double wall = std::numeric_limits<double>::infinity();
        glm::dvec3 at{0.0};
    };
    tbb::combinable<Thinnest> thinnest;
    const std::size_t triangles = mesh.triangles.size(), faces = triangles + mesh.quads.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces), [&](const auto& range) {
        const openvdb::FloatGrid::ConstAccessor access = grid->getConstAccessor();
        const openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> field(
            access, grid->transform());
        auto distance = [&](const glm::dvec3& p) { return double(field.wsSample(openvdb::Vec3d(p.x, p.y, p.z))); };
        Thinnest& local = thinnest.local();
        for (std::size_t face = range.begin(); face < range.end(); ++face) {
            const std::uint32_t* corners =
                face < triangles ? mesh.triangles[face].data() : mesh.quads[face - triangles].data();
            const int count = face < triangles ? 3 : 4;
            glm::dvec3 p[4], centre(0.0);
            for (int corner = 0; corner < count; ++corner)
                centre += p[corner] = glm::dvec3(mesh.positions[corners[corner]]);
            centre /= double(count);
            const glm::dvec3 normal =
                count == 3 ? glm::cross(p[1] - p[0], p[2] - p[0]) : glm::cross(p[2] - p[0], p[3] - p[1]);
            if (glm::length(normal) == 0.0) continue;
            const glm::dvec3 inward = -glm::normalize(normal);
            // Inside, the distance to the nearest face is a step that cannot pass the far side.
            double before = 0.0;
            for (double along = least; along < std::min(longest, local.wall);) {
                const double d = distance(centre + along * inward);
                if (d > 0.0) {
                    for (int halving = 0; halving < 10; ++halving) {
                        const double middle = (before + along) / 2.0;
                        (distance(centre + middle * inward) > 0.0 ? along : before) = middle;
                    }
                    const double wall = (before + along) / 2.0;
                    if (wall < local.wall) local = {wall, centre + wall / 2.0 * inward};
                    break;
                }
                before = along;
                along += std::max(-d, least);
            }
        }
    });
    const Thinnest result =
        thinnest.combine([](const Thinnest& a, const Thinnest& b) { return a.wall <= b.wall ? a : b; });
    where = result.at;
    return result.wall;
}

std::string number(double value) {
    std::ostringstream text;
    text.precision(4);
    text << value;
    return text.str();
}

}  // namespace

bool isPrintFormat(const std::string& path) {
    const std::string extension = AtomicFile::lowercaseExtension(path);
    return extension == ".stl" || extension == ".3mf";
}

std::vector<std::uint32_t> vertexIslands(const Mesh& mesh, std::uint32_t& count) {
    VertexSets sets(mesh.positions.size());
    forEachFace(mesh, [&](const std::uint32_t* corners, int size) {
        for (int corner = 1; corner < size; ++corner) sets.join(corners[0], corners[corner]);
    });
    // A root is its set's least vertex, so it comes before the rest: numbered in vertex order.
    std::vector<std::uint32_t> labels(mesh.positions.size());
    count = 0;
    for (std::size_t vertex = 0; vertex < labels.size(); ++vertex) {
        const std::uint32_t root = sets.find(std::uint32_t(vertex));
        labels[vertex] = root == vertex ? count++ : labels[root];
    }
    return labels;
}

void dropIslands(Mesh& mesh, const PrintOptions& options, PrintReport& report) {
    if (options.minIslandFaces == 0 && !options.largestOnly) return;
    std::uint32_t count = 0;
    const std::vector<std::uint32_t> labels = vertexIslands(mesh, count);
    const std::vector<std::uint64_t> faces = islandFaces(mesh, labels, count);
    const auto largest = std::max_element(faces.begin(), faces.end());
    std::vector<bool> keep(count);
    for (std::uint32_t island = 0; island < count; ++island) {
        keep[island] = faces[island] > 0 && faces[island] >= options.minIslandFaces &&
                       (!options.largestOnly || faces.begin() + island == largest);
        if (!keep[island] && faces[island] > 0) {
            ++report.droppedIslands;
            report.droppedFaces += faces[island];
        }
    }
    if (largest != faces.end() && *largest > 0 && !keep[std::size_t(largest - faces.begin())])
        throw ParamError("min_island", "--min-island " + std::to_string(options.minIslandFaces) +
                                           " drops every island: the largest has " + std::to_string(*largest) +
                                           " faces");
    // The kept vertices, renumbered in their order; then the kept faces.
    std::vector<std::uint32_t> renumbered(mesh.positions.size(), UINT32_MAX);
    std::uint32_t next = 0;
    for (std::size_t vertex = 0; vertex < mesh.positions.size(); ++vertex) {
        if (!keep[labels[vertex]]) continue;
        renumbered[vertex] = next;
        mesh.positions[next] = mesh.positions[vertex];
        if (!mesh.normals.empty()) mesh.normals[next] = mesh.normals[vertex];
        if (!mesh.colors.empty()) mesh.colors[next] = mesh.colors[vertex];
        ++next;
    }
    mesh.positions.resize(next);
    if (!mesh.normals.empty()) mesh.normals.resize(next);
    if (!mesh.colors.empty()) mesh.colors.resize(next);
    auto keptFaces = [&](auto& list) {
        std::size_t kept = 0;
        for (const auto& face : list) {
            if (!keep[labels[face[0]]]) continue;
            auto& to = list[kept++];
            for (std::size_t corner = 0; corner < face.size(); ++corner) to[corner] = renumbered[face[corner]];
        }
        list.resize(kept);
    };
    keptFaces(mesh.triangles);
    keptFaces(mesh.quads);
}

void checkPrint(const Mesh& mesh, const PrintOptions& options, PrintReport& report, const ProgressCallback& progress) {
    auto step = [&](double fraction) {
        if (progress && !progress(fraction)) throw Cancelled();
    };
    report.minWall = options.minWall;
    report.islandsCounted = true;
    report.faces = mesh.quads.size() + mesh.triangles.size();
    std::uint32_t count = 0;
    const std::vector<std::uint32_t> labels = vertexIslands(mesh, count);
    const std::vector<std::uint64_t> faces = islandFaces(mesh, labels, count);
    std::vector<bool> open(count, false);
    step(0.1);
    checkEdges(mesh, labels, open, report);
    step(0.3);

    // Each island's box (output units), then its volume about its box's corner (for precision).
    const double scale = options.scale;
    std::vector<PrintIsland> islands(count);
    std::vector<bool> seen(count, false);
    for (std::size_t vertex = 0; vertex < mesh.positions.size(); ++vertex) {
        const glm::dvec3 p = (glm::dvec3(mesh.positions[vertex]) - options.origin) * scale;
        PrintIsland& island = islands[labels[vertex]];
        island.min = seen[labels[vertex]] ? glm::min(island.min, p) : p;
        island.max = seen[labels[vertex]] ? glm::max(island.max, p) : p;
        seen[labels[vertex]] = true;
    }
    forEachFace(mesh, [&](const std::uint32_t* corners, int size) {
        PrintIsland& island = islands[labels[corners[0]]];
        auto placed = [&](std::uint32_t vertex) {
            return (glm::dvec3(mesh.positions[vertex]) - options.origin) * scale - island.min;
        };
        const glm::dvec3 a = placed(corners[0]);
        for (int corner = 1; corner + 1 < size; ++corner) {
            const glm::dvec3 b = placed(corners[corner]), c = placed(corners[corner + 1]);
            island.volume += glm::dot(a, glm::cross(b, c)) / 6.0;
        }
    });
    report.islands.clear();
    for (std::uint32_t island = 0; island < count; ++island) {
        if (faces[island] == 0) continue;  // a vertex no face uses
        islands[island].faces = faces[island];
        islands[island].closed = !open[island];
        if (open[island]) islands[island].volume = 0.0;
        report.islands.push_back(islands[island]);
    }
    std::stable_sort(report.islands.begin(), report.islands.end(),
                     [](const PrintIsland& a, const PrintIsland& b) { return a.faces > b.faces; });
    step(0.4);

    if (options.voxel > 0.0 && !report.islands.empty()) {
        const double limit = std::clamp(options.minWall / scale / options.voxel + 2.0, kDefaultWallVoxels, 256.0);
        glm::dvec3 where(0.0);
        const double wall = thinnestWall(mesh, options.voxel, limit, where);
        report.wallMeasured = true;
        report.thinnestWallAt = (where - options.origin) * scale;
        report.wallLimit = limit * options.voxel * scale;
        report.wallFound = std::isfinite(wall);
        report.thinnestWall = report.wallFound ? wall * scale : report.wallLimit;
    }
    step(1.0);
}

std::string PrintReport::failure() const {
    std::vector<std::string> reasons;
    if (faces == 0) reasons.emplace_back("the mesh has no faces");
    if (!closed()) reasons.push_back("it is not closed: " + std::to_string(boundaryEdges) + " boundary edges (holes)");
    if (!manifold())
        reasons.push_back("it is not edge-manifold: " + std::to_string(nonManifoldEdges) +
                          " edges in more than two faces");
    if (minWall > 0.0 && wallMeasured && wallFound && thinnestWall < minWall)
        reasons.push_back("its thinnest wall, " + number(thinnestWall) + ", is under --min-wall " + number(minWall));
    std::string text;
    for (const std::string& reason : reasons) text += (text.empty() ? "" : "; ") + reason;
    return text;
}

std::string printReportText(const PrintReport& report) {
    std::ostringstream text;
    std::uint64_t faces = 0;
    for (const PrintIsland& island : report.islands) faces += island.faces;
    text << "print check: "
         << (report.closed() ? "closed" : "not closed (" + std::to_string(report.boundaryEdges) + " boundary edges)")
         << ", "
         << (report.manifold()
                 ? "edge-manifold"
                 : "not edge-manifold (" + std::to_string(report.nonManifoldEdges) + " edges in more than two faces)")
         << "; ";
    if (!report.islandsCounted) {  // EdgeTally's report
        text << report.faces << " faces (islands and walls are measured with --min-island, --largest-only or "
             << "--min-wall)\n";
        return text.str();
    }
    text << report.islands.size() << (report.islands.size() == 1 ? " island" : " islands") << ", " << faces << " faces";
    if (report.droppedIslands > 0)
        text << " (" << report.droppedIslands << " dropped, " << report.droppedFaces << " faces)";
    text << "\n";
    constexpr std::size_t kShown = 5;
    for (std::size_t index = 0; index < std::min(kShown, report.islands.size()); ++index) {
        const PrintIsland& island = report.islands[index];
        const glm::dvec3 size = island.max - island.min;
        text << "  island " << index + 1 << ": " << island.faces << " faces, " << number(size.x) << " x "
             << number(size.y) << " x " << number(size.z);
        if (island.closed)
            text << ", volume " << number(island.volume);
        else
            text << ", open";
        text << "\n";
    }
    if (report.islands.size() > kShown) {
        std::uint64_t rest = 0;
        for (std::size_t index = kShown; index < report.islands.size(); ++index) rest += report.islands[index].faces;
        text << "  and " << report.islands.size() - kShown << " smaller islands, " << rest << " faces\n";
    }
    if (report.wallMeasured) {
        text << "  thinnest wall: "
             << (report.wallFound ? number(report.thinnestWall) + " at (" + number(report.thinnestWallAt.x) + ", " +
                                        number(report.thinnestWallAt.y) + ", " + number(report.thinnestWallAt.z) + ")"
                                  : "none under " + number(report.wallLimit));
        if (report.minWall > 0.0)
            text << " (--min-wall " << number(report.minWall)
                 << (report.wallFound && report.thinnestWall < report.minWall ? ": too thin)" : ": passes)");
        text << "\n";
    }
    return text.str();
}

void EdgeTally::add(const Mesh& part) {
    const std::uint64_t first = vertices_;  // this part's first vertex
    vertices_ += part.positions.size();
    appendEdges(part, open_);
    // The next part's faces name only its own vertices and this part's (mesh_stream.hpp): an
    // edge with a vertex before this part has all its faces now.
    std::vector<std::uint64_t> still;
    forEachEdge(open_, [&](std::uint64_t edge, std::size_t faces) {
        if (edge >> 32 >= first)
            still.insert(still.end(), faces, edge);
        else
            countEdge(faces, report_);
    });
    open_ = std::move(still);
    report_.faces += part.quads.size() + part.triangles.size();
}

const PrintReport& EdgeTally::finish() {
    forEachEdge(open_, [&](std::uint64_t, std::size_t faces) { countEdge(faces, report_); });
    open_ = {};
    return report_;
}

MeshCounts bakeMeshFileChecked(const Params& params, const std::string& path, const BakeOptions& options,
                               const ProgressCallback& progress, BakeStats* statsOut, const MeshScale& scale,
                               const std::function<void(const PrintReport&)>& approve) {
    validate(params);
    MeshFile file(path, params.bake.meshColors, options.existing, scale);  // fails now, before the work
    EdgeTally edges;
    BakeStats stats;
    meshSurface(
        params, options, progress,
        [&](Mesh&& part) {
            if (approve) edges.add(part);
            file.add(part);
        },
        stats);
    if (progress && !progress(1.0)) throw Cancelled();  // a signal in the last moments: publish nothing
    if (approve) approve(edges.finish());               // may throw: nothing is published
    file.commit();
    if (statsOut) *statsOut = stats;
    return file.counts();
}

Mesh meshForPrint(const Params& params, const BakeOptions& options, PrintOptions print,
                  const ProgressCallback& progress, BakeStats& stats, PrintReport& report, const MeshScale& scale) {
    validate(params);
    checkMeshScale(scale);
    auto within = [&progress](double begin, double end) -> ProgressCallback {
        if (!progress) return {};
        return [&progress, begin, end](double fraction) { return progress(begin + fraction * (end - begin)); };
    };
    Mesh mesh;
    try {
        meshSurface(
            params, options, within(0.0, 0.85), [&mesh](Mesh&& part) { mesh = std::move(part); }, stats, kOnePieceOnly);
    } catch (const MemoryLimitError& error) {
        std::string message = error.what();
        const std::string prefix = "bake.resolution: ";
        if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
        throw MemoryLimitError(message +
                                   " (the print check, for .stl and .3mf and with --min-wall, --min-island or "
                                   "--largest-only, needs the mesh in one piece: it is not made slab by slab yet)",
                               error.estimate(), error.limit());
    }
    if (print.voxel <= 0.0) print.voxel = bakeVoxelSize(params);
    dropIslands(mesh, print, report);
    if (scale.size && !mesh.positions.empty()) {  // as MeshFile places it
        glm::dvec3 least(mesh.positions[0]), most(mesh.positions[0]);
        for (const glm::vec3& p : mesh.positions)
            least = glm::min(least, glm::dvec3(p)), most = glm::max(most, glm::dvec3(p));
        const MeshPlacement placement = meshPlacement(scale, least, most);
        print.scale = placement.factor, print.origin = placement.origin;
    }
    checkPrint(mesh, print, report, within(0.85, 1.0));
    return mesh;
}

}  // namespace dqj
