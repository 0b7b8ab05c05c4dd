// The one mesher (mesh_stream.hpp): in one piece where the limit allows, else slab by slab.
#include "bake/mesh_stream.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dqjulia/batch.hpp"
#include "dqjulia/coloring.hpp"
#include "bake/grid_mesher.hpp"
#include "bake/level_set.hpp"
#include "bake/memory.hpp"
#include "bake/mesh_simplify.hpp"
#include "bake/sparse_sampler.hpp"
#include "platform/parallel_progress.hpp"
#include "platform/platform.hpp"
#include "platform/thread_scratch.hpp"

namespace dqj {
namespace {

constexpr std::size_t kVerticesPerTask = 4096;
constexpr int kLayer = 8;  // voxels: slabs are whole leaves thick
constexpr std::uint32_t kNoVertex = UINT32_MAX;

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

/// OpenVDB's mesher (grid_mesher.hpp: the grid let go once read): its point list and polygon
/// pools become the mesh's arrays, each freed once copied, so the mesh is never held twice.
/// Faces are counter-clockwise seen from the positive (outside) side.
Mesh meshOfGrid(openvdb::FloatGrid::Ptr& grid, double adaptivity, const ProgressCallback& progress) {
    Mesh mesh;
    parallelForWithProgress(1, progress, [&](std::size_t, const std::atomic<bool>&) {
        GridMesh mesher = meshGrid(grid, adaptivity);
        platform::releaseFreedMemory();
        const openvdb::Vec3s* points = mesher.points.get();
        mesh.positions.resize(mesher.pointCount);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.positions.size()), [&](const auto& range) {
            for (std::size_t index = range.begin(); index < range.end(); ++index)
                mesh.positions[index] = glm::vec3(points[index].x(), points[index].y(), points[index].z());
        });
        mesher.points.reset();
        // Each pool goes to its place in the face arrays (pool order, as one after another), then is freed.
        const std::size_t pools = mesher.poolCount;
        std::vector<std::size_t> quadsBefore(pools + 1, 0), trianglesBefore(pools + 1, 0);
        for (std::size_t pool = 0; pool < pools; ++pool) {
            quadsBefore[pool + 1] = quadsBefore[pool] + mesher.pools[pool].numQuads();
            trianglesBefore[pool + 1] = trianglesBefore[pool] + mesher.pools[pool].numTriangles();
        }
        mesh.quads.resize(quadsBefore[pools]);
        mesh.triangles.resize(trianglesBefore[pools]);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pools), [&](const auto& range) {
            for (std::size_t pool = range.begin(); pool < range.end(); ++pool) {
                openvdb::tools::PolygonPool& polygons = mesher.pools[pool];
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
    return mesh;
}

/// Colours: the material's colouring of the orbit at each vertex (orbitColour, coloring.hpp), as
/// the renderer's, taken kSurfaceColourOffset voxels outside along the vertex normal.
void addColours(const Params& params, double voxel, Mesh& mesh, const ProgressCallback& progress, BakeStats& stats) {
    mesh.colors.resize(mesh.positions.size());
    const Slice slice = params.slice.effective();
    const std::size_t tasks = (mesh.positions.size() + kVerticesPerTask - 1) / kVerticesPerTask;
    ThreadScratch<BatchBuffer<double>> batches;  // a task's vertices through the SIMD kernel together
    parallelForWithProgress(tasks, progress, [&](std::size_t task, const std::atomic<bool>&) {
        const std::size_t first = task * kVerticesPerTask;
        const std::size_t end = std::min(mesh.positions.size(), (task + 1) * kVerticesPerTask);
        BatchBuffer<double>& batch = batches.local();
        batch.clear();
        for (std::size_t index = first; index < end; ++index)
            batch.add(slice.map(glm::dvec3(mesh.positions[index]) +
                                kSurfaceColourOffset * voxel * glm::dvec3(mesh.normals[index])));
        batch.evaluate(params.fractal);
        for (std::size_t index = first; index < end; ++index)
            mesh.colors[index] = glm::vec3(orbitColour(params.material, params.fractal, batch.escape(index - first)));
    });
    stats.evaluated += mesh.positions.size();
}

/// A vertex by its position's bits: slabs compute a vertex they share from the same values, so
/// to the same bits.
struct PositionKey {
    std::uint32_t bits[3];
    bool operator==(const PositionKey&) const = default;
};
struct PositionHash {
    std::size_t operator()(const PositionKey& key) const {
        std::uint64_t hash = 14695981039346656037ull;
        for (const std::uint32_t word : key.bits) hash = (hash ^ word) * 1099511628211ull;
        return std::size_t(hash ^ (hash >> 29));
    }
};
PositionKey keyOf(const glm::vec3& p) {
    PositionKey key;
    std::memcpy(key.bits, &p, sizeof key.bits);
    return key;
}
/// The vertices one slab handed on that the next may use: position -> number in the whole mesh.
using Seam = std::unordered_map<PositionKey, std::uint32_t, PositionHash>;

/// What slab [lo, hi) owns of its local mesh: the faces whose least vertex x lies in it, their
/// vertices renumbered into the whole mesh (those in `seam` keep their numbers, the others are
/// new, from `firstVertex`, with their normals). `seam` becomes the vertices at x >= hi.
Mesh ownedPart(const Mesh& local, double lo, double hi, std::uint64_t firstVertex, Seam& seam) {
    Mesh part;
    std::vector<std::uint32_t> global(local.positions.size(), kNoVertex);
    auto number = [&](std::uint32_t vertex) {
        std::uint32_t& index = global[vertex];
        if (index != kNoVertex) return index;
        const auto known = seam.find(keyOf(local.positions[vertex]));
        if (known != seam.end()) return index = known->second;
        index = std::uint32_t(firstVertex + part.positions.size());
        part.positions.push_back(local.positions[vertex]);
        part.normals.push_back(local.normals[vertex]);
        return index;
    };
    auto owned = [&](const auto& face) {
        float x = std::numeric_limits<float>::infinity();
        for (const std::uint32_t vertex : face) x = std::min(x, local.positions[vertex].x);
        return double(x) >= lo && double(x) < hi;
    };
    for (const auto& triangle : local.triangles)
        if (owned(triangle)) part.triangles.push_back({number(triangle[0]), number(triangle[1]), number(triangle[2])});
    for (const auto& quad : local.quads)
        if (owned(quad)) part.quads.push_back({number(quad[0]), number(quad[1]), number(quad[2]), number(quad[3])});
    Seam next;
    for (std::size_t vertex = 0; vertex < local.positions.size(); ++vertex)
        if (global[vertex] != kNoVertex && double(local.positions[vertex].x) >= hi)
            next.emplace(keyOf(local.positions[vertex]), global[vertex]);
    seam = std::move(next);
    return part;
}

/// A slab: layers [first, end) of the bake's leaf layers along x (LeafLayers numbering).
struct Slab {
    std::size_t first = 0, end = 0;
    double share = 0.0;  // of the work, for progress
};

/// The estimate of sampling and meshing slab [first, end) with its halo (slabLeaves,
/// sparse_sampler.hpp: it bounds the sampler's first wave).
std::uint64_t slabEstimate(const LeafLayers& layers, std::size_t first, std::size_t end, bool dense) {
    return samplingEstimate(meshMemoryModel(), slabLeaves(layers, first, end, kSlabHalo / kLayer), dense);
}

/// The refusal of a resolution whose thinnest slab at `layer` (one layer and its halo) needs
/// `estimate`, more than the limit.
MemoryLimitError thinnestSlabError(const Params& params, const LeafLayers& layers, std::size_t layer,
                                   const SamplingLimit& limit, std::uint64_t estimate) {
    const int x = (layers.first + int(layer)) * kLayer;
    return MemoryLimitError("resolution " + std::to_string(params.bake.resolution) + " does not fit the limit of " +
                                limit.text() + " even meshed slab by slab: the thinnest slab, the " +
                                std::to_string(kLayer) + " voxels from x = " + std::to_string(x) + " with " +
                                std::to_string(kSlabHalo) + " more on either side, needs an estimated " +
                                formatBytes(estimate) + " or more" + limit.advice(),
                            estimate, limit.bytes);
}

/// Refuses when the thinnest slab at `layer` exceeds the limit (with layers not counted yet as
/// 0, the estimate only grows as they are).
void checkThinnestSlab(const Params& params, const LeafLayers& layers, std::size_t layer, const SamplingLimit& limit,
                       bool dense) {
    const std::uint64_t thinnest = slabEstimate(layers, layer, layer + 1, dense);
    if (thinnest > limit.bytes) throw thinnestSlabError(params, layers, layer, limit, thinnest);
}

/// The slabs, each as many layers as the limit allows; refuses a layer that cannot fit alone.
std::vector<Slab> planSlabs(const Params& params, const LeafLayers& layers, const SamplingLimit& limit, bool dense) {
    std::vector<Slab> slabs;
    std::uint64_t total = 0;
    for (std::size_t first = 0; first < layers.sampled.size();) {
        std::size_t end = first + 1;
        checkThinnestSlab(params, layers, first, limit, dense);
        while (end < layers.sampled.size() && slabEstimate(layers, first, end + 1, dense) <= limit.bytes) ++end;
        Slab slab{first, end, 0.0};
        for (std::size_t layer = first; layer < end; ++layer) slab.share += double(layers.sampled[layer]);
        total += std::uint64_t(slab.share);
        slabs.push_back(slab);
        first = end;
    }
    for (Slab& slab : slabs) slab.share = total ? slab.share / double(total) : 1.0 / double(slabs.size());
    return slabs;
}

/// Slabs of a given thickness (tests).
std::vector<Slab> evenSlabs(const LeafLayers& layers, int slabVoxels) {
    const std::size_t step = std::size_t(std::max(1, slabVoxels / kLayer));
    std::vector<Slab> slabs;
    for (std::size_t first = 0; first < layers.sampled.size(); first += step)
        slabs.push_back({first, std::min(layers.sampled.size(), first + step), 0.0});
    for (Slab& slab : slabs) slab.share = 1.0 / double(slabs.size());
    return slabs;
}

/// Why `params` are meshed in one piece only, as a note for a refusal; "" when slabs may do.
std::string onePieceReason(const Params& params) {
    if (params.bake.maxFaces > 0)
        return " (a mesh with bake.max_faces, --faces, is simplified in one piece: lower the resolution, or mesh "
               "without it, slab by slab)";
    if (params.bake.adaptivity > 0.0)
        return " (a mesh with bake.adaptivity above 0 is made in one piece, since its merged cells cross slabs: "
               "with adaptivity 0 it would be meshed slab by slab)";
    return "";
}

/// Refuses when planning the slabs alone (the classification by layer) exceeds the limit.
void checkPlanFits(const Params& params, const SamplingLimit& limit, bool dense) {
    const std::uint64_t planBytes = samplingEstimate(meshMemoryModel(), 0, dense) + countLeafLayersBytes(params);
    if (planBytes > limit.bytes)
        throw MemoryLimitError("resolution " + std::to_string(params.bake.resolution) + " does not fit the limit of " +
                                   limit.text() + " even meshed slab by slab: planning the slabs alone may take " +
                                   formatBytes(planBytes) + limit.advice(),
                               planBytes, limit.bytes);
}

void addStats(BakeStats& total, const BakeStats& slab) {
    total.evaluated += slab.evaluated;
    total.sampledLeaves += slab.sampledLeaves;
    total.interiorLeaves += slab.interiorLeaves;
    total.prunedLeaves += slab.prunedLeaves;
    total.estimatedBytes = std::max(total.estimatedBytes, slab.estimatedBytes);
    total.voxelSize = slab.voxelSize;
}

}  // namespace

void meshSurface(const Params& params, const BakeOptions& options, const ProgressCallback& progress,
                 const MeshPartSink& sink, BakeStats& stats, int slabVoxels) {
    const auto start = std::chrono::steady_clock::now();
    initializeOpenVdb();
    // One fraction that only grows, over the attempt in one piece, the plan and the slabs.
    double last = 0.0;
    auto within = [&](double begin, double end) -> ProgressCallback {
        if (!progress) return {};
        return [&progress, &last, begin, end](double fraction) {
            last = std::max(last, begin + std::clamp(fraction, 0.0, 1.0) * (end - begin));
            return progress(last);
        };
    };
    const double voxel = bakeVoxelSize(params);
    stats = BakeStats{};
    auto finish = [&] {
        stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };

    if (slabVoxels <= 0) {
        // In one piece, as long as the sampler does not refuse it for the limit (before sampling).
        try {
            StagedProgress staged(within(0.0, 1.0), options.monitor);
            SampledSurface sampled = sampleSurface(params, options, meshMemoryModel(), staged, 0.05, 0.8);
            stats = sampled.stats;
            Mesh mesh;
            if (params.bake.maxFaces > 0) {
                // The grid kept for every try (meshOfGrid lets go of its own pointer only).
                SimplifiedMesh simplified = simplifyToFaces(
                    std::uint64_t(params.bake.maxFaces), voxel,
                    [&sampled](double adaptivity) {
                        openvdb::FloatGrid::Ptr grid = sampled.grid;
                        return meshOfGrid(grid, adaptivity, {});
                    },
                    staged.stage(BakeStage::Meshing, 0.8, 0.9));
                sampled.grid.reset();
                mesh = std::move(simplified.mesh);
                stats.adaptivity = simplified.adaptivity;
                stats.fullTriangles = simplified.fullTriangles;
                stats.deviationVertices = simplified.deviation.vertices;
                stats.deviationSamples = simplified.deviation.samples;
            } else {
                mesh = meshOfGrid(sampled.grid, params.bake.adaptivity, staged.stage(BakeStage::Meshing, 0.8, 0.9));
            }
            if (params.bake.meshColors)
                addColours(params, voxel, mesh, staged.stage(BakeStage::Meshing, 0.9, 1.0), stats);
            stats.slabs = 1;
            sink(std::move(mesh));
            finish();
            return;
        } catch (const MemoryLimitError& error) {
            if (slabVoxels == kOnePieceOnly) throw;
            const std::string prefix = "bake.resolution: ";
            std::string message = error.what();
            if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
            if (const std::string why = onePieceReason(params); !why.empty())
                throw MemoryLimitError(message + why, error.estimate(), error.limit());
            if (samplingEstimate(meshMemoryModel(), 0, options.dense) > error.limit()) throw;
        }
    } else if (params.bake.adaptivity > 0.0 || params.bake.maxFaces > 0) {
        throw ParamError("bake.adaptivity", "meshes in slabs need bake.adaptivity 0 and no bake.max_faces");
    }

    // Slab by slab: plan from the classification alone, refuse before sampling if a slab cannot
    // fit. The limit is fixed here, for the plan and every slab (the default, half the available
    // memory, moves as the machine's load does).
    const SamplingLimit limit = samplingMemoryLimit(options);
    LeafLayers layers;
    std::vector<Slab> slabs;
    if (slabVoxels > 0) {
        const openvdb::CoordBBox full = bakeIndexBox(params);
        layers.first = int(std::floor(double(full.min().x()) / kLayer));
        const int lastLayer = int(std::floor(double(full.max().x()) / kLayer));
        layers.sampled.assign(std::size_t(lastLayer - layers.first) + 1, 0);
        slabs = evenSlabs(layers, slabVoxels);
    } else {
        StagedProgress planning(within(0.0, 0.05), options.monitor);
        checkPlanFits(params, limit, options.dense);
        // A layer too large even alone is refused as soon as its chunk is counted.
        const std::size_t halo = kSlabHalo / kLayer;
        layers = countLeafLayers(params, options, planning.stage(BakeStage::Classifying, 0.0, 1.0),
                                 [&](const LeafLayers& counted, std::size_t first, std::size_t end) {
                                     const std::size_t from = first >= halo ? first - halo : 0;
                                     const std::size_t to = std::min(counted.sampled.size(), end + halo);
                                     for (std::size_t layer = from; layer < to; ++layer)
                                         checkThinnestSlab(params, counted, layer, limit, options.dense);
                                 });
        slabs = planSlabs(params, layers, limit, options.dense);
        stats.evaluated += layers.evaluated;
    }
    const double planned = slabVoxels > 0 ? 0.0 : 0.05;

    const openvdb::CoordBBox full = bakeIndexBox(params);
    if (options.monitor) {
        options.monitor->slabs = std::uint32_t(slabs.size());
        options.monitor->dense = denseVoxels(params);
    }
    Seam seam;
    std::uint64_t vertices = 0;
    double begin = planned;
    // The slabs still to make, the next last. The plan bounds each slab's first wave (slabLeaves),
    // but a slab whose sampler still finds it over the limit (forced thicknesses; a count the plan
    // missed) is split in two, at run time, rather than refused: only a slab of one layer is.
    std::vector<Slab> pending(slabs.rbegin(), slabs.rend());
    std::size_t made = 0;
    while (!pending.empty()) {
        const Slab slab = pending.back();
        pending.pop_back();
        const double end = pending.empty() ? 1.0 : begin + slab.share * (1.0 - planned);
        if (options.monitor) options.monitor->slab = std::uint32_t(made + 1);
        StagedProgress staged(within(begin, end), options.monitor);
        // The slab's bounds, in voxels and in slice units (open outwards at the ends).
        const int x0 = (layers.first + int(slab.first)) * kLayer, x1 = (layers.first + int(slab.end)) * kLayer;
        const double lo = slab.first == 0 ? -std::numeric_limits<double>::infinity() : x0 * voxel;
        const double hi = slab.end == layers.sampled.size() ? std::numeric_limits<double>::infinity() : x1 * voxel;
        const openvdb::CoordBBox window(openvdb::Coord(x0 - kSlabHalo, full.min().y(), full.min().z()),
                                        openvdb::Coord(x1 + kSlabHalo - 1, full.max().y(), full.max().z()));
        SampledSurface sampled;
        try {
            sampled = sampleSurface(params, options, meshMemoryModel(), staged, 0.05, 0.8, &window, &limit);
        } catch (const MemoryLimitError& error) {
            if (slab.end - slab.first < 2) throw thinnestSlabError(params, layers, slab.first, limit, error.estimate());
            const std::size_t middle = slab.first + (slab.end - slab.first) / 2;
            pending.push_back({middle, slab.end, 0.5 * slab.share});
            pending.push_back({slab.first, middle, 0.5 * slab.share});
            if (options.monitor) options.monitor->slabs = std::uint32_t(made + pending.size());
            continue;
        }
        begin = end;
        addStats(stats, sampled.stats);
        Mesh local = meshOfGrid(sampled.grid, 0.0, staged.stage(BakeStage::Meshing, 0.8, 0.9));
        Mesh part = ownedPart(local, lo, hi, vertices, seam);
        local = Mesh{};
        if (params.bake.meshColors) addColours(params, voxel, part, staged.stage(BakeStage::Meshing, 0.9, 1.0), stats);
        vertices += part.positions.size();
        if (vertices > std::uint64_t(UINT32_MAX))
            throw std::runtime_error(
                "the mesh has more than 2^32 vertices, more than its 32-bit indices can name: "
                "lower the resolution or mesh a smaller region (bake.bounds)");
        sink(std::move(part));
        platform::releaseFreedMemory();
        ++made;
    }
    stats.slabs = made;
    stats.dense = denseVoxels(params);
    stats.voxelSize = voxel;
    finish();
}

/// Triangles (a quad counts as two) a mesh has per sampled leaf (all sampled, pruned ones too):
/// on the default fractal 36 at 128^3, 45 at 256^3, 47 at 512^3; on the ball 26, 31, 31.
constexpr double kTrianglesPerLeaf = 40.0;

MeshEstimate estimateMesh(const Params& params, const BakeOptions& options, const ProgressCallback& progress) {
    validate(params);
    initializeOpenVdb();
    const SamplingLimit limit = samplingMemoryLimit(options);
    checkPlanFits(params, limit, options.dense);
    StagedProgress staged(progress, options.monitor);
    const LeafLayers layers = countLeafLayers(params, options, staged.stage(BakeStage::Classifying, 0.0, 1.0));
    std::uint64_t leaves = 0;
    for (const std::uint64_t count : layers.sampled) leaves += count;
    MeshEstimate estimate;
    estimate.limit = limit.bytes;
    estimate.faces = std::uint64_t(kTrianglesPerLeaf * double(leaves));
    if (params.bake.maxFaces > 0) estimate.faces = std::min(estimate.faces, std::uint64_t(params.bake.maxFaces));
    const std::uint64_t whole = samplingEstimate(meshMemoryModel(), leaves, options.dense);
    if (whole <= limit.bytes) {
        estimate.bytes = whole;
        estimate.slabs = 1;
        return estimate;
    }
    if (params.bake.adaptivity > 0.0 || params.bake.maxFaces > 0)
        throw MemoryLimitError("resolution " + std::to_string(params.bake.resolution) + " needs an estimated " +
                                   formatBytes(whole) + " in one piece, more than the limit of " + limit.text() +
                                   limit.advice() + onePieceReason(params),
                               whole, limit.bytes);
    const std::vector<Slab> slabs = planSlabs(params, layers, limit, options.dense);
    estimate.slabs = slabs.size();
    for (const Slab& slab : slabs)
        estimate.bytes = std::max(estimate.bytes, slabEstimate(layers, slab.first, slab.end, options.dense));
    return estimate;
}

}  // namespace dqj
