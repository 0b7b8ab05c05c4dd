// What `dqjulia bake` and `dqjulia mesh` share: their flags, frame ranges and output names,
// the memory limit, the progress display and the --stats report.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common.hpp"
#include "dqjulia/bake.hpp"
#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/tiles.hpp"


namespace dqj::cli {

/// An inclusive range of whole frames (--frames A-B, or A alone).
struct FrameRange {
    int first = 1;
    int last = 1;
};

/// The commands that take the bake flags: each registers the flags that mean something to it.
enum class BakeCommand { Bake, Mesh, Farm };

struct BakeFlags {
    FractalOptions fractal;
    std::string output;
    std::optional<int> resolution;
    std::vector<double> boundsMin, boundsMax;
    std::optional<double> bandWidth;
    std::string grids;
    std::string frames;
    std::string maxMemory;
    std::optional<double> adaptivity;  // mesh only
    bool noColors = false;             // mesh only
    std::string units;                 // mesh only: --units (meshScale)
    std::optional<std::string> size;   // mesh only: --size, as given (meshScale)
    // The print check (mesh only; print_check.hpp).
    std::optional<double> minWall;
    std::uint64_t minIsland = 0;
    bool largestOnly = false;
    bool allowUnprintable = false;
    std::optional<int> faces;          // mesh only: bake.max_faces
    std::string tiles;                 // bake and farm
    std::optional<int> tile;           // bake only
    std::optional<int> threads;        // bake and mesh
    bool skipExisting = false;         // bake and mesh
    bool dense = false;
    bool force = false;
    bool quiet = false;
    bool stats = false;

    /// Registers the flags of `command`: mesh adds --adaptivity and --no-colors, bake --grids,
    /// --band-width and the tiles, farm the parameters' flags and --tiles alone.
    void addTo(CLI::App& command, BakeCommand kind);
    /// Defaults, the file, then the flags; validated. Throws ParamError.
    Params load() const;
    /// --frames, if given. Throws ParamError for a malformed or reversed range.
    std::optional<FrameRange> frameRange() const;
    /// --units and --size. Throws ParamError for an unknown unit, a size that is not a number or
    /// out of range (checkMeshScale), and --size without --units.
    MeshScale meshScale() const;
    /// --max-memory in bytes, or 0 for the default. Throws ParamError.
    std::uint64_t memoryLimit() const;
    /// --tiles (its index --tile, or 0 for every tile), if given. Throws ParamError.
    std::optional<Tile> tiling() const;
    /// Whether a print check flag (--min-wall, --min-island, --largest-only) was given.
    bool printCheckAsked() const { return minWall || minIsland > 0 || largestOnly; }
    /// --threads, or defaultThreadCount().
    int threadCount() const;
    /// What an existing output means: refused (the default), replaced (--force) or skipped
    /// (--skip-existing). Throws ParamError for both flags at once.
    void checkExistingFlags() const;
    /// Whether --skip-existing skips the output at `path`: it is complete, since a final file exists
    /// only once written whole. Says so on stderr unless quiet.
    bool skips(const std::string& path) const;
};

/// "out/fractal.vdb", 12 -> "out/fractal_0012.vdb": the numbering Blender reads as a sequence.
std::string framePath(const std::string& path, int frame);

/// The frames of --frames, or frame 1 alone; and the output path of each (numbered only with --frames).
std::vector<std::pair<int, std::string>> framePaths(const BakeFlags& flags);

/// The exit codes as a scheduler reads them, for the commands' --help.
extern const char* const kExitCodesHelp;

/// A progress callback that draws the bar with the bake's stage and evaluated/dense counts.
ProgressCallback bakeProgress(ProgressBar& bar, const BakeMonitor& monitor);

/// "evaluated 3.2M of 16.8M voxels (19%)".
std::string evaluatedSummary(const BakeStats& stats);

/// The lines --stats prints for one bake (stdout), peak memory included.
void printBakeStats(const BakeStats& stats);

}  // namespace dqj::cli
