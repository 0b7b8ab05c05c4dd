// A mesh of at most N triangles and its deviation from the full mesh (mesh_simplify.hpp).
#include "bake/mesh_simplify.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "dqjulia/params.hpp"

namespace dqj {
namespace {

constexpr int kBisections = 12;        // adaptivity to 1/4096
constexpr double kCloseEnough = 0.98;  // of N: a try this full ends the search
constexpr float kCellVoxels = 2.0f;    // the reference's hash cells
constexpr int kRings = 8;              // of cells searched: 16 voxels
constexpr std::int64_t kCellBias = std::int64_t(1) << 20;

using Triangle = std::array<std::uint32_t, 3>;

std::vector<Triangle> trianglesOf(const Mesh& mesh) {
    std::vector<Triangle> triangles(mesh.triangles.begin(), mesh.triangles.end());
    triangles.reserve(mesh.triangleCount());
    for (const auto& quad : mesh.quads) {
        triangles.push_back({quad[0], quad[1], quad[2]});
        triangles.push_back({quad[0], quad[2], quad[3]});
    }
    return triangles;
}

/// The point of triangle abc nearest p (the Voronoi regions of its corners, edges and face).
glm::vec3 nearestOnTriangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
    const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f) return a;
    const glm::vec3 bp = p - b;
    const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3) return b;
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + ab * (d1 / (d1 - d3));
    const glm::vec3 cp = p - c;
    const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6) return c;
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + ac * (d2 / (d2 - d6));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const float sum = va + vb + vc;
    if (!(sum > 0.0f)) return a;  // a degenerate triangle: its corner will do (its edges are tested by neighbours)
    return a + ab * (vb / sum) + ac * (vc / sum);
}

/// The reference's triangles by the 2-voxel cells their boxes overlap, sorted by cell.
class TriangleCells {
public:
    TriangleCells(const Mesh& reference, float cell)
        : positions_(reference.positions), triangles_(trianglesOf(reference)), cell_(cell) {
        std::vector<std::size_t> counts(triangles_.size());
        for (std::size_t index = 0; index < triangles_.size(); ++index) {
            const auto [lo, hi] = cellBox(index);
            counts[index] =
                std::size_t(hi[0] - lo[0] + 1) * std::size_t(hi[1] - lo[1] + 1) * std::size_t(hi[2] - lo[2] + 1);
        }
        std::size_t total = 0;
        for (const std::size_t count : counts) total += count;
        entries_.reserve(total);
        for (std::size_t index = 0; index < triangles_.size(); ++index) {
            const auto [lo, hi] = cellBox(index);
            for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
                for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                    for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
                        entries_.emplace_back(key(x, y, z), std::uint32_t(index));
        }
        tbb::parallel_sort(entries_.begin(), entries_.end());
    }

    /// The distance from p to the nearest triangle, or the search's reach when none is within it.
    float distance(const glm::vec3& p) const {
        const std::array<std::int64_t, 3> home = cellOf(p);
        float best = std::numeric_limits<float>::infinity();
        for (int ring = 0; ring <= kRings; ++ring) {
            for (int dx = -ring; dx <= ring; ++dx)
                for (int dy = -ring; dy <= ring; ++dy)
                    for (int dz = -ring; dz <= ring; ++dz) {
                        if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
                        const std::uint64_t cell = key(home[0] + dx, home[1] + dy, home[2] + dz);
                        auto it = std::lower_bound(entries_.begin(), entries_.end(), std::pair(cell, std::uint32_t(0)));
                        for (; it != entries_.end() && it->first == cell; ++it) {
                            const Triangle& t = triangles_[it->second];
                            const glm::vec3 nearest =
                                nearestOnTriangle(p, positions_[t[0]], positions_[t[1]], positions_[t[2]]);
                            best = std::min(best, glm::length(p - nearest));
                        }
                    }
            // Triangles not met yet lie in cells of the next rings: at least `ring` cells away.
            if (best <= float(ring) * cell_) return best;
        }
        return std::min(best, float(kRings) * cell_);
    }

private:
    std::array<std::int64_t, 3> cellOf(const glm::vec3& p) const {
        return {std::int64_t(std::floor(p.x / cell_)), std::int64_t(std::floor(p.y / cell_)),
                std::int64_t(std::floor(p.z / cell_))};
    }
    std::pair<std::array<std::int64_t, 3>, std::array<std::int64_t, 3>> cellBox(std::size_t index) const {
        const Triangle& t = triangles_[index];
        const glm::vec3 lo = glm::min(positions_[t[0]], glm::min(positions_[t[1]], positions_[t[2]]));
        const glm::vec3 hi = glm::max(positions_[t[0]], glm::max(positions_[t[1]], positions_[t[2]]));
        return {cellOf(lo), cellOf(hi)};
    }
    static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
        auto part = [](std::int64_t v) {
            return std::uint64_t(std::clamp<std::int64_t>(v + kCellBias, 0, 2 * kCellBias - 1));
        };
        return (part(x) << 42) | (part(y) << 21) | part(z);
    }

    const std::vector<glm::vec3>& positions_;
    std::vector<Triangle> triangles_;
    float cell_;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> entries_;
};

std::string figure(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.2f", value);
    return text;
}

}  // namespace

MeshDeviation meshDeviation(const Mesh& reference, const Mesh& mesh, double voxel) {
    MeshDeviation deviation;
    if (mesh.positions.empty()) return deviation;
    if (reference.positions.empty()) return {double(kRings) * kCellVoxels, double(kRings) * kCellVoxels};
    const TriangleCells cells(reference, float(kCellVoxels * voxel));
    tbb::combinable<double> vertices([] { return 0.0; }), samples([] { return 0.0; });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.positions.size()), [&](const auto& range) {
        double& farthest = vertices.local();
        for (std::size_t index = range.begin(); index < range.end(); ++index)
            farthest = std::max(farthest, double(cells.distance(mesh.positions[index])));
    });
    const std::vector<Triangle> triangles = trianglesOf(mesh);
    static constexpr float kSix = 1.0f / 6.0f, kThird = 1.0f / 3.0f;
    static constexpr std::array<std::array<float, 3>, 7> kWeights{{{kThird, kThird, kThird},
                                                                   {0.5f, 0.5f, 0.0f},
                                                                   {0.0f, 0.5f, 0.5f},
                                                                   {0.5f, 0.0f, 0.5f},
                                                                   {4 * kSix, kSix, kSix},
                                                                   {kSix, 4 * kSix, kSix},
                                                                   {kSix, kSix, 4 * kSix}}};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size()), [&](const auto& range) {
        double& farthest = samples.local();
        for (std::size_t index = range.begin(); index < range.end(); ++index) {
            const Triangle& t = triangles[index];
            for (const auto& w : kWeights) {
                const glm::vec3 p =
                    w[0] * mesh.positions[t[0]] + w[1] * mesh.positions[t[1]] + w[2] * mesh.positions[t[2]];
                farthest = std::max(farthest, double(cells.distance(p)));
            }
        }
    });
    deviation.vertices = vertices.combine([](double a, double b) { return std::max(a, b); }) / voxel;
    deviation.samples = samples.combine([](double a, double b) { return std::max(a, b); }) / voxel;
    return deviation;
}

SimplifiedMesh simplifyToFaces(std::uint64_t maxTriangles, double voxel, const std::function<Mesh(double)>& meshAt,
                               const ProgressCallback& progress) {
    auto step = [&](int done) {
        if (progress && !progress(double(done) / double(kBisections + 3))) throw Cancelled();
    };
    SimplifiedMesh result;
    Mesh full = meshAt(0.0);
    if (full.triangleCount() <= maxTriangles) {
        result.mesh = std::move(full);
        return result;
    }
    result.fullTriangles = full.triangleCount();
    step(1);
    Mesh best = meshAt(1.0);
    const std::string asked = "at most " + std::to_string(maxTriangles) + " faces (triangles; a quad counts as two)";
    if (best.triangleCount() > maxTriangles)
        throw ParamError("bake.max_faces",
                         asked + " is fewer than adaptive meshing reaches at this resolution: " +
                             std::to_string(best.triangleCount()) + " at the most adaptive (the full mesh has " +
                             std::to_string(result.fullTriangles) + "); ask for " +
                             std::to_string(best.triangleCount()) + " or more, or lower the resolution");
    double lo = 0.0, hi = 1.0;
    for (int bisection = 0; bisection < kBisections; ++bisection) {
        step(2 + bisection);
        if (double(best.triangleCount()) >= kCloseEnough * double(maxTriangles)) break;
        const double middle = 0.5 * (lo + hi);
        Mesh candidate = meshAt(middle);
        if (candidate.triangleCount() <= maxTriangles) {
            hi = middle;
            best = std::move(candidate);
        } else {
            lo = middle;
        }
    }
    step(kBisections + 2);
    result.adaptivity = hi;
    result.deviation = meshDeviation(full, best, voxel);
    if (result.deviation.vertices > kSimplifiedVertexBound || result.deviation.samples > kSimplifiedSampleBound)
        throw ParamError("bake.max_faces",
                         asked + " strays too far from the full mesh (" + std::to_string(result.fullTriangles) +
                             " faces): a vertex " + figure(result.deviation.vertices) +
                             " voxels from it and a point on a face " + figure(result.deviation.samples) +
                             " voxels, beyond the bounds of " + figure(kSimplifiedVertexBound) + " and " +
                             figure(kSimplifiedSampleBound) + ": ask for more faces");
    result.mesh = std::move(best);
    return result;
}

}  // namespace dqj
