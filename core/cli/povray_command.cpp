// dqjulia povray: write a POV-Ray scene that draws what `dqjulia render` draws (and a DF3 grid).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/empty_result.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/povray.hpp"
#include "platform/platform.hpp"
#include "files/message_text.hpp"
#include "files/text_input.hpp"
#include "schema_options.hpp"

namespace dqj::cli {
namespace {

struct PovrayOptions {
    FractalOptions fractal;
    std::string output;
    std::optional<int> width, height, samples;
    std::optional<double> detail, fov;
    std::string coloring;
    bool df3 = false;
    int df3Resolution = 128;
    int df3Bits = 16;
    bool noInclude = false;
    bool force = false;
    bool quiet = false;
};

int runPovray(const PovrayOptions& options) {
    Params params =
        options.fractal.paramsFile.empty() ? Params{} : loadParams(options.fractal.paramsFile, Validation::TypesOnly);
    options.fractal.applyTo(params);
    if (options.width) params.render.width = *options.width;
    if (options.height) params.render.height = *options.height;
    if (options.samples) params.render.samples = *options.samples;
    if (options.detail) params.render.detail = *options.detail;
    if (options.fov) params.camera.fovDegrees = *options.fov;
    if (!options.coloring.empty())
        params.material.coloring = schemaChoice<Coloring>("material.coloring", options.coloring);
    validate(params);
    // An empty picture needs a reason, in POV-Ray as in `dqjulia render`.
    const std::string provenEmpty = provenEmptyReason(params);
    if (!provenEmpty.empty())
        std::cerr << "dqjulia povray: warning: " << emptyResultMessage(EmptyResult::Povray, provenEmpty) << "\n";

    PovrayWriteOptions write;
    write.copyInclude = !options.noInclude;
    write.df3 = options.df3;
    write.df3Resolution = options.df3Resolution;
    write.df3Bits = options.df3Bits;
    write.sourceName = options.fractal.paramsFile;
    write.existing = existingPolicy(options.force);
    // Check every output before the work: existing files need --force. An identical copy of
    // the include is fine (several scenes share one folder); a different one is not replaced silently.
    const PovrayFiles files = povrayFiles(params, options.output, write);
    std::vector<NamedPath> outputs;
    for (const NamedPath& output : {NamedPath{"--output", files.scene}, NamedPath{"--df3 (grid)", files.df3},
                                    NamedPath{"--df3 (scene)", files.df3Scene}})
        if (!output.path.empty()) outputs.push_back(output);
    std::vector<NamedPath> all = outputs;
    if (!files.include.empty()) all.push_back({"the include copy", files.include});
    checkInputsKept(all, options.fractal.inputs());
    checkDistinctOutputs(all);
    for (const NamedPath& output : outputs) checkOutputPath(output.path, options.force, output.flag);
    if (!files.include.empty()) {
        std::error_code error;
        const bool regular = std::filesystem::is_regular_file(platform::pathFromUtf8(files.include), error);
        const bool same = regular && fileHolds(files.include, povrayInclude()) == true;
        if (regular && !same && !options.force)
            throw ParamError("output.path", "'" + inputExcerpt(files.include) +
                                                "' exists and differs from this version's dqjulia.inc; pass --force to "
                                                "replace it, or --no-include to keep it");
        if (!same) checkOutputPath(files.include, options.force);
    }
    if (files.scene.empty())
        std::cerr << "dqjulia povray: N = " << params.fractal.iterations
                  << " is beyond dqjulia.inc's limit of 1000 iterations (POV-Ray's function call depth): "
                     "writing only the DF3 scene\n";
    ProgressBar progress("baking", options.quiet || !options.df3);
    const std::vector<std::string> written = writePovray(params, options.output, write, progress.callback());
    progress.finish();
    if (!options.quiet) {
        for (const std::string& path : written) std::cerr << "wrote " << path << "\n";
        // POV-Ray looks for the include and the DF3 file in the folder it runs in and on its
        // library path, not beside the scene: run it in the scene's folder.
        const std::filesystem::path scene = platform::pathFromUtf8(files.scene.empty() ? files.df3Scene : files.scene);
        std::cerr << "render with: "
                  << (scene.has_parent_path() ? "cd '" + platform::utf8FromPath(scene.parent_path()) + "' && " : "")
                  << povrayCommand(params, platform::utf8FromPath(scene.filename()))
                  << (write.copyInclude ? "" : " +L<dqjulia>/povray") << "\n";
    }
    return kSuccess;
}

}  // namespace

Runner addPovrayCommand(CLI::App& app) {
    auto options = std::make_shared<PovrayOptions>();
    CLI::App* command = app.add_subcommand(
        "povray",
        "Write a POV-Ray 3.7 scene (camera, lights, material, background) that draws what `render` draws,\n"
        "the fractal as an isosurface of the same distance estimate (dqjulia.inc, written beside it)");
    options->fractal.addTo(*command);
    command->add_option("-o,--output", options->output, "Scene file to write, e.g. scene.pov")->required();
    schemaOption(*command, "-W,--width", "render.width", options->width, "The image width the view is framed for");
    schemaOption(*command, "-H,--height", "render.height", options->height, "The image height the view is framed for");
    schemaOption(*command, "-s,--samples", "render.samples", options->samples, "In the scene's render command");
    schemaOption(*command, "--detail", "render.detail", options->detail);
    schemaOption(*command, "--fov", "camera.fov", options->fov);
    schemaOption(*command, "--coloring", "material.coloring", options->coloring);
    command->add_flag("--df3", options->df3,
                      "Also bake <scene>.df3 (the distance estimate on a grid) and <scene>_df3.pov drawing it: fast\n"
                      "renders of heavy settings, at the grid's resolution");
    command->add_option("--df3-resolution", options->df3Resolution, "Samples per axis of the DF3 grid")
        ->check(CLI::Range(kMinDf3Resolution, kMaxDf3Resolution));
    command->add_option("--df3-bits", options->df3Bits, "Bits per DF3 sample: 8, 16 or 32")
        ->check(CLI::IsMember(std::vector<int>(kDf3Bits.begin(), kDf3Bits.end())));
    command->add_flag("--no-include", options->noInclude,
                      "Do not write dqjulia.inc beside the scene (render with +L<dqjulia>/povray)");
    command->add_flag("-f,--force", options->force, "Overwrite existing output files");
    command->add_flag("-q,--quiet", options->quiet, "No progress bar or summary");
    return [options] { return reportErrors("povray", [&] { return runPovray(*options); }); };
}

}  // namespace dqj::cli
