// dqjulia explore: a contact sheet of random constants (seeded), one parameter file per tile.
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "contact_sheet.hpp"
#include "explore.hpp"
#include "dqjulia/render.hpp"
#include "file_names.hpp"
#include "message_text.hpp"

namespace dqj::cli {
namespace {

struct ExploreCommandOptions {
    FractalOptions fractal;
    std::uint64_t seed = 1;
    int count = 12;
    int columns = 4;
    int width = 240;
    int height = 180;
    int samples = 1;
    std::string folder = "out/explore";
    bool force = false;
    bool quiet = false;
};

int runExplore(const ExploreCommandOptions& options) {
    Params base = options.fractal.load();
    base.render.width = options.width;
    base.render.height = options.height;
    base.render.samples = options.samples;
    validate(base);

    namespace fs = std::filesystem;
    const fs::path folder = pathFromUtf8(options.folder);
    const fs::path sheetPath = folder / "sheet.png";
    std::error_code error;
    fs::create_directories(folder, error);
    if (error)
        throw std::runtime_error("cannot create folder '" + inputExcerpt(options.folder) + "': " + error.message());
    checkOutputPath(utf8FromPath(sheetPath), options.force, "--output");

    ExploreOptions exploreOptions;
    exploreOptions.seed = options.seed;
    exploreOptions.count = options.count;
    const ExploreResult found = explore(base, exploreOptions);
    if (found.tiles.empty())
        throw std::runtime_error("no constant with a non-empty slice in " + std::to_string(found.attempts) +
                                 " attempts; try fewer iterations or another slice");

    ProgressBar progress("exploring", options.quiet);
    std::vector<SheetTile> tiles;
    for (std::size_t index = 0; index < found.tiles.size(); ++index) {
        Params tile = found.tiles[index];
        char name[32];
        std::snprintf(name, sizeof name, "tile_%02zu", index + 1);
        tile.output.path = utf8FromPath(folder / (std::string(name) + ".png"));
        // Each tile's share of the progress bar; Ctrl-C stops between and inside tiles.
        const double start = double(index) / found.tiles.size(), share = 1.0 / found.tiles.size();
        const ProgressCallback callback = progress.callback();
        const RenderResult result = render(tile, [&](double fraction) { return callback(start + share * fraction); });
        writeImage(result.image, tile.output.path, ImageFormat::Png8);
        saveParams(tile, utf8FromPath(folder / (std::string(name) + ".json")));
        tiles.push_back({result.image, std::string(name) + "  " + constantText(tile.fractal.c, 3)});
    }
    progress.finish();
    SheetLayout layout;
    layout.columns = options.columns;
    writeImage(composeSheet(tiles, layout), utf8FromPath(sheetPath), ImageFormat::Png8, existingPolicy(options.force));
    if (!options.quiet)
        std::cerr << "wrote " << utf8FromPath(sheetPath) << " and " << tiles.size()
                  << " tiles (tile_NN.png, tile_NN.json) to " << options.folder << "; " << found.skippedEmpty << " of "
                  << found.attempts << " candidate constants skipped for empty slices\n";
    return kSuccess;
}

}  // namespace

Runner addExploreCommand(CLI::App& app) {
    auto options = std::make_shared<ExploreCommandOptions>();
    CLI::App* command =
        app.add_subcommand("explore",
                           "Render a contact sheet of random constants (seeded, reproducible), skipping empty slices;\n"
                           "writes sheet.png and, per tile, tile_NN.png and tile_NN.json to continue with");
    options->fractal.addTo(*command);
    command->add_option("--seed", options->seed, "Random seed (the same seed gives the same constants)");
    command->add_option("--count", options->count, "Number of tiles")->check(CLI::Range(1, 100));
    command->add_option("--columns", options->columns, "Tiles per row")->check(CLI::Range(1, 20));
    command->add_option("--tile-width", options->width, "Tile width in pixels")->check(CLI::Range(16, 4096));
    command->add_option("--tile-height", options->height, "Tile height in pixels")->check(CLI::Range(16, 4096));
    command->add_option("-s,--samples", options->samples, "Anti-aliasing per tile: S x S rays a pixel")
        ->check(CLI::Range(1, 8));
    command->add_option("-o,--output", options->folder, "Folder for the sheet, tiles and parameter files");
    command->add_flag("-f,--force", options->force, "Overwrite an existing sheet");
    command->add_flag("-q,--quiet", options->quiet, "No progress bar or summary");
    return [options] { return reportErrors("explore", [&] { return runExplore(*options); }); };
}

}  // namespace dqj::cli
