// dqjulia/bake.hpp - bakes the fractal into an OpenVDB file: a narrow-band level set "surface",
// a fog volume "density" and optional attribute grids ("color", "trap", "iterations").
// Code: core/src/bake/bake.cpp; the memory limits (MemoryLimitError, processMemoryHeadroom,
// defaultMemoryLimit, formatBytes) in core/src/bake/memory.cpp.
//
// The surface (docs/baking.md): with h the voxel size and eps = h / 4, the solid is the
// N-iteration set together with every point whose 3-D distance estimate is below eps, cut to
// the bake bounds. The bake samples f = DE/stretch - eps outside the set and -eps inside it
// (zero on the surface, continuous where the DE goes to 0 at the set), meshes f = 0 and turns
// the mesh into an exact signed distance with OpenVDB (levelSetRebuild); the fog volume is the
// level set's interior (sdfToFogVolume).
//
// Cost: sparse. Blocks of voxels (64^3 down to 8^3) are tested with a rigorous ball bound
// (ball_bound.hpp) and skipped whole when no point in them can be on the surface; blocks whose
// centre is inside the set are sampled only when the surface reaches them from a sampled
// neighbour. So evaluations and memory grow with the surface's area, not the grid's volume
// (about 4x per doubling of the resolution; `BakeStats` reports evaluated against dense).
// Threads: TBB, one 8^3 leaf per task, leaves assembled into one tree; OpenVDB's tools are
// parallel themselves. A memory estimate is checked before the heavy work (MemoryLimitError).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "dqjulia/export.h"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// The stages of a bake or mesh, in order.
enum class BakeStage { Classifying, Sampling, LevelSet, Grids, Meshing, Writing };
DQJ_API std::string_view bakeStageName(BakeStage stage);

/// Live counters for a progress display: read them from the progress callback (any thread).
struct BakeMonitor {
    std::atomic<BakeStage> stage{BakeStage::Classifying};
    std::atomic<std::uint64_t> evaluated{0};  ///< fractal evaluations so far
    std::atomic<std::uint64_t> dense{0};      ///< voxels a dense bake evaluates (set at the start)
    std::atomic<std::uint32_t> slab{0};       ///< a mesh made in slabs: the slab being made (from 1)
    std::atomic<std::uint32_t> slabs{0};      ///< and how many there are (0 or 1: one piece)
};

/// One tile of a tiled bake (tiles.hpp): the whole bake's index box cut into
/// counts[0] x counts[1] x counts[2] boxes, and which of them (1-based, x fastest).
struct Tile {
    std::array<int, 3> counts{1, 1, 1};
    int index = 1;
};

struct BakeOptions {
    bool dense = false;                     ///< evaluate every voxel, skip nothing (for comparisons and tests)
    std::uint64_t memoryLimit = 0;          ///< refuse above this estimate, in bytes; 0 = defaultMemoryLimit()
    BakeMonitor* monitor = nullptr;         ///< optional live counters
    Existing existing = Existing::Replace;  ///< bakeVdb: replace an existing file, or keep it and fail
    std::optional<Tile> tile;               ///< bakeVdb: bake this tile only (tiles.hpp); not for meshes
};

struct BakeStats {
    std::uint64_t evaluated = 0;       ///< fractal evaluations, the block tests included
    std::uint64_t dense = 0;           ///< voxels in the bounds' box: what a dense bake evaluates
    std::uint64_t sampledLeaves = 0;   ///< 8^3 blocks sampled voxel by voxel
    std::uint64_t interiorLeaves = 0;  ///< 8^3 blocks inside the set, never sampled (filled)
    std::uint64_t prunedLeaves = 0;    ///< sampled blocks then dropped: no surface cell touches them
    std::uint64_t activeVoxels = 0;    ///< active voxels of the surface level set (bakes; 0 for meshes)
    std::uint64_t estimatedBytes = 0;  ///< the memory estimate checked against the limit (slabs: the largest's)
    std::uint64_t slabs = 0;           ///< meshes: the slabs it was made in (1: one piece); bakes: 0
    double voxelSize = 0.0;            ///< h, in slice units
    /// Meshes with bake.max_faces (mesh_simplify.hpp): the adaptivity chosen, the full mesh's
    /// triangles, and the farthest vertex and face point of the result from the full mesh, in
    /// voxels; all 0 when the full mesh met the limit (or without it).
    double adaptivity = 0.0;
    std::uint64_t fullTriangles = 0;
    double deviationVertices = 0.0;
    double deviationSamples = 0.0;
    double seconds = 0.0;
};

/// Thrown before any heavy work when the estimate exceeds the limit. A ParamError (key
/// "bake.resolution"), so the command exits with status 2; the C ABI gives DQJ_ERROR_OUT_OF_MEMORY.
class DQJ_API MemoryLimitError : public ParamError {
public:
    MemoryLimitError(const std::string& message, std::uint64_t estimate, std::uint64_t limit);
    std::uint64_t estimate() const { return estimate_; }
    std::uint64_t limit() const { return limit_; }

private:
    std::uint64_t estimate_;
    std::uint64_t limit_;
};

/// What this process may still allocate under its own limits: RLIMIT_AS and RLIMIT_DATA
/// (ulimit -v, ulimit -d) less what it uses, and the memory.max (cgroup v2) or
/// memory.limit_in_bytes (v1) of its cgroups less their usage; on Windows, its job object's limits.
/// UINT64_MAX when unlimited.
DQJ_API std::uint64_t processMemoryHeadroom();
/// Half of the memory the system reports available (MemAvailable) right now, at most
/// processMemoryHeadroom().
DQJ_API std::uint64_t defaultMemoryLimit();
/// "1.5 GB", "312 MB", ...
DQJ_API std::string formatBytes(std::uint64_t bytes);

/// Bakes `params` (validated; for an animation frame pass atFrame(params, frame)) into the
/// OpenVDB file `path`, with the grids params.bake.grids names. The file appears only when
/// complete (temporary file + rename). With options.tile, one tile of it (tiles.hpp).
/// Throws ParamError, MemoryLimitError, Cancelled (the progress callback returned false) or
/// std::runtime_error (I/O).
DQJ_API BakeStats bakeVdb(const Params& params, const std::string& path, const BakeOptions& options = {},
                          const ProgressCallback& progress = {});

}  // namespace dqj
