// dqjulia bake: the fractal as an OpenVDB file (level set "surface", fog volume "density",
// attribute grids), one file or, with --frames, one file per frame of an animation.
#include <iomanip>
#include <iostream>

#include "bake_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/bake.hpp"
#include "dqjulia/inspect.hpp"

namespace dqj::cli {
namespace {

/// The work of one file: which frame, its parameters and where it goes.
struct Job {
    int frame = 1;
    Params params;
    std::string path;
};

/// Every frame's parameters and output path, checked before the first long bake starts.
std::vector<Job> plan(const BakeFlags& flags, const Params& params) {
    std::vector<Job> jobs;
    if (const auto range = flags.frameRange()) {
        for (int frame = range->first; frame <= range->last; ++frame)
            jobs.push_back({frame, paramsAtFrame(params, frame), framePath(flags.output, frame)});
    } else {
        jobs.push_back({1, paramsAtFrame(params, 1), flags.output});
    }
    for (const Job& job : jobs) checkOutputPath(job.path, flags.force);
    return jobs;
}

int runBake(const BakeFlags& flags) {
    const Params params = flags.load();
    std::string extension = flags.output.size() >= 4 ? flags.output.substr(flags.output.size() - 4) : "";
    for (char& ch : extension) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (extension != ".vdb") throw ParamError("output.path", "--output '" + flags.output + "' must end in .vdb");
    const std::uint64_t memoryLimit = flags.memoryLimit();
    const std::vector<Job> jobs = plan(flags, params);

    for (std::size_t index = 0; index < jobs.size(); ++index) {
        const Job& job = jobs[index];
        BakeMonitor monitor;
        BakeOptions options;
        options.dense = flags.dense;
        options.memoryLimit = memoryLimit;
        options.monitor = &monitor;
        options.existing = existingPolicy(flags.force);
        const std::string label = jobs.size() > 1 ? "baking frame " + std::to_string(job.frame) : "baking";
        BakeStats stats;
        {
            ProgressBar bar(label, flags.quiet);
            try {
                stats = bakeVdb(job.params, job.path, options, bakeProgress(bar, monitor));
            } catch (const Cancelled&) {
                bar.finish();
                if (index == 0) throw;
                std::cerr << "dqjulia bake: interrupted at frame " << job.frame << "; frames " << jobs.front().frame
                          << " to " << jobs[index - 1].frame << " were written, frame " << job.frame << " was not\n";
                return kInterrupted;
            }
            bar.finish();
        }
        if (stats.activeVoxels == 0) {
            const std::string reason = inspect(job.params).emptyReason;
            std::cerr << "dqjulia bake: warning: " << job.path << " holds no surface: "
                      << (reason.empty()
                              ? "nothing within the bounds is in the set at this resolution; try more iterations or a "
                                "higher resolution"
                              : reason)
                      << "\n";
        }
        if (!flags.quiet)
            std::cerr << "wrote " << job.path << " (" << job.params.bake.resolution << " voxels across, voxel size "
                      << std::setprecision(4) << stats.voxelSize << "; " << evaluatedSummary(stats) << "; "
                      << stats.activeVoxels << " active voxels; " << std::fixed << std::setprecision(2) << stats.seconds
                      << " s)\n"
                      << std::defaultfloat;
        if (flags.stats) {
            if (jobs.size() > 1) std::cout << "frame " << job.frame << "\n";
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
        "Bake an OpenVDB file: level set \"surface\", fog volume \"density\" and attribute grids (README: Baking)");
    flags->addTo(*command, false);
    return [flags] { return reportErrors("bake", [&] { return runBake(*flags); }); };
}

}  // namespace dqj::cli
