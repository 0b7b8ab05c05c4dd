#include "bake_options.hpp"

#include "dqjulia/threads.hpp"
#include "platform/platform.hpp"
#include "files/message_text.hpp"
#include "schema_options.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace dqj::cli {
namespace {

std::string shortCount(std::uint64_t count) {
    char text[32];
    if (count >= 1000000000)
        std::snprintf(text, sizeof text, "%.2fG", count / 1e9);
    else if (count >= 1000000)
        std::snprintf(text, sizeof text, "%.1fM", count / 1e6);
    else if (count >= 1000)
        std::snprintf(text, sizeof text, "%.1fk", count / 1e3);
    else
        std::snprintf(text, sizeof text, "%llu", static_cast<unsigned long long>(count));
    return text;
}

std::string percent(std::uint64_t part, std::uint64_t whole) {
    char text[16];
    std::snprintf(text, sizeof text, "%.1f%%", whole ? 100.0 * double(part) / double(whole) : 0.0);
    return text;
}

int parseFrame(const std::string& text, const std::string& whole) {
    std::size_t used = 0;
    long value = -1;
    try {
        value = std::stol(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (text.empty() || used != text.size() || value < 0 || value > 999999 || text[0] == '+' || text[0] == '-')
        throw ParamError("frames", "--frames \"" + inputExcerpt(whole) +
                                       "\": expected FIRST-LAST with whole frame numbers from 0 to 999999, e.g. 1-48");
    return int(value);
}

}  // namespace

const char* const kExitCodesHelp =
    "Exit status: 0 done (also when --skip-existing found everything done); 1 failed while working (I/O, "
    "memory ran out, an output appeared meanwhile): a retry may help, and with --skip-existing redoes only what "
    "is missing; 2 bad input (flags, parameters, tiles that do not belong together, an existing output): a "
    "retry cannot help until the input changes; 130 interrupted (Ctrl-C, SIGTERM, SIGHUP: a preempted task): "
    "a retry helps.";

void BakeFlags::addTo(CLI::App& command, BakeCommand kind) {
    const bool mesh = kind == BakeCommand::Mesh;
    fractal.addTo(command);
    command
        .add_option("-o,--output", output,
                    mesh                        ? "Output mesh: .ply (binary), .obj, .stl (binary; no colours) or .3mf "
                                                  "(vertex colours)"
                    : kind == BakeCommand::Farm ? "The bake's output file (.vdb), on storage every machine shares"
                                                : "Output OpenVDB file (.vdb)")
        ->required();
    schemaOption(command, "-r,--resolution", "bake.resolution", resolution);
    schemaOption(command, "--bounds-min", "bake.bounds.min", boundsMin, "Bakes only this box (with --bounds-max)");
    schemaOption(command, "--bounds-max", "bake.bounds.max", boundsMax, "Bakes only this box (with --bounds-min)");
    if (mesh) {
        schemaOption(command, "--adaptivity", "bake.adaptivity", adaptivity);
        schemaOffFlag(command, "--no-colors", "bake.mesh_colors", noColors);
        command.add_option("--units", units,
                           "The mesh's length unit: mm, cm, m or in; the unit of --size, and a .3mf's unit "
                           "(default mm). Without --size the coordinates are the slice's, whatever the unit");
        command.add_option("--size", size,
                           "Scale the mesh so that its largest side is SIZE --units long (needs --units), its least "
                           "corner at 0 (for printing; up to 1 km); every format");
        // The print check: always for .stl and .3mf, else with any of its flags.
        command
            .add_option("--min-wall", minWall,
                        "Print check: walls thinner than W (output units, measured on the mesh's distance field) "
                        "fail it; .stl and .3mf are then not written (docs: Baking, Printing)")
            ->check(CLI::PositiveNumber);
        command.add_option("--min-island", minIsland,
                           "Print check: drop the islands (parts not connected to the rest) of fewer than N faces");
        command.add_flag("--largest-only", largestOnly, "Print check: keep only the island with the most faces");
        command.add_flag("--allow-unprintable", allowUnprintable,
                         "Write .stl and .3mf even when the print check fails (not closed, not edge-manifold, a wall "
                         "under --min-wall): the report still names the problems");
        schemaOption(command, "--faces", "bake.max_faces", faces,
                     "Made in one piece: past the memory limit's one-piece mesh it is refused before sampling");
    } else {
        schemaOption(command, "--grids", "bake.grids", grids);
        schemaOption(command, "--band-width", "bake.band_width", bandWidth);
    }
    command.add_option(
        "--frames", frames,
        "Keyframed parameters: bake frames FIRST-LAST (0-999999) into NAME_0001.EXT, ... (or one frame); "
        "every frame's parameters are checked first, a million in about 0.2 s (2 s with 28 "
        "animated rotations of the slice)");
    if (kind != BakeCommand::Mesh)
        command.add_option("--tiles", tiles,
                           "Bake in AxBxC tiles on the whole bake's grid, into NAME.tile_K.vdb (K from 1, x fastest); "
                           "dqjulia merge joins them (docs: Baking and farms)");
    if (kind == BakeCommand::Farm) {
        command.add_flag("-f,--force", force, "Overwrite the script files");
        return;
    }
    if (kind == BakeCommand::Bake)
        command.add_option("--tile", tile, "With --tiles: bake tile K alone (default: every tile, one after another)");
    command.add_option("--max-memory", maxMemory,
                       kind == BakeCommand::Mesh
                           ? "Mesh in slabs, each written as it is made, when the estimate in one piece exceeds this, "
                             "and refuse when even the thinnest slab does; e.g. 4G or 512M (default: half the "
                             "available memory)"
                           : "Refuse when the estimate exceeds this, e.g. 4G or 512M (default: half the available "
                             "memory)");
    command
        .add_option("--threads", threads,
                    "Threads to use (default: SLURM_CPUS_PER_TASK, else the CPUs this process may run on)")
        ->check(CLI::Range(1, kMaxThreadCount));
    command.add_flag("--skip-existing", skipExisting,
                     "Skip the frames (and tiles) whose output file exists: they are complete, since files get their "
                     "name only when complete");
    command.add_flag("--dense", dense, "Evaluate every voxel instead of skipping empty blocks (slow; for comparisons)");
    command.add_flag("-f,--force", force, "Overwrite existing output files");
    command.add_flag("-q,--quiet", quiet, "No progress bar or summary");
    command.add_flag("--stats", stats,
                     "Print time, voxels evaluated against dense, active voxels and peak memory to stdout");
    command.footer(kExitCodesHelp);
}

std::optional<Tile> BakeFlags::tiling() const {
    if (tiles.empty()) {
        if (tile) throw ParamError("tiles", "--tile goes with --tiles AxBxC: give the tiling too");
        return std::nullopt;
    }
    Tile result;
    try {
        result = parseTiling(tiles);
    } catch (const ParamError& error) {
        throw ParamError(error.key(), std::string("--") + error.what());
    }
    result.index = tile.value_or(0);
    if (tile && (*tile < 1 || *tile > tileCount(result)))
        throw ParamError("tiles", "--tile " + std::to_string(*tile) + ": the tiling " + tilingText(result) +
                                      " has tiles 1 to " + std::to_string(tileCount(result)));
    return result;
}

int BakeFlags::threadCount() const { return threads.value_or(defaultThreadCount()); }

void BakeFlags::checkExistingFlags() const {
    if (force && skipExisting)
        throw ParamError("output.path",
                         "--force replaces existing outputs and --skip-existing keeps them: give one of the two");
}

bool BakeFlags::skips(const std::string& path) const {
    if (!skipExisting || !std::filesystem::is_regular_file(platform::pathFromUtf8(path))) return false;
    if (!quiet) std::cerr << "skipped " << path << ": it exists (--skip-existing)\n";
    return true;
}

std::vector<std::pair<int, std::string>> framePaths(const BakeFlags& flags) {
    std::vector<std::pair<int, std::string>> result;
    if (const auto range = flags.frameRange()) {
        for (int frame = range->first; frame <= range->last; ++frame)
            result.emplace_back(frame, framePath(flags.output, frame));
    } else {
        result.emplace_back(1, flags.output);
    }
    return result;
}

Params BakeFlags::load() const {
    Params params = fractal.paramsFile.empty() ? Params{} : loadParams(fractal.paramsFile, Validation::TypesOnly);
    fractal.applyTo(params);
    BakeSettings& bake = params.bake;
    if (resolution) bake.resolution = *resolution;
    if (boundsMin.empty() != boundsMax.empty())
        throw ParamError("bake.bounds", "--bounds-min and --bounds-max go together: give both corners of the box");
    if (!boundsMin.empty())
        bake.bounds = Box{{boundsMin[0], boundsMin[1], boundsMin[2]}, {boundsMax[0], boundsMax[1], boundsMax[2]}};
    if (bandWidth) bake.bandWidth = *bandWidth;
    if (adaptivity) bake.adaptivity = *adaptivity;
    if (noColors) bake.meshColors = false;
    if (faces) bake.maxFaces = *faces;
    if (!grids.empty()) {  // names the option's check accepted; one named twice is written once
        bake.grids.clear();
        std::size_t start = 0;
        while (start <= grids.size()) {
            const std::size_t comma = std::min(grids.find(',', start), grids.size());
            const auto grid = schemaChoice<BakeGrid>("bake.grids", grids.substr(start, comma - start));
            if (!hasGrid(bake, grid)) bake.grids.push_back(grid);
            start = comma + 1;
        }
    }
    validate(params);
    return params;
}

std::optional<FrameRange> BakeFlags::frameRange() const {
    if (frames.empty()) return std::nullopt;
    const std::size_t dash = frames.find('-');
    FrameRange range;
    range.first = parseFrame(frames.substr(0, dash), frames);
    range.last = dash == std::string::npos ? range.first : parseFrame(frames.substr(dash + 1), frames);
    if (range.last < range.first)
        throw ParamError("frames", "--frames \"" + inputExcerpt(frames) +
                                       "\": the last frame comes before the first; write FIRST-LAST, e.g. 1-48");
    return range;
}

MeshScale BakeFlags::meshScale() const {
    MeshScale scale;
    if (!units.empty()) {
        static const std::pair<const char*, MeshUnit> kUnits[] = {{"mm", MeshUnit::Millimeter},
                                                                  {"cm", MeshUnit::Centimeter},
                                                                  {"m", MeshUnit::Meter},
                                                                  {"in", MeshUnit::Inch}};
        const auto known =
            std::find_if(std::begin(kUnits), std::end(kUnits), [&](const auto& unit) { return units == unit.first; });
        if (known == std::end(kUnits))
            throw ParamError("mesh.units", "--units \"" + inputExcerpt(units) + "\": expected mm, cm, m or in");
        scale.unit = known->second;
    }
    if (!size) return scale;
    const std::string& text = *size;
    if (units.empty())
        throw ParamError("mesh.size", "--size " + inputExcerpt(text) +
                                          " needs --units (mm, cm, m or in): a print's size means nothing without one");
    std::size_t used = 0;
    try {
        scale.size = std::stod(text, &used);  // nan and inf too: checkMeshScale refuses them
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != text.size())
        throw ParamError("mesh.size", "--size \"" + inputExcerpt(text) + "\": expected a number, e.g. 120");
    checkMeshScale(scale);
    return scale;
}

std::uint64_t BakeFlags::memoryLimit() const {
    if (maxMemory.empty()) return 0;
    const std::string message =
        "--max-memory \"" + inputExcerpt(maxMemory) + "\": expected a size such as 512M, 4G or 1.5G (or bytes)";
    std::size_t used = 0;
    double value = 0.0;
    try {
        value = std::stod(maxMemory, &used);
    } catch (const std::exception&) {
        throw ParamError("max-memory", message);
    }
    std::string unit = maxMemory.substr(used);
    if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b')) unit.pop_back();
    double scale = 1.0;
    if (unit == "k" || unit == "K")
        scale = 1e3;
    else if (unit == "M" || unit == "m")
        scale = 1e6;
    else if (unit == "G" || unit == "g")
        scale = 1e9;
    else if (unit == "T" || unit == "t")
        scale = 1e12;
    else if (!unit.empty())
        throw ParamError("max-memory", message);
    if (!std::isfinite(value) || value * scale < 1.0 || value * scale > 1e18) throw ParamError("max-memory", message);
    return std::uint64_t(value * scale);
}

std::string framePath(const std::string& path, int frame) {
    const std::size_t slash = path.find_last_of('/');
    std::size_t dot = path.rfind('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) dot = path.size();
    char number[16];
    std::snprintf(number, sizeof number, "_%04d", frame);
    return path.substr(0, dot) + number + path.substr(dot);
}

ProgressCallback bakeProgress(ProgressBar& bar, const BakeMonitor& monitor) {
    ProgressCallback draw = bar.callback();
    return [&bar, &monitor, draw](double fraction) {
        const std::uint32_t slabs = monitor.slabs.load();
        bar.setStatus(
            std::string(bakeStageName(monitor.stage.load())) +
            (slabs > 1 ? " slab " + std::to_string(monitor.slab.load()) + " of " + std::to_string(slabs) : "") + ", " +
            shortCount(monitor.evaluated.load()) + " of " + shortCount(monitor.dense.load()) + " voxels evaluated");
        return draw(fraction);
    };
}

std::string evaluatedSummary(const BakeStats& stats) {
    return "evaluated " + shortCount(stats.evaluated) + " of " + shortCount(stats.dense) + " voxels (" +
           percent(stats.evaluated, stats.dense) + ")";
}

void printBakeStats(const BakeStats& stats) {
    std::cout << "seconds " << stats.seconds << "\n"
              << "voxel_size " << stats.voxelSize << "\n"
              << "voxels_evaluated " << stats.evaluated << "\n"
              << "voxels_dense " << stats.dense << "\n"
              << "evaluated_fraction " << (stats.dense ? double(stats.evaluated) / double(stats.dense) : 0.0) << "\n"
              << "sampled_leaves " << stats.sampledLeaves << "\n"
              << "interior_leaves " << stats.interiorLeaves << "\n"
              << "pruned_leaves " << stats.prunedLeaves << "\n"
              << "active_voxels " << stats.activeVoxels << "\n"
              << "estimated_bytes " << stats.estimatedBytes << "\n"
              << "peak_memory_bytes " << platform::peakMemoryBytes() << "\n";
}

}  // namespace dqj::cli
