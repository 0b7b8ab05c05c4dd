// dqjulia inspect: what the constant and slice give, and why a slice is empty.
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/inspect.hpp"

namespace dqj::cli {
namespace {

struct InspectOptions {
    FractalOptions fractal;
    int samples = 32;
    bool json = false;
};

int runInspect(const InspectOptions& options) {
    const Params params = options.fractal.load();
    const InspectReport report = inspect(params, options.samples);
    std::cout << (options.json ? reportJson(report) : formatReport(report));
    return kSuccess;
}

}  // namespace

Runner addInspectCommand(CLI::App& app) {
    auto options = std::make_shared<InspectOptions>();
    CLI::App* command = app.add_subcommand(
        "inspect",
        "Report the variant, containment radius, each part's equivalent complex constant and whether it\n"
        "lies in the Mandelbrot set, the fraction of the slice inside at N, and why a slice is empty");
    options->fractal.addTo(*command);
    command->add_option("--samples", options->samples, "Samples per axis for the inside fraction")
        ->check(CLI::Range(2, 512));
    command->add_flag("--json", options->json, "Print JSON instead of text");
    return [options] { return reportErrors("inspect", [&] { return runInspect(*options); }); };
}

}  // namespace dqj::cli
