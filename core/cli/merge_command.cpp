// dqjulia merge: the tiles of a tiled bake (dqjulia bake --tiles) joined into the file the
// one-piece bake writes (tiles.hpp), for one file or, with --frames, each frame of a sequence.
#include <filesystem>
#include <iomanip>
#include <iostream>

#include "bake_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/threads.hpp"
#include "dqjulia/tiles.hpp"
#include "platform/platform.hpp"
#include "files/message_text.hpp"

namespace dqj::cli {
namespace {

struct MergeFlags {
    std::vector<std::string> inputs;
    BakeFlags bake;  // its output, frames, tiles, threads and the flags for existing outputs
};

int runMerge(const MergeFlags& flags) {
    const BakeFlags& bake = flags.bake;
    bake.checkExistingFlags();
    const std::optional<Tile> tiling = bake.tiling();
    if (flags.inputs.empty() == !tiling)
        throw ParamError("tiles", flags.inputs.empty()
                                      ? "give the tiles to merge (NAME.tile_*.vdb), or --tiles AxBxC to merge "
                                        "NAME.tile_1.vdb ... beside --output"
                                      : "give the tiles to merge or --tiles, not both");
    if (!flags.inputs.empty() && bake.frameRange())
        throw ParamError("frames", "--frames goes with --tiles: the tiles' names come from --output then");

    // Each output and its tiles, all checked before the first merge starts: no output is one of the tiles.
    std::vector<std::pair<std::string, std::vector<std::string>>> merges;
    std::vector<NamedPath> outputs, tiles;
    for (const auto& [frame, path] : framePaths(bake)) {
        std::vector<std::string> inputs = flags.inputs;
        for (int index = 1; tiling && index <= tileCount(*tiling); ++index) inputs.push_back(tilePath(path, index));
        if (bake.skips(path)) continue;
        std::string missing;
        for (const std::string& input : inputs)
            if (std::error_code error; !std::filesystem::is_regular_file(platform::pathFromUtf8(input), error))
                missing += (missing.empty() ? "'" : ", '") + inputExcerpt(input) + "'";
        if (!missing.empty())
            throw ParamError("tiles", "no tile " + missing + ": bake it first (dqjulia bake --tiles)");
        outputs.push_back({"--output", path});
        for (const std::string& input : inputs) tiles.push_back({"the tile", input});
        merges.emplace_back(path, std::move(inputs));
    }
    checkOutputs(outputs, tiles, bake.force);
    const std::uint64_t memoryLimit = bake.memoryLimit();
    const ThreadLimit threads(bake.threadCount());
    for (const auto& [path, inputs] : merges) {
        MergeStats stats;
        {
            ProgressBar bar(merges.size() > 1 ? "merging " + path : "merging", bake.quiet);
            stats = mergeTiles(inputs, path, existingPolicy(bake.force), bar.callback(), memoryLimit);
            bar.finish();
        }
        if (!bake.quiet)
            std::cerr << "wrote " << path << " (" << stats.tiles << " tiles; " << stats.activeVoxels
                      << " active voxels; " << std::fixed << std::setprecision(2) << stats.seconds << " s)\n"
                      << std::defaultfloat;
        if (bake.stats) {
            std::cout << "output " << path << "\ntiles " << stats.tiles << "\nactive_voxels " << stats.activeVoxels
                      << "\ntile_bytes " << stats.tileBytes << "\nseconds " << stats.seconds << "\npeak_memory_bytes "
                      << platform::peakMemoryBytes() << "\n";
        }
    }
    return kSuccess;
}

}  // namespace

Runner addMergeCommand(CLI::App& app) {
    auto flags = std::make_shared<MergeFlags>();
    CLI::App* command = app.add_subcommand(
        "merge", "Merge the tiles of dqjulia bake --tiles into the one-piece bake's file (docs: Baking and farms)");
    command->add_option("tiles", flags->inputs, "The tiles: NAME.tile_*.vdb (every tile of one bake, any order)");
    command->add_option("-o,--output", flags->bake.output, "The merged OpenVDB file (.vdb)")->required();
    command->add_option("--tiles", flags->bake.tiles,
                        "Instead of naming the tiles: merge NAME.tile_1.vdb ... of this AxBxC tiling beside --output");
    command->add_option("--frames", flags->bake.frames,
                        "With --tiles: merge frames FIRST-LAST, NAME_0001.tile_K.vdb into NAME_0001.vdb, ...");
    command
        ->add_option("--threads", flags->bake.threads,
                     "Threads to use (default: SLURM_CPUS_PER_TASK, else the CPUs this process may run on)")
        ->check(CLI::Range(1, kMaxThreadCount));
    command->add_option("--max-memory", flags->bake.maxMemory,
                        "Refuse when the estimate exceeds this, e.g. 4G or 512M (default: half the available memory)");
    command->add_flag("--skip-existing", flags->bake.skipExisting, "Skip the outputs that exist: they are complete");
    command->add_flag("-f,--force", flags->bake.force, "Overwrite existing output files");
    command->add_flag("-q,--quiet", flags->bake.quiet, "No progress bar or summary");
    command->add_flag("--stats", flags->bake.stats, "Print tiles, active voxels, time and peak memory to stdout");
    command->footer(kExitCodesHelp);
    return [flags] { return reportErrors("merge", [&] { return runMerge(*flags); }); };
}

}  // namespace dqj::cli
