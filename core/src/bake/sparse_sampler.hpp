// sparse_sampler.hpp - samples the bake's surface function f on a voxel grid, skipping the
// blocks that provably hold no surface (internal to libdqjulia; bake.hpp has the definitions).
//
// 1. Classify: blocks of 64^3 voxels, split down to 8^3 leaves, are tested with boundBall() on
//    the block grown by one voxel; a block is skipped when every point of it escapes with a
//    3-D DE above eps (so f > 0 there and on the voxels next to it). One evaluation a block.
// 2. Sample: every 8^3 leaf that was not skipped is sampled voxel by voxel (after the same
//    test on each of its 4^3 quarters), except leaves whose centre is inside the set: those are
//    sampled only when a sampled or skipped neighbour shows outside values next to them (face,
//    edge or corner), in waves, so the inside of the set is not sampled. Leaves never reached
//    are inside: tiles of -eps. (A pocket of outside wholly within such leaves is missed.)
// 3. The leaves, built in parallel, are added to one FloatTree.
// A dense option samples every leaf, for comparisons. Cost: evaluations ~ the surface's area
// (in voxels) times a few hundred; memory ~ one 8^3 float leaf per sampled leaf.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/batch.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/slice.hpp"
#include "bake/memory.hpp"
#include "bake/staged_progress.hpp"
#include "platform/thread_scratch.hpp"

namespace dqj {

/// Where the solid may be: the render bounds' sphere (bake.bounds "auto") or the box bake.bounds.
class BakeRegion {
public:
    explicit BakeRegion(const Params& params);
    /// Signed distance to the region's boundary: negative inside (exact for the sphere, the
    /// usual box distance for the box).
    double signedDistance(const glm::dvec3& p) const;
    /// Does every point of the box [lo, hi] lie at least `margin` inside the region?
    bool containsWithMargin(const glm::dvec3& lo, const glm::dvec3& hi, double margin) const;
    /// The region's bounding box.
    const Box& box() const { return box_; }

private:
    bool sphere_ = true;
    Bounds bounds_;
    Box box_;
};

/// The surface function f (bake.hpp) on a grid of voxel size h: f = max(DE3 - eps, d) outside
/// the set and max(-eps, d) inside, with d the region's signed distance; outside the region
/// f = d without evaluating the fractal. Clamped to +-background. Thread-safe.
class SurfaceFunction {
public:
    SurfaceFunction(const Params& params, double voxelSize);
    /// f at slice point p; adds 1 to `evaluations` when the fractal was evaluated.
    float operator()(const glm::dvec3& p, std::uint64_t& evaluations) const;
    /// f at `count` points at once, the fractal evaluated by the SIMD batch kernel (batch.hpp):
    /// the values of operator() (the kernel's DE differs from evaluate()'s in its last bits).
    void operator()(const glm::dvec3* points, std::size_t count, float* values, std::uint64_t& evaluations) const;

    const Fractal& fractal() const { return fractal_; }
    const Slice& slice() const { return slice_; }
    const BakeRegion& region() const { return region_; }
    double voxelSize() const { return voxelSize_; }
    double epsilon() const { return epsilon_; }       ///< eps = h / 4
    double stretch() const { return stretch_; }       ///< the slice's largest stretch (3-D -> 8-D)
    double stretchA() const { return stretchA_; }     ///< stretch into the real part alone
    double stretchB() const { return stretchB_; }     ///< stretch into the dual part alone
    float background() const { return background_; }  ///< (band width + 1) * h

private:
    float value(int n, double de, double regionDistance) const;  ///< f from an escape count and DE

    /// A thread's batch for the SIMD kernel and the indices of its points inside the region.
    struct BatchScratch {
        BatchBuffer<double> batch;
        std::vector<std::size_t> evaluated;
        std::vector<double> distances;
    };

    Fractal fractal_;
    Slice slice_;
    BakeRegion region_;
    double voxelSize_;
    double epsilon_;
    double stretch_ = 1.0, stretchA_ = 1.0, stretchB_ = 0.0;
    float background_;
    mutable ThreadScratch<BatchScratch> scratch_;
};

/// What the sampling produced: f on a FloatGrid (transform: voxel size h, voxel (i, j, k) at
/// (i h, j h, k h)), and its counters.
struct SampledSurface {
    openvdb::FloatGrid::Ptr grid;
    BakeStats stats;  ///< evaluated, dense, sampledLeaves, interiorLeaves, estimatedBytes, voxelSize
};

/// The voxel size of the bake: the bounds' largest side / bake.resolution.
double bakeVoxelSize(const Params& params);

/// The index box a bake samples: the bounds' box in voxels, grown by 2 voxels so the cut
/// faces close. Tiles cut this box (tile_geometry.hpp).
openvdb::CoordBBox bakeIndexBox(const Params& params);

/// Samples f for `params` (validated); with options.tile, only the tile's window of the whole
/// bake's grid (tileWindow); with `window`, only that box of it (a slab of a streamed mesh). In a
/// window, leaves stay where the whole bake has them and are classified and sampled as there, except
/// that leaves inside the set next to the window's cut are sampled (the whole bake fills them
/// with -eps unless the surface reaches them), so f is the whole bake's on every leaf a leaf or
/// more inside the window, bar a pocket of outside inside the set the whole bake misses (above).
/// Throws MemoryLimitError (before sampling) and Cancelled. Uses progress stages Classifying in
/// [0, split] and Sampling in [split, end]. `limit`: the limit to check against, where the
/// caller fixed it (a streamed mesh's slabs keep the limit they were planned under; the
/// default, half the available memory, moves); else samplingMemoryLimit(options).
struct SamplingLimit;
SampledSurface sampleSurface(const Params& params, const BakeOptions& options, const MemoryModel& memory,
                             StagedProgress& progress, double split, double end,
                             const openvdb::CoordBBox* window = nullptr, const SamplingLimit* limit = nullptr);

/// The voxels in the bounds' box: what a dense bake of the whole evaluates (BakeStats::dense).
std::uint64_t denseVoxels(const Params& params);

/// The memory sampleSurface estimates for `leaves` sampled leaves and the later stages of
/// `memory` (what it checks against the limit).
std::uint64_t samplingEstimate(const MemoryModel& memory, std::uint64_t leaves, bool dense);

/// The memory limit sampleSurface checks against: options.memoryLimit, or defaultMemoryLimit(),
/// capped by processMemoryHeadroom(); and how messages name it.
struct SamplingLimit {
    std::uint64_t bytes = 0;
    std::string source;           ///< why the limit is what it is: " (half of the available memory)", ...
    bool processLimited = false;  ///< the process's own limits set it
    std::string text() const;     ///< "2.0 GB (half of the available memory)"
    std::string advice() const;   ///< "; lower the resolution, ... or raise the limit (--max-memory)"
};
SamplingLimit samplingMemoryLimit(const BakeOptions& options);

/// Leaves counted by leaf layer along x: layer i holds the leaves whose origin's x is
/// 8 (first + i). What a streamed mesh plans its slabs with (mesh_stream.hpp).
struct LeafLayers {
    int first = 0;
    std::vector<std::uint64_t> sampled;   ///< leaves sampleSurface's first wave samples (dense: every leaf)
    std::vector<std::uint64_t> deferred;  ///< leaves inside the set it samples only if the surface reaches them
    std::uint64_t evaluated = 0;          ///< fractal evaluations the classification took
};

/// The leaves sampleSurface's first wave may sample in the window of layers [first, end) grown
/// by `halo` layers on either side: the window's first-wave leaves, and the deferred leaves of
/// its two outer layers (next to the window's cut they join the first wave). A bound, not an
/// estimate: the window classifies its leaves as the whole bake does (tested).
std::uint64_t slabLeaves(const LeafLayers& layers, std::size_t first, std::size_t end, std::size_t halo);

/// The most memory countLeafLayers may hold at once, from the resolution alone: a chunk's leaf
/// lists and states with no leaf of it proven empty (2.5 GB at 16384, 630 MB at 8192).
std::uint64_t countLeafLayersBytes(const Params& params);

/// Called as each chunk of layers [first, end) has been counted (the others may still be 0).
using LayersCounted = std::function<void(const LeafLayers& layers, std::size_t first, std::size_t end)>;

/// The classification of sampleSurface alone, over the whole bake's grid in chunks of 64 voxels
/// along x (each with a leaf more on either side, so the counts are the whole bake's), from the
/// middle outwards: its leaves by layer, nothing sampled, no memory check. Memory: a chunk's
/// classification. Throws Cancelled, and what `counted` throws.
LeafLayers countLeafLayers(const Params& params, const BakeOptions& options, const ProgressCallback& progress,
                           const LayersCounted& counted = {});

}  // namespace dqj
