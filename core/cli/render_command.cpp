// dqjulia render: sphere-trace the fractal into a PNG or EXR.
#include <fstream>
#include <iomanip>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/image.hpp"
#include "dqjulia/empty_result.hpp"
#include "dqjulia/render.hpp"
#include "render/image_writer.hpp"
#include "schema_options.hpp"
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
    if (!options.format.empty()) params.output.format = schemaChoice<ImageFormat>("output.format", options.format);
    RenderSettings& render = params.render;
    if (options.width) render.width = *options.width;
    if (options.height) render.height = *options.height;
    if (options.samples) render.samples = *options.samples;
    if (options.maxSteps) render.maxSteps = *options.maxSteps;
    if (options.stepFactor) render.stepFactor = *options.stepFactor;
    if (options.maxStep) render.maxStep = *options.maxStep;
    if (options.detail) render.detail = *options.detail;
    if (options.fov) params.camera.fovDegrees = *options.fov;
    if (!options.normals.empty()) render.normals = schemaChoice<NormalMethod>("render.normals", options.normals);
    if (!options.coloring.empty())
        params.material.coloring = schemaChoice<Coloring>("material.coloring", options.coloring);
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
    ProgressBar progress("rendering", options.quiet);
    const RenderResult result = options.voxels.empty() ? render(params, progress.callback())
                                                       : renderVoxels(params, options.voxels, progress.callback());
    progress.finish();
    if (interrupted()) throw Cancelled();  // a signal in the last moments of the work: write nothing
    writeImage(result.image, files.add(params.output.path), formatFor(params.output));
    files.commit();

    const RenderStats& stats = result.stats;
    // An empty picture needs a reason: the render's own (render.hpp).
    if (stats.hitPixels == 0)
        std::cerr << "dqjulia render: warning: " << emptyResultMessage(EmptyResult::Render, result.emptyReason) << "\n";
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
    schemaOption(*command, "-o,--output", "output.path", options->output,
                 "PNG: 8-bit sRGB (16-bit with --format png16); EXR: linear, with depth and normals");
    schemaOption(*command, "--format", "output.format", options->format);
    schemaOption(*command, "-W,--width", "render.width", options->width);
    schemaOption(*command, "-H,--height", "render.height", options->height);
    schemaOption(*command, "-s,--samples", "render.samples", options->samples);
    schemaOption(*command, "--step-factor", "render.step_factor", options->stepFactor);
    schemaOption(*command, "--max-step", "render.max_step", options->maxStep);
    schemaOption(*command, "--max-steps", "render.max_steps", options->maxSteps);
    schemaOption(*command, "--detail", "render.detail", options->detail);
    schemaOption(*command, "--fov", "camera.fov", options->fov);
    schemaOption(*command, "--normals", "render.normals", options->normals);
    schemaOption(*command, "--coloring", "material.coloring", options->coloring);
    schemaOption(*command, "--camera-position", "camera.position", options->cameraPosition);
    schemaOption(*command, "--camera-target", "camera.target", options->cameraTarget);
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
