// dqjulia mesh: the baked surface as a PLY or OBJ mesh (normals, vertex colours), one file or,
// with --frames, one file per frame of an animation.
#include <iomanip>
#include <iostream>

#include "bake_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/empty_result.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/mesh.hpp"
#include "dqjulia/threads.hpp"
#include "files/message_text.hpp"

namespace dqj::cli {
namespace {

int runMesh(const BakeFlags& flags) {
    const Params params = flags.load();
    std::string extension = flags.output.size() >= 4 ? flags.output.substr(flags.output.size() - 4) : "";
    for (char& ch : extension) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (extension != ".ply" && extension != ".obj")
        throw ParamError("output.path", "--output '" + inputExcerpt(flags.output) + "' must end in .ply or .obj");
    const std::uint64_t memoryLimit = flags.memoryLimit();

    flags.checkExistingFlags();
    std::vector<int> frames;
    std::vector<Params> perFrame;
    std::vector<std::string> paths;
    const FrameRange range = flags.frameRange().value_or(FrameRange{});  // frame 1 without --frames
    checkFrames(params, range.first, range.last);
    for (const auto& [frame, path] : framePaths(flags)) {
        if (flags.skips(path)) continue;
        frames.push_back(frame);
        perFrame.push_back(atFrame(params, frame));  // valid: checkFrames
        paths.push_back(path);
    }
    std::vector<NamedPath> outputs;
    outputs.reserve(paths.size());
    for (const std::string& path : paths) outputs.push_back({"--output", path});
    checkOutputs(outputs, flags.fractal.inputs(), flags.force);
    const ThreadLimit threads(flags.threadCount());

    for (std::size_t index = 0; index < frames.size(); ++index) {
        BakeMonitor monitor;
        BakeOptions options;
        options.dense = flags.dense;
        options.memoryLimit = memoryLimit;
        options.monitor = &monitor;
        options.existing = existingPolicy(flags.force);
        BakeStats stats;
        MeshCounts mesh;
        {
            ProgressBar bar(frames.size() > 1 ? "meshing frame " + std::to_string(frames[index]) : "meshing",
                            flags.quiet);
            try {
                // Written as it is made, slab by slab where the memory limit asks for it; the file
                // appears only complete (a signal in the last moments, too, leaves nothing).
                mesh = bakeMeshFile(perFrame[index], paths[index], options, bakeProgress(bar, monitor), &stats);
            } catch (const Cancelled&) {
                bar.finish();
                if (index == 0) throw;
                std::cerr << "dqjulia mesh: interrupted at frame " << frames[index] << "; frames " << frames.front()
                          << " to " << frames[index - 1] << " were written, frame " << frames[index] << " was not\n";
                return kInterrupted;
            }
            bar.finish();
        }
        const std::uint64_t faces = mesh.quads + mesh.triangles;
        if (mesh.vertices == 0)
            std::cerr << "dqjulia mesh: warning: "
                      << emptyResultMessage(EmptyResult::Mesh, inspect(perFrame[index]).emptyReason, paths[index])
                      << "\n";
        if (!flags.quiet)
            std::cerr << "wrote " << paths[index] << " (" << mesh.vertices << " vertices, " << faces << " faces"
                      << (stats.slabs > 1 ? ", meshed in " + std::to_string(stats.slabs) + " slabs" : "") << "; "
                      << evaluatedSummary(stats) << "; " << std::fixed << std::setprecision(2) << stats.seconds
                      << " s)\n"
                      << std::defaultfloat;
        if (!flags.quiet && stats.fullTriangles > 0)
            std::cerr << "simplified from " << stats.fullTriangles << " triangles (adaptivity " << stats.adaptivity
                      << "): every vertex within " << std::fixed << std::setprecision(2) << stats.deviationVertices
                      << " voxels of the full mesh, every face within " << stats.deviationSamples << "\n"
                      << std::defaultfloat;
        if (flags.stats) {
            if (frames.size() > 1) std::cout << "frame " << frames[index] << "\n";
            printBakeStats(stats);
            std::cout << "slabs " << stats.slabs << "\nvertices " << mesh.vertices << "\nfaces " << faces << "\nquads "
                      << mesh.quads << "\ntriangles " << mesh.triangles << "\ntriangulated "
                      << mesh.triangles + 2 * mesh.quads << "\n";
            if (stats.fullTriangles > 0)
                std::cout << "full_triangles " << stats.fullTriangles << "\nadaptivity " << stats.adaptivity
                          << "\ndeviation_vertices " << stats.deviationVertices << "\ndeviation_faces "
                          << stats.deviationSamples << "\n";
        }
    }
    return kSuccess;
}

}  // namespace

Runner addMeshCommand(CLI::App& app) {
    auto flags = std::make_shared<BakeFlags>();
    CLI::App* command = app.add_subcommand("mesh", "Mesh the baked surface into a PLY or OBJ file (docs: Baking)");
    flags->addTo(*command, BakeCommand::Mesh);
    return [flags] { return reportErrors("mesh", [&] { return runMesh(*flags); }); };
}

}  // namespace dqj::cli
