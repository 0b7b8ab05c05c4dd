// dqjulia render: sphere-trace the fractal into a PNG or EXR.
#include <fstream>
#include <iomanip>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/image.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/render.hpp"
#include "image_writer.hpp"
#include "voxel_render.hpp"

namespace dqj::cli {
namespace {

struct RenderOptions {
    FractalOptions fractal;
    std::optional<std::string> output;  // given empty (-o '') is an error, not the default
    std::string format;
    std::optional<int> width, height, samples, maxSteps;
    std::optional<double> stepFactor, maxStep, detail, fov;
    std::string normals, coloring;
    std::vector<double> cameraPosition, cameraTarget;
    std::string saveParams;
    bool saveParamsGiven = false;
    std::string voxels;
    bool quiet = false;
    bool stats = false;
    bool force = false;
};

Params loadRenderParams(const RenderOptions& options) {
    Params params =
        options.fractal.paramsFile.empty() ? Params{} : loadParams(options.fractal.paramsFile, Validation::TypesOnly);
    options.fractal.applyTo(params);
    if (options.output) {
        if (options.output->empty()) throw ParamError("output.path", "--output is empty; give a file name");
        params.output.path = *options.output;
    }
    if (!options.format.empty()) {
        params.output.format = options.format == "png16" ? ImageFormat::Png16
                               : options.format == "exr" ? ImageFormat::Exr
                                                         : ImageFormat::Png8;
    }
    RenderSettings& render = params.render;
    if (options.width) render.width = *options.width;
    if (options.height) render.height = *options.height;
    if (options.samples) render.samples = *options.samples;
    if (options.maxSteps) render.maxSteps = *options.maxSteps;
    if (options.stepFactor) render.stepFactor = *options.stepFactor;
    if (options.maxStep) render.maxStep = *options.maxStep;
    if (options.detail) render.detail = *options.detail;
    if (options.fov) params.camera.fovDegrees = *options.fov;
    if (!options.normals.empty())
        render.normals = options.normals == "central"    ? NormalMethod::CentralDifferences
                         : options.normals == "analytic" ? NormalMethod::Analytic
                                                         : NormalMethod::Auto;
    if (!options.coloring.empty())
        params.material.coloring = options.coloring == "solid"        ? Coloring::Solid
                                   : options.coloring == "iterations" ? Coloring::Iterations
                                                                      : Coloring::Trap;
    if (!options.cameraPosition.empty())
        params.camera.position =
            glm::dvec3(options.cameraPosition[0], options.cameraPosition[1], options.cameraPosition[2]);
    if (!options.cameraTarget.empty())
        params.camera.target = glm::dvec3(options.cameraTarget[0], options.cameraTarget[1], options.cameraTarget[2]);
    validate(params);
    return params;
}

int runRender(const RenderOptions& options) {
    const Params params = loadRenderParams(options);
    std::vector<NamedPath> outputs{{"--output", params.output.path}};
    if (options.saveParamsGiven) outputs.push_back({"--save-params", options.saveParams});
    std::vector<NamedPath> inputs = options.fractal.inputs();
    if (!options.voxels.empty()) inputs.push_back({"--voxels", options.voxels});
    checkOutputs(outputs, inputs, options.force);
    // The image and the parameter file are published together, once the image is done: both or neither.
    AtomicFileSet files(existingPolicy(options.force));
    if (options.saveParamsGiven) files.add(options.saveParams).stream() << toJson(params);
    // Say up front when the slice is provably empty: an empty picture needs a reason.
    const std::string provenEmpty = provenEmptyReason(params);
    if (!provenEmpty.empty()) std::cerr << "dqjulia render: warning: " << provenEmpty << "\n";

    ProgressBar progress("rendering", options.quiet);
    const RenderResult result = options.voxels.empty() ? render(params, progress.callback())
                                                       : renderVoxels(params, options.voxels, progress.callback());
    progress.finish();
    if (interrupted()) throw Cancelled();  // a signal in the last moments of the work: write nothing
    writeImage(result.image, files.add(params.output.path), formatFor(params.output));
    files.commit();

    const RenderStats& stats = result.stats;
    if (stats.hitPixels == 0) {
        const std::string reason = provenEmpty.empty() ? inspect(params).emptyReason : provenEmpty;
        std::cerr
            << "dqjulia render: warning: the image shows no surface: "
            << (reason.empty()
                    ? "no ray came within the hit threshold; try more iterations, a larger --detail or another camera"
                    : reason)
            << "\n";
    }
    if (!options.quiet)
        std::cerr << "wrote " << params.output.path << " (" << params.render.width << "x" << params.render.height
                  << ", " << stats.hitPixels << " pixels on the surface, " << std::fixed << std::setprecision(2)
                  << stats.seconds << " s)" << (options.saveParamsGiven ? " and " + options.saveParams : "") << "\n";
    if (options.stats)
        std::cout << "rays " << stats.rays << "\nsteps " << stats.steps << "\nsteps_per_ray "
                  << (stats.rays ? double(stats.steps) / double(stats.rays) : 0.0) << "\nevaluations "
                  << stats.evaluations << "\nevaluations_per_ray "
                  << (stats.rays ? double(stats.evaluations) / double(stats.rays) : 0.0) << "\nhit_pixels "
                  << stats.hitPixels << "\nseconds " << stats.seconds << "\n";
    return kSuccess;
}

}  // namespace

Runner addRenderCommand(CLI::App& app) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* command = app.add_subcommand("render", "Render an image by sphere tracing the distance estimate");
    options->fractal.addTo(*command);
    command->add_option("-o,--output", options->output,
                        "Output image: .png (8-bit sRGB) or .exr (linear, depth, normals)");
    command->add_option("--format", options->format, "png8, png16 or exr (default: from the file name)")
        ->check(CLI::IsMember({"png8", "png16", "exr"}));
    command->add_option("-W,--width", options->width, "Image width in pixels");
    command->add_option("-H,--height", options->height, "Image height in pixels");
    command->add_option("-s,--samples", options->samples, "Anti-aliasing: S x S rays per pixel");
    command->add_option("--step-factor", options->stepFactor, "Fraction of the distance estimate per step (0..1]");
    command->add_option("--max-step", options->maxStep, "Largest step in slice units");
    command->add_option("--max-steps", options->maxSteps, "Most steps per ray");
    command->add_option("--detail", options->detail, "Hit threshold in pixel footprints (smaller = finer)");
    command->add_option("--fov", options->fov, "Vertical field of view in degrees");
    command->add_option("--normals", options->normals, "auto, central or analytic (dual variant)")
        ->check(CLI::IsMember({"auto", "central", "analytic"}));
    command->add_option("--coloring", options->coloring, "solid, iterations or trap")
        ->check(CLI::IsMember({"solid", "iterations", "trap"}));
    command->add_option("--camera-position", options->cameraPosition, "Camera position x y z")->expected(3);
    command->add_option("--camera-target", options->cameraTarget, "Camera target x y z")->expected(3);
    command->add_option("--save-params", options->saveParams, "Also write the complete parameter file used");
    command
        ->add_option("--voxels", options->voxels,
                     "Draw the voxels of a baked VDB (its density grid) as cubes instead of tracing the fractal")
        ->check(existingFile());
    command->add_flag("-f,--force", options->force, "Overwrite existing output files");
    command->add_flag("-q,--quiet", options->quiet, "No progress bar or summary");
    command->add_flag("--stats", options->stats, "Print ray and step counts to stdout");
    return [options, command] {
        options->saveParamsGiven = command->count("--save-params") != 0;
        return reportErrors("render", [&] { return runRender(*options); });
    };
}

}  // namespace dqj::cli
