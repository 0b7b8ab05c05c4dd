// The sparse sampler (sparse_sampler.hpp): classify blocks, sample leaves in waves, assemble.
#include "bake/sparse_sampler.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>

#include "dqjulia/ball_bound.hpp"
#include "dqjulia/batch.hpp"
#include "dqjulia/slice.hpp"
#include "platform/parallel_progress.hpp"
#include "platform/platform.hpp"
#include "bake/tile_geometry.hpp"

namespace dqj {

using openvdb::Coord;
using openvdb::CoordBBox;
using FloatLeaf = openvdb::FloatTree::LeafNodeType;

namespace {

constexpr int kLeafSize = int(FloatLeaf::DIM);                // 8
constexpr int kTopBlockSize = 64;                             // classification starts with blocks this big
constexpr std::size_t kChunkLayers = kTopBlockSize / kLeafSize;  // countLeafLayers: the leaf layers of a chunk
constexpr double kFloatLeafBytes = sizeof(FloatLeaf) + 64.0;  // a leaf and its share of the tree

/// A leaf's state during sampling, stored per leaf (key = origin / 8).
enum LeafState : int {
    kSkipped = 0,   ///< proven to hold no surface (the tree's background)
    kSurface = 1,   ///< to sample
    kDeferred = 2,  ///< centre inside the set: sampled only if the surface reaches it
    kQueued = 3     ///< a deferred leaf that the surface reached: sampled
};

Coord leafKey(const Coord& origin) { return Coord(origin.x() >> 3, origin.y() >> 3, origin.z() >> 3); }

glm::dvec3 voxelCentre(const Coord& ijk, double h) { return glm::dvec3(ijk.x(), ijk.y(), ijk.z()) * h; }

/// Does the leaf have a voxel that is inside (f < 0, `inside` true) or not inside (f >= 0,
/// `inside` false) on its boundary towards the neighbour at offset (dx, dy, dz) (each -1, 0 or
/// 1): a face, an edge or a corner?
bool anyOnBoundaryTowards(const FloatLeaf& leaf, int dx, int dy, int dz, bool inside) {
    auto range = [](int d, int& low, int& high) {
        low = d > 0 ? kLeafSize - 1 : 0;
        high = d < 0 ? 0 : kLeafSize - 1;
    };
    int x0, x1, y0, y1, z0, z1;
    range(dx, x0, x1);
    range(dy, y0, y1);
    range(dz, z0, z1);
    const float* values = leaf.buffer().data();
    for (int x = x0; x <= x1; ++x)
        for (int y = y0; y <= y1; ++y)
            for (int z = z0; z <= z1; ++z)
                if ((values[FloatLeaf::coordToOffset(Coord(x, y, z))] < 0.0f) == inside) return true;
    return false;
}

/// The 26 neighbour offsets.
std::vector<Coord> neighbourOffsets() {
    std::vector<Coord> offsets;
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz)
                if (dx != 0 || dy != 0 || dz != 0) offsets.emplace_back(dx, dy, dz);
    return offsets;
}

/// Replaces every leaf that no cell with a sign change touches by a tile of `background`. Mesh
/// extraction (volumeToMesh, and levelSetRebuild through it) reads values only at the corners
/// of cells whose corners differ in sign (f < 0 against f >= 0), and a cell reaches at most one
/// voxel beyond a leaf: a leaf whose voxels and one-voxel shell are all f >= 0 is in no such
/// cell, so the surface is unchanged. About half the sampled leaves of a rough fractal are
/// outside the surface's cells; memory after the sampling scales with the surface's cells.
std::size_t pruneAwayFromSurface(openvdb::FloatTree& tree, float background) {
    std::vector<const FloatLeaf*> leaves;
    leaves.reserve(tree.leafCount());
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) leaves.push_back(leaf.getLeaf());
    std::vector<char> prunable(leaves.size(), 0);
    const std::vector<Coord> offsets = neighbourOffsets();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          openvdb::tree::ValueAccessor<const openvdb::FloatTree> accessor(tree);
                          for (std::size_t index = range.begin(); index != range.end(); ++index) {
                              const FloatLeaf& leaf = *leaves[index];
                              const float* values = leaf.buffer().data();
                              bool inside = std::any_of(values, values + FloatLeaf::SIZE,
                                                        [](float value) { return value < 0.0f; });
                              // The one-voxel shell: each neighbour's boundary towards this leaf,
                              // or its tile's value.
                              for (std::size_t k = 0; k < offsets.size() && !inside; ++k) {
                                  const Coord& offset = offsets[k];
                                  const Coord origin =
                                      leaf.origin().offsetBy(offset.x() * kLeafSize, offset.y() * kLeafSize,
                                                             offset.z() * kLeafSize);
                                  if (const FloatLeaf* neighbour = accessor.probeConstLeaf(origin))
                                      inside =
                                          anyOnBoundaryTowards(*neighbour, -offset.x(), -offset.y(), -offset.z(), true);
                                  else
                                      inside = accessor.getValue(origin) < 0.0f;
                              }
                              prunable[index] = !inside;
                          }
                      });
    std::vector<Coord> origins;
    for (std::size_t index = 0; index < leaves.size(); ++index)
        if (prunable[index]) origins.push_back(leaves[index]->origin());
    for (const Coord& origin : origins) tree.addTile(1, origin, background, false);
    return origins.size();
}

double largestStretch(Slice slice, bool keepReal, bool keepDual) {
    for (Vec8& axis : slice.axes)
        for (int index = 0; index < 8; ++index)
            if ((index < 4 && !keepReal) || (index >= 4 && !keepDual)) axis[index] = 0.0;
    return stretchOf(slice).max;
}

/// Classification and sampling for one bake.
class Sampler {
public:
    Sampler(const Params& params, const BakeOptions& options, const MemoryModel& memory, StagedProgress& progress,
            const CoordBBox* window = nullptr, const SamplingLimit* limit = nullptr)
        : params_(params),
          options_(options),
          memory_(memory),
          progress_(progress),
          f_(params, bakeVoxelSize(params)),
          h_(f_.voxelSize()),
          dense_(denseVoxels(params)),
          slab_(window != nullptr) {
        indexBox_ = bakeIndexBox(params);
        if (options.tile) {
            // A tile samples the whole bake's grid in its window only; blocks and leaves stay
            // where the whole bake has them, so every leaf is classified and sampled as there.
            const double whole = double(indexBox_.volume());
            indexBox_.intersect(tileWindow(params, *options.tile));
            dense_ = std::max<std::uint64_t>(1, std::uint64_t(double(dense_) * double(indexBox_.volume()) / whole));
        }
        if (window) {  // a slab of a streamed mesh: likewise, the whole bake's grid in the window only
            const double whole = double(indexBox_.volume());
            indexBox_.intersect(*window);
            dense_ = std::max<std::uint64_t>(1, std::uint64_t(double(dense_) * double(indexBox_.volume()) / whole));
        }
        limit_ = limit ? *limit : samplingMemoryLimit(options);
    }

    /// Classification alone (no memory check, nothing sampled): the first wave's leaves and the
    /// deferred leaves, each by leaf layer along x, for the layers of `counted`.
    void countLayers(LeafLayers& layers, const CoordBBox& counted, const ProgressCallback& progress) {
        limit_.bytes = UINT64_MAX;
        const std::vector<Coord> wave = classify(progress);
        auto layerOf = [&](const Coord& origin) -> std::ptrdiff_t {
            if (origin.x() < counted.min().x() || origin.x() > counted.max().x()) return -1;
            return std::ptrdiff_t(floorTo(origin.x(), kLeafSize) / kLeafSize - layers.first);
        };
        for (const Coord& origin : wave)
            if (const std::ptrdiff_t layer = layerOf(origin); layer >= 0) ++layers.sampled[std::size_t(layer)];
        for (auto it = states_.cbeginValueOn(); it; ++it) {
            if (*it != kDeferred) continue;
            const Coord key = it.getCoord();
            if (const std::ptrdiff_t layer =
                    layerOf(Coord(key.x() * kLeafSize, key.y() * kLeafSize, key.z() * kLeafSize));
                layer >= 0)
                ++layers.deferred[std::size_t(layer)];
        }
        layers.evaluated += evaluated_.load();
    }

    SampledSurface run(double split, double end) {
        if (!slab_) progress_.setDense(dense_);  // a slab's mesh sets the whole's
        std::vector<Coord> wave;
        if (options_.dense) {
            checkMemory(leafCount(), true);  // before the list of them is made
            wave = allLeaves();              // nothing to classify: every leaf is sampled
        } else {
            checkMemory(0, false);  // the fixed part alone may exceed a small limit
            wave = classify(progress_.stage(BakeStage::Classifying, 0.0, split));
        }

        openvdb::FloatTree::Ptr tree(new openvdb::FloatTree(f_.background()));
        // Waves: the first holds most of the work; later ones (deferred leaves the surface
        // reached) share the rest of the stage, each half of what remains.
        double begin = split, finish = split + 0.9 * (end - split);
        const std::vector<Coord> offsets = neighbourOffsets();
        while (!wave.empty()) {
            std::vector<std::unique_ptr<FloatLeaf>> leaves =
                sampleLeaves(wave, progress_.stage(BakeStage::Sampling, begin, finish));
            std::vector<Coord> next;
            for (const auto& leaf : leaves) {
                const Coord key = leafKey(leaf->origin());
                for (const Coord& offset : offsets) {
                    const Coord neighbour = key + offset;
                    if (states_.getValue(neighbour) != kDeferred) continue;
                    if (!anyOnBoundaryTowards(*leaf, offset.x(), offset.y(), offset.z(), false)) continue;
                    states_.setValue(neighbour, kQueued);
                    next.push_back(leaf->origin().offsetBy(offset.x() * kLeafSize, offset.y() * kLeafSize,
                                                           offset.z() * kLeafSize));
                }
            }
            stats_.sampledLeaves += leaves.size();
            for (auto& leaf : leaves) tree->addLeaf(leaf.release());
            wave = std::move(next);
            begin = finish;
            finish = begin + 0.5 * (end - begin);
        }

        // Deferred leaves the surface never reached are inside the set: constant tiles.
        for (auto it = states_.cbeginValueOn(); it; ++it) {
            if (*it != kDeferred) continue;
            const Coord key = it.getCoord();
            tree->addTile(1, Coord(key.x() * kLeafSize, key.y() * kLeafSize, key.z() * kLeafSize), float(-f_.epsilon()),
                          false);
            ++stats_.interiorLeaves;
        }

        stats_.prunedLeaves = pruneAwayFromSurface(*tree, f_.background());
        platform::releaseFreedMemory();

        SampledSurface result;
        result.grid = openvdb::FloatGrid::create(tree);
        result.grid->setTransform(openvdb::math::Transform::createLinearTransform(h_));
        result.grid->setName("f");
        stats_.evaluated = evaluated_.load();
        stats_.dense = dense_;
        stats_.voxelSize = h_;
        result.stats = stats_;
        return result;
    }

private:
    /// The leaves (or blocks of `step` voxels) along each axis that cover indexBox_.
    std::array<std::uint64_t, 3> blocksAlong(int step) const {
        std::array<std::uint64_t, 3> counts{};
        for (int axis = 0; axis < 3; ++axis)
            counts[axis] =
                std::uint64_t((std::int64_t(indexBox_.max()[axis]) - floorTo(indexBox_.min()[axis], step)) / step + 1);
        return counts;
    }

    /// allLeaves().size(), counted without making the list.
    std::uint64_t leafCount() const {
        const std::array<std::uint64_t, 3> counts = blocksAlong(kLeafSize);
        return counts[0] * counts[1] * counts[2];
    }

    std::vector<Coord> allLeaves() const {
        std::vector<Coord> leaves;
        const Coord lo = indexBox_.min(), hi = indexBox_.max();
        for (int x = floorTo(lo.x(), kLeafSize); x <= hi.x(); x += kLeafSize)
            for (int y = floorTo(lo.y(), kLeafSize); y <= hi.y(); y += kLeafSize)
                for (int z = floorTo(lo.z(), kLeafSize); z <= hi.z(); z += kLeafSize) leaves.emplace_back(x, y, z);
        return leaves;
    }

    static int floorTo(int value, int step) { return int(std::floor(double(value) / step)) * step; }

    struct Lists {
        std::vector<Coord> surface;
        std::vector<Coord> deferred;
    };

    /// Classifies every leaf; returns the first wave to sample (surface leaves and deferred
    /// leaves next to skipped space) after checking the memory estimate. One work item is a
    /// column of top blocks along z, so what the classification itself holds grows with the
    /// surface it finds, which is checked against the limit as it grows, and with the square of
    /// the resolution, a list per column (3 MB at 16384), never with its cube (a list per block
    /// took 1 GB there before any check could refuse). The leaves come out in x, y, z order of
    /// their blocks, as from a list of blocks.
    std::vector<Coord> classify(const ProgressCallback& progress) {
        const Coord lo = indexBox_.min();
        const std::array<std::uint64_t, 3> blocks = blocksAlong(kTopBlockSize);
        const int x0 = floorTo(lo.x(), kTopBlockSize), y0 = floorTo(lo.y(), kTopBlockSize);
        const int z0 = floorTo(lo.z(), kTopBlockSize);
        std::vector<Lists> lists(blocks[0] * blocks[1]);
        std::atomic<std::uint64_t> surfaceLeaves{0};
        parallelForWithProgress(lists.size(), progress, [&](std::size_t column, const std::atomic<bool>& stop) {
            const int x = x0 + int(column / blocks[1]) * kTopBlockSize;
            const int y = y0 + int(column % blocks[1]) * kTopBlockSize;
            std::uint64_t count = 0;
            for (std::uint64_t k = 0; k < blocks[2] && !stop; ++k)
                classifyBlock(Coord(x, y, z0 + int(k) * kTopBlockSize), kTopBlockSize, lists[column], count);
            evaluated_ += count;
            progress_.countEvaluations(count);
            // Refuse early: the surface leaves alone already exceed the limit.
            const std::uint64_t total = surfaceLeaves += lists[column].surface.size();
            if (estimateFor(total) > limit_.bytes) checkMemory(total, false);
        });
        // Into two lists of their exact size, each column's freed as it is taken: all the lists
        // together never hold more than four Coords a leaf (countLeafLayersBytes counts on it).
        std::size_t surfaceCount = 0, deferredCount = 0;
        for (const Lists& list : lists) {
            surfaceCount += list.surface.size();
            deferredCount += list.deferred.size();
        }
        std::vector<Coord> wave;
        std::vector<Coord> deferred;
        wave.reserve(surfaceCount + deferredCount);  // the deferred leaves next to skipped space join it
        deferred.reserve(deferredCount);
        for (Lists& list : lists) {
            for (const Coord& origin : list.surface) {
                states_.setValue(leafKey(origin), kSurface);
                wave.push_back(origin);
            }
            for (const Coord& origin : list.deferred) {
                states_.setValue(leafKey(origin), kDeferred);
                deferred.push_back(origin);
            }
            list = Lists{};
        }
        // A deferred leaf next to skipped space touches outside values there: sample it.
        const std::vector<Coord> offsets = neighbourOffsets();
        for (const Coord& origin : deferred) {
            const Coord key = leafKey(origin);
            for (const Coord& offset : offsets) {
                if (states_.getValue(key + offset) != kSkipped) continue;
                states_.setValue(key, kQueued);
                wave.push_back(origin);
                break;
            }
        }
        checkMemory(wave.size(), true);
        return wave;
    }

    /// Is the block (grown by one voxel) proven to hold no surface? True when it lies outside
    /// the bounds, or when boundBall proves every point escapes with a 3-D DE above eps. Counts
    /// the evaluation and reports whether the block's centre is inside the set (and the bounds).
    bool provenEmpty(const Coord& origin, int size, std::uint64_t& evaluations, bool* centreInside = nullptr) const {
        const glm::dvec3 centre = (glm::dvec3(origin.x(), origin.y(), origin.z()) + 0.5 * (size - 1)) * h_;
        const double radius = 0.5 * (size + 1) * h_ * std::sqrt(3.0);
        const double regionDistance = f_.region().signedDistance(centre);
        if (regionDistance > radius) return true;  // wholly outside the bounds: f = distance > 0
        ++evaluations;
        const BallBound bound =
            boundBall(f_.fractal(), f_.slice().map(centre), radius * f_.stretchA(), radius * f_.stretchB());
        if (centreInside) *centreInside = regionDistance < 0.0 && bound.centre.n == 0;
        return bound.allEscape && bound.minDe / f_.stretch() > f_.epsilon();
    }

    /// Skips a block, splits it, or files it as a leaf to sample or to defer.
    void classifyBlock(const Coord& origin, int size, Lists& lists, std::uint64_t& evaluations) const {
        if (!indexBox_.hasOverlap(CoordBBox(origin, origin.offsetBy(size - 1)))) return;
        bool centreInside = false;
        if (provenEmpty(origin, size, evaluations, &centreInside)) return;
        if (size == kLeafSize) {
            (centreInside ? lists.deferred : lists.surface).push_back(origin);
            return;
        }
        const int half = size / 2;
        for (int x = 0; x < 2; ++x)
            for (int y = 0; y < 2; ++y)
                for (int z = 0; z < 2; ++z)
                    classifyBlock(origin.offsetBy(x * half, y * half, z * half), half, lists, evaluations);
    }

    /// Samples leaves in parallel, one task a leaf. A leaf's 4^3 quarters are tested first, and
    /// a proven quarter keeps the (positive) background: no surface cell touches it.
    std::vector<std::unique_ptr<FloatLeaf>> sampleLeaves(const std::vector<Coord>& origins,
                                                         const ProgressCallback& progress) {
        std::vector<std::unique_ptr<FloatLeaf>> leaves(origins.size());
        constexpr int kQuarter = kLeafSize / 2;
        parallelForWithProgress(origins.size(), progress, [&](std::size_t index, const std::atomic<bool>& stop) {
            auto leaf = std::make_unique<FloatLeaf>(origins[index], f_.background(), false);
            std::uint64_t count = 0;
            openvdb::Index offsets[FloatLeaf::SIZE];
            glm::dvec3 centres[FloatLeaf::SIZE];
            float values[FloatLeaf::SIZE];
            std::size_t voxels = 0;
            for (int quarter = 0; quarter < 8; ++quarter) {
                if (stop.load(std::memory_order_relaxed)) return;
                const Coord corner((quarter & 1) * kQuarter, ((quarter >> 1) & 1) * kQuarter,
                                   ((quarter >> 2) & 1) * kQuarter);
                if (!options_.dense && provenEmpty(leaf->origin() + corner, kQuarter, count)) continue;
                for (int x = 0; x < kQuarter; ++x)
                    for (int y = 0; y < kQuarter; ++y)
                        for (int z = 0; z < kQuarter; ++z) {
                            const openvdb::Index offset = FloatLeaf::coordToOffset(corner.offsetBy(x, y, z));
                            offsets[voxels] = offset;
                            centres[voxels++] = voxelCentre(leaf->offsetToGlobalCoord(offset), h_);
                        }
            }
            // The leaf's voxels through the SIMD batch kernel together.
            f_(centres, voxels, values, count);
            for (std::size_t voxel = 0; voxel < voxels; ++voxel) leaf->setValueOn(offsets[voxel], values[voxel]);
            evaluated_ += count;
            progress_.countEvaluations(count);
            leaves[index] = std::move(leaf);
        });
        return leaves;
    }

    std::uint64_t estimateFor(std::uint64_t leaves) const { return samplingEstimate(memory_, leaves, options_.dense); }

    /// Refuses (MemoryLimitError) when `leaves` sampled leaves would exceed the limit. `final`:
    /// the whole count after classification; otherwise a count still growing during it.
    void checkMemory(std::uint64_t leaves, bool final) {
        const std::uint64_t estimate = estimateFor(leaves);
        if (final) stats_.estimatedBytes = estimate;
        if (estimate <= limit_.bytes) return;
        const std::string limit = limit_.text();
        const std::string blocks = std::to_string(leaves) + " blocks of 8^3 voxels to sample";
        throw MemoryLimitError("resolution " + std::to_string(params_.bake.resolution) +
                                   (final ? " needs an estimated " + formatBytes(estimate) + " (" + blocks +
                                                "), more than the limit of " + limit
                                    : leaves > 0 ? " needs more than the limit of " + limit + ": the first " + blocks +
                                                       " already need " + formatBytes(estimate)
                                                 : " needs at least " + formatBytes(estimate) +
                                                       " before any voxel is sampled, more than "
                                                       "the limit of " +
                                                       limit) +
                                   limit_.advice(),
                               estimate, limit_.bytes);
    }

    const Params& params_;
    const BakeOptions& options_;
    MemoryModel memory_;
    StagedProgress& progress_;
    SurfaceFunction f_;
    double h_;
    CoordBBox indexBox_;  // the voxels sampled: the whole bake's, or a tile's window of them
    std::uint64_t dense_ = 1;
    bool slab_ = false;
    SamplingLimit limit_;
    std::atomic<std::uint64_t> evaluated_{0};
    openvdb::Int32Tree states_{kSkipped};  // keyed by leaf (origin / 8)
    BakeStats stats_;
};

}  // namespace

BakeRegion::BakeRegion(const Params& params) {
    if (params.bake.bounds) {
        sphere_ = false;
        box_ = *params.bake.bounds;
        return;
    }
    bounds_ = renderBounds(params);
    box_.min = bounds_.center - bounds_.radius;
    box_.max = bounds_.center + bounds_.radius;
}

double BakeRegion::signedDistance(const glm::dvec3& p) const {
    if (sphere_) return glm::length(p - bounds_.center) - bounds_.radius;
    const glm::dvec3 centre = 0.5 * (box_.min + box_.max);
    const glm::dvec3 q = glm::abs(p - centre) - 0.5 * (box_.max - box_.min);
    const double outside = glm::length(glm::max(q, glm::dvec3(0.0)));
    const double inside = std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
    return outside + inside;
}

bool BakeRegion::containsWithMargin(const glm::dvec3& lo, const glm::dvec3& hi, double margin) const {
    if (sphere_) {  // the box's corner farthest from the centre
        const glm::dvec3 far = glm::max(glm::abs(lo - bounds_.center), glm::abs(hi - bounds_.center));
        return glm::length(far) <= bounds_.radius - margin;
    }
    return glm::all(glm::greaterThanEqual(lo, box_.min + margin)) &&
           glm::all(glm::lessThanEqual(hi, box_.max - margin));
}

SurfaceFunction::SurfaceFunction(const Params& params, double voxelSize)
    : fractal_(params.fractal),
      slice_(params.slice.effective()),
      region_(params),
      voxelSize_(voxelSize),
      epsilon_(0.25 * voxelSize),
      background_(float((params.bake.bandWidth + 1.0) * voxelSize)) {
    stretch_ = stretchOf(slice_).max;
    stretchA_ = largestStretch(slice_, true, false);
    stretchB_ = largestStretch(slice_, false, true);
}

float SurfaceFunction::operator()(const glm::dvec3& p, std::uint64_t& evaluations) const {
    const double limit = background_;
    const double regionDistance = region_.signedDistance(p);
    if (regionDistance > 0.0) return float(std::min(regionDistance, limit));
    ++evaluations;
    const Escape escape = evaluate(fractal_, slice_.map(p));
    return value(escape.n, escape.de, regionDistance);
}

inline float SurfaceFunction::value(int n, double de, double regionDistance) const {
    const double limit = background_;
    // DE = +inf (an orbit from the critical point) carries no distance: the clamp takes it.
    const double inner = n == 0 ? -epsilon_ : std::min(de / stretch_, limit) - epsilon_;
    return float(std::clamp(std::max(inner, regionDistance), -limit, limit));
}

void SurfaceFunction::operator()(const glm::dvec3* points, std::size_t count, float* values,
                                 std::uint64_t& evaluations) const {
    BatchScratch& scratch = scratch_.local();
    BatchBuffer<double>& batch = scratch.batch;
    std::vector<std::size_t>& evaluated = scratch.evaluated;  // indices of the points inside the region
    std::vector<double>& distances = scratch.distances;       // and their region distances, computed once
    // Room for every point, written in place and cut to the points inside the region (no
    // push_back's capacity check per coordinate).
    batch.resize(count);
    std::array<double*, 8> coordinates;
    for (int k = 0; k < 8; ++k) coordinates[k] = batch.start(k);
    // Where every point lies deeper inside the region than the band, its distance d <= -limit
    // cannot change f: clamp(max(inner, d)) = clamp(inner) for any inner (NaN included), so d
    // is taken as -limit without computing it. A voxel more margin covers the rounding of d.
    const double limit = background_;
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < count; ++i) {
        lo = glm::min(lo, points[i]);
        hi = glm::max(hi, points[i]);
    }
    const bool deep = count > 0 && region_.containsWithMargin(lo, hi, limit + voxelSize_);
    if (deep) {                      // every point: the slice map coordinate by coordinate (vectorised)
        const Slice slice = slice_;  // a local copy: the stores below cannot alias it
        for (int k = 0; k < 8; ++k) {
            double* coordinate = coordinates[k];
            for (std::size_t i = 0; i < count; ++i) coordinate[i] = slice.coordinate(k, points[i]);
        }
        batch.evaluate(fractal_);
        evaluations += count;
        for (std::size_t i = 0; i < count; ++i) values[i] = value(batch.n(i), batch.de(i), -limit);
        return;
    }
    evaluated.resize(count);
    distances.resize(count);
    std::size_t inside = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const double regionDistance = region_.signedDistance(points[i]);
        if (regionDistance > 0.0) {
            values[i] = float(std::min(regionDistance, limit));
            continue;
        }
        const Vec8 z = toVec8(slice_.map(points[i]));
        for (int k = 0; k < 8; ++k) coordinates[k][inside] = z[k];
        evaluated[inside] = i;
        distances[inside] = regionDistance;
        ++inside;
    }
    batch.resize(inside);
    batch.evaluate(fractal_);
    evaluations += inside;
    for (std::size_t k = 0; k < inside; ++k) values[evaluated[k]] = value(batch.n(k), batch.de(k), distances[k]);
}

CoordBBox bakeIndexBox(const Params& params) {
    const BakeRegion region(params);
    const Box& box = region.box();
    const double h = bakeVoxelSize(params);
    constexpr int kPadding = 2;  // voxels beyond the bounds, so the cut face closes
    Coord lo, hi;
    for (int axis = 0; axis < 3; ++axis) {
        lo[axis] = int(std::floor(box.min[axis] / h)) - kPadding;
        hi[axis] = int(std::ceil(box.max[axis] / h)) + kPadding;
    }
    return CoordBBox(lo, hi);
}

double bakeVoxelSize(const Params& params) {
    const BakeRegion region(params);
    const glm::dvec3 size = region.box().max - region.box().min;
    return std::max(size.x, std::max(size.y, size.z)) / params.bake.resolution;
}

SampledSurface sampleSurface(const Params& params, const BakeOptions& options, const MemoryModel& memory,
                             StagedProgress& progress, double split, double end, const CoordBBox* window,
                             const SamplingLimit* limit) {
    Sampler sampler(params, options, memory, progress, window, limit);
    return sampler.run(split, end);
}

std::uint64_t denseVoxels(const Params& params) {
    const BakeRegion region(params);
    const Box& box = region.box();
    const double h = bakeVoxelSize(params);
    std::uint64_t dense = 1;
    for (int axis = 0; axis < 3; ++axis)
        dense *= std::uint64_t(std::max<long long>(1, std::llround((box.max[axis] - box.min[axis]) / h)));
    return dense;
}

std::uint64_t samplingEstimate(const MemoryModel& memory, std::uint64_t leaves, bool dense) {
    const double perLeaf = dense ? kFloatLeafBytes : kFloatLeafBytes + memory.bytesPerLeaf;
    return std::uint64_t(memory.fixedBytes + perLeaf * double(leaves));
}

SamplingLimit samplingMemoryLimit(const BakeOptions& options) {
    // An explicit limit too is capped by what the process may really allocate (ulimit -v,
    // cgroups): beyond that the bake would fail late with an allocation error.
    const std::uint64_t processLimit = processMemoryHeadroom();
    const std::uint64_t requested = options.memoryLimit ? options.memoryLimit : defaultMemoryLimit();
    SamplingLimit limit;
    limit.bytes = std::min(requested, processLimit);
    limit.processLimited = processLimit <= requested;  // defaultMemoryLimit() too may be the process limit
    limit.source = limit.processLimited  ? " (what this process may still allocate under its memory limits: ulimit -v, "
                                           "ulimit -d or its cgroup's memory.max)"
                   : options.memoryLimit ? ""
                                         : " (half of the available memory)";
    return limit;
}

std::string SamplingLimit::text() const { return formatBytes(bytes) + source; }

std::string SamplingLimit::advice() const {
    return processLimited
               ? "; lower the resolution, bake a smaller region (bake.bounds) or raise the process's limit"
               : "; lower the resolution, bake a smaller region (bake.bounds) or raise the limit (--max-memory)";
}

std::uint64_t slabLeaves(const LeafLayers& layers, std::size_t first, std::size_t end, std::size_t halo) {
    const std::size_t lo = first >= halo ? first - halo : 0, hi = std::min(layers.sampled.size(), end + halo);
    std::uint64_t leaves = 0;
    for (std::size_t layer = lo; layer < hi; ++layer) leaves += layers.sampled[layer];
    if (!layers.deferred.empty()) {  // none where every leaf is sampled (dense, or thickness forced)
        if (lo > 0) leaves += layers.deferred[lo];
        if (hi < layers.sampled.size()) leaves += layers.deferred[hi - 1];
    }
    return leaves;
}

std::uint64_t countLeafLayersBytes(const Params& params) {
    // A bound from the resolution alone. A chunk's classification, at worst (no leaf of its window
    // proven empty), holds for each leaf of its window (the chunk's layers and one more on either
    // side): a Coord in its column's list (up to twice that while the list grows), then in the wave
    // and the deferred leaves (classify), four Coords a leaf at most; and a state in an Int32Tree
    // keyed by leaf, whose leaf nodes (each with its 8^3 values, allocated apart from the node) the
    // window touches up to 3 across x (10 keys) and all across y and z, with the internal nodes
    // above them. At 16384 this is 2.5 GB (8192: 630 MB, 4096: 160 MB); measured there (default
    // fractal, the middle chunk): 400 MB. (Counting sizeof(leaf node) alone, without its values,
    // once gave 30 MB, and a 600 MB cap ran out here instead of refusing.)
    const CoordBBox full = bakeIndexBox(params);
    using StateTree = openvdb::Int32Tree;
    using StateLeaf = StateTree::LeafNodeType;
    using Lower = StateTree::RootNodeType::ChildNodeType::ChildNodeType;  // 16^3 leaf nodes
    using Upper = StateTree::RootNodeType::ChildNodeType;                 // 32^3 lower nodes
    constexpr std::uint64_t kAllocation = 64;                             // malloc's own, a block
    auto across = [](std::uint64_t keys, std::uint64_t perNode) { return keys / perNode + 2; };
    const std::uint64_t keysX = kChunkLayers + 2;
    const std::uint64_t keysY = std::uint64_t(full.dim().y() / kLeafSize + 2);
    const std::uint64_t keysZ = std::uint64_t(full.dim().z() / kLeafSize + 2);
    const std::uint64_t lists = 4 * sizeof(Coord) * keysX * keysY * keysZ;
    const std::uint64_t leafNodes = 3 * across(keysY, StateLeaf::DIM) * across(keysZ, StateLeaf::DIM);
    const std::uint64_t lowerNodes = 2 * across(keysY, Lower::DIM) * across(keysZ, Lower::DIM);
    const std::uint64_t upperNodes = 2 * across(keysY, Upper::DIM) * across(keysZ, Upper::DIM);
    return lists + leafNodes * (sizeof(StateLeaf) + StateLeaf::SIZE * sizeof(std::int32_t) + 2 * kAllocation) +
           lowerNodes * (sizeof(Lower) + kAllocation) + upperNodes * (sizeof(Upper) + kAllocation);
}

LeafLayers countLeafLayers(const Params& params, const BakeOptions& options, const ProgressCallback& progress,
                           const LayersCounted& counted) {
    const CoordBBox full = bakeIndexBox(params);
    LeafLayers layers;
    const int firstX = int(std::floor(double(full.min().x()) / kLeafSize)) * kLeafSize;
    layers.first = firstX / kLeafSize;
    const std::size_t count = std::size_t(full.max().x() - firstX) / kLeafSize + 1;
    layers.sampled.assign(count, 0);
    layers.deferred.assign(count, 0);
    if (options.dense) {  // every leaf is sampled, nothing is classified
        const Coord dim = full.dim();
        const std::uint64_t perLayer = std::uint64_t((dim.y() + 2 * kLeafSize - 1) / kLeafSize) *
                                       std::uint64_t((dim.z() + 2 * kLeafSize - 1) / kLeafSize);
        layers.sampled.assign(count, perLayer);
        return layers;
    }
    // Chunks of layers, each classified with a leaf more on either side, so that its deferred
    // leaves see their true neighbours (the first wave takes those next to skipped space).
    // From the middle outwards, where a solid is usually widest: a caller that refuses a layer
    // too large for its limit does so after the first few chunks.
    const std::size_t chunks = (count + kChunkLayers - 1) / kChunkLayers;
    std::vector<std::size_t> order(chunks);
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) order[chunk] = chunk;
    const double middle = 0.5 * double(chunks - 1);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return std::abs(double(a) - middle) < std::abs(double(b) - middle);
    });
    BakeOptions quiet = options;
    quiet.monitor = nullptr;
    for (std::size_t step = 0; step < chunks; ++step) {
        const std::size_t chunk = order[step];
        const int x0 = firstX + int(chunk * kChunkLayers) * kLeafSize;
        const CoordBBox box(Coord(x0, full.min().y(), full.min().z()),
                            Coord(x0 + int(kChunkLayers) * kLeafSize - 1, full.max().y(), full.max().z()));
        CoordBBox window = box;
        window.expand(kLeafSize);
        StagedProgress staged({}, nullptr);
        Sampler sampler(params, quiet, MemoryModel{}, staged, &window);
        const double begin = double(step) / double(chunks), end = double(step + 1) / double(chunks);
        sampler.countLayers(layers, box,
                            progress ? ProgressCallback(
                                           [&](double fraction) { return progress(begin + fraction * (end - begin)); })
                                     : ProgressCallback());
        if (counted) counted(layers, chunk * kChunkLayers, std::min(count, (chunk + 1) * kChunkLayers));
    }
    return layers;
}

}  // namespace dqj
