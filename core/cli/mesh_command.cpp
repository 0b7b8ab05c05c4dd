// dqjulia mesh: the baked surface as a PLY, OBJ, STL or 3MF mesh, one file or,
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
#include "bake/print_check.hpp"
#include "files/message_text.hpp"

namespace dqj::cli {
namespace {

/// Stops before writing `path` when it is for printing and the check failed, unless
/// --allow-unprintable; else shows the report (a failure always, as a warning).
void refuseUnprintable(const BakeFlags& flags, const std::string& path, const PrintReport& report) {
    const std::string failure = report.failure();
    if (!flags.quiet || !failure.empty()) std::cerr << printReportText(report);
    if (failure.empty()) return;
    if (isPrintFormat(path) && !flags.allowUnprintable)
        throw ParamError("output.path", "not printable, so '" + inputExcerpt(path) + "' was not written: " + failure +
                                            " (--allow-unprintable writes it anyway)");
    std::cerr << "dqjulia mesh: warning: " << path << " is not printable: " << failure << "\n";
}

/// The print check's lines for --stats: key value, the five largest islands numbered from 1.
void printPrintStats(const PrintReport& report) {
    std::cout << "print_closed " << report.closed() << "\nprint_boundary_edges " << report.boundaryEdges
              << "\nprint_edge_manifold " << report.manifold() << "\nprint_nonmanifold_edges "
              << report.nonManifoldEdges << "\n";
    if (!report.islandsCounted) {  // streamed: the edges alone
        std::cout << "print_ok " << report.failure().empty() << "\n";
        return;
    }
    std::cout << "print_islands " << report.islands.size() << "\nprint_dropped_islands " << report.droppedIslands
              << "\nprint_dropped_faces " << report.droppedFaces << "\n";
    for (std::size_t index = 0; index < std::min<std::size_t>(5, report.islands.size()); ++index) {
        const PrintIsland& island = report.islands[index];
        const glm::dvec3 size = island.max - island.min;
        const std::string key = "print_island_" + std::to_string(index + 1);
        std::cout << key << "_faces " << island.faces << "\n"
                  << key << "_size " << size.x << " " << size.y << " " << size.z << "\n"
                  << key << "_volume " << island.volume << "\n";
    }
    if (report.wallMeasured)
        std::cout << "print_thinnest_wall " << report.thinnestWall << "\nprint_wall_found " << report.wallFound << "\n";
    std::cout << "print_ok " << report.failure().empty() << "\n";
}

int runMesh(const BakeFlags& flags) {
    const Params params = flags.load();
    checkMeshPath(flags.output);
    const MeshScale scale = flags.meshScale();
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
    const bool check = isPrintFormat(flags.output) || flags.printCheckAsked();
    PrintOptions print;
    print.minWall = flags.minWall.value_or(0.0);
    print.minIslandFaces = flags.minIsland;
    print.largestOnly = flags.largestOnly;

    for (std::size_t index = 0; index < frames.size(); ++index) {
        BakeMonitor monitor;
        BakeOptions options;
        options.dense = flags.dense;
        options.memoryLimit = memoryLimit;
        options.monitor = &monitor;
        options.existing = existingPolicy(flags.force);
        BakeStats stats;
        MeshCounts mesh;
        PrintReport report;
        {
            ProgressBar bar(frames.size() > 1 ? "meshing frame " + std::to_string(frames[index]) : "meshing",
                            flags.quiet);
            try {
                if (flags.printCheckAsked()) {
                    // Islands and walls: checked whole before it is written; refused, with nothing
                    // written, when unprintable.
                    const ProgressCallback progress = bakeProgress(bar, monitor);
                    const Mesh whole = meshForPrint(perFrame[index], options, print, progress, stats, report, scale);
                    if (progress && !progress(1.0)) throw Cancelled();
                    bar.finish();
                    refuseUnprintable(flags, paths[index], report);
                    writeMesh(whole, paths[index], options.existing, scale);
                    mesh = MeshCounts{whole.positions.size(), whole.quads.size(), whole.triangles.size()};
                } else {
                    // Written as it is made, slab by slab where the memory limit asks for it; the file
                    // appears only complete (a signal in the last moments, too, leaves nothing).
                    // .stl and .3mf: closed and edge-manifold checked as the slabs come, before it is published.
                    std::function<void(const PrintReport&)> approve;
                    if (check)
                        approve = [&](const PrintReport& edges) {
                            report = edges;
                            bar.finish();
                            refuseUnprintable(flags, paths[index], report);
                        };
                    mesh = bakeMeshFileChecked(perFrame[index], paths[index], options, bakeProgress(bar, monitor),
                                               &stats, scale, approve);
                }
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
            if (check) printPrintStats(report);
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
    CLI::App* command =
        app.add_subcommand("mesh", "Mesh the baked surface into a PLY, OBJ, STL or 3MF file (docs: Baking)");
    flags->addTo(*command, BakeCommand::Mesh);
    return [flags] { return reportErrors("mesh", [&] { return runMesh(*flags); }); };
}

}  // namespace dqj::cli
