// dqjulia bake: the fractal as an OpenVDB file (level set "surface", fog volume "density",
// attribute grids), one file or, with --frames, one file per frame of an animation; with
// --tiles, tiles of it for dqjulia merge.
#include <iomanip>
#include <iostream>

#include "bake_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/bake.hpp"
#include "dqjulia/empty_result.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/threads.hpp"
#include "dqjulia/tiles.hpp"
#include "files/message_text.hpp"

namespace dqj::cli {
namespace {

/// The work of one file: which frame (and tile), its parameters and where it goes.
struct Job {
    int frame = 1;
    std::optional<Tile> tile;
    Params params;
    std::string path;
    std::string label;  // "frame 3", "tile 2", "frame 3, tile 2" or ""
};

/// Every file's parameters and output path, checked before the first long bake starts; with
/// --skip-existing, the files that exist are left out (and reported).
std::vector<Job> plan(const BakeFlags& flags, const Params& params) {
    const std::optional<Tile> tiling = flags.tiling();
    const FrameRange range = flags.frameRange().value_or(FrameRange{});  // frame 1 without --frames
    checkFrames(params, range.first, range.last);
    std::vector<Job> jobs;
    for (const auto& [frame, path] : framePaths(flags)) {
        const Params atFrame = dqj::atFrame(params, frame);  // valid: checkFrames
        const std::string frameLabel = flags.frameRange() ? "frame " + std::to_string(frame) : "";
        if (!tiling) {
            jobs.push_back({frame, std::nullopt, atFrame, path, frameLabel});
            continue;
        }
        Tile tile = *tiling;
        const int first = tile.index ? tile.index : 1, last = tile.index ? tile.index : tileCount(tile);
        for (tile.index = first; tile.index <= last; ++tile.index) {
            const std::string tileLabel = "tile " + std::to_string(tile.index);
            checkTile(atFrame, tile);
            jobs.push_back({frame, tile, atFrame, tilePath(path, tile.index),
                            frameLabel.empty() ? tileLabel : frameLabel + ", " + tileLabel});
        }
    }
    std::vector<Job> todo;
    std::vector<NamedPath> outputs;
    for (Job& job : jobs) {
        if (flags.skips(job.path)) continue;
        outputs.push_back({"--output", job.path});
        todo.push_back(std::move(job));
    }
    checkOutputs(outputs, flags.fractal.inputs(), flags.force);
    return todo;
}

int runBake(const BakeFlags& flags) {
    const Params params = flags.load();
    std::string extension = flags.output.size() >= 4 ? flags.output.substr(flags.output.size() - 4) : "";
    for (char& ch : extension) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (extension != ".vdb")
        throw ParamError("output.path", "--output '" + inputExcerpt(flags.output) + "' must end in .vdb");
    const std::uint64_t memoryLimit = flags.memoryLimit();
    flags.checkExistingFlags();
    const std::vector<Job> jobs = plan(flags, params);
    const ThreadLimit threads(flags.threadCount());

    for (std::size_t index = 0; index < jobs.size(); ++index) {
        const Job& job = jobs[index];
        BakeMonitor monitor;
        BakeOptions options;
        options.dense = flags.dense;
        options.memoryLimit = memoryLimit;
        options.monitor = &monitor;
        options.existing = existingPolicy(flags.force);
        options.tile = job.tile;
        const std::string label = jobs.size() > 1 ? "baking " + job.label : "baking";
        BakeStats stats;
        {
            ProgressBar bar(label, flags.quiet);
            try {
                stats = bakeVdb(job.params, job.path, options, bakeProgress(bar, monitor));
            } catch (const Cancelled&) {
                bar.finish();
                if (index == 0) throw;
                std::cerr << "dqjulia bake: interrupted at " << job.label << "; " << jobs.front().label << " to "
                          << jobs[index - 1].label << " were written, " << job.label << " was not\n";
                return kInterrupted;
            }
            bar.finish();
        }
        if (stats.activeVoxels == 0 && !job.tile)  // a tile may lie where the surface is not
            std::cerr << "dqjulia bake: warning: "
                      << emptyResultMessage(EmptyResult::Bake, inspect(job.params).emptyReason, job.path) << "\n";
        if (!flags.quiet)
            std::cerr << "wrote " << job.path << " (" << job.params.bake.resolution << " voxels across, voxel size "
                      << std::setprecision(4) << stats.voxelSize << "; " << evaluatedSummary(stats) << "; "
                      << stats.activeVoxels << " active voxels; " << std::fixed << std::setprecision(2) << stats.seconds
                      << " s)\n"
                      << std::defaultfloat;
        if (flags.stats) {
            if (jobs.size() > 1) std::cout << job.label << "\n";
            printBakeStats(stats);
        }
    }
    return kSuccess;
}

}  // namespace

Runner addBakeCommand(CLI::App& app) {
    auto flags = std::make_shared<BakeFlags>();
    CLI::App* command = app.add_subcommand(
        "bake",
        "Bake an OpenVDB file: level set \"surface\", fog volume \"density\" and attribute grids (docs: Baking)");
    flags->addTo(*command, BakeCommand::Bake);
    return [flags] { return reportErrors("bake", [&] { return runBake(*flags); }); };
}

}  // namespace dqj::cli
