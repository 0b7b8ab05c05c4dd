// dqjulia explore: a contact sheet of random constants (seeded), one parameter file per tile.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "contact_sheet.hpp"
#include "explore.hpp"
#include "files/atomic_file.hpp"
#include "dqjulia/render.hpp"
#include "files/file_names.hpp"
#include "render/image_writer.hpp"
#include "files/message_text.hpp"

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

/// The folders a run made for its files (deepest first): removed again, if still empty, unless kept.
struct MadeFolders {
    std::vector<std::filesystem::path> paths;
    bool keep = false;
    ~MadeFolders() {
        std::error_code error;
        if (!keep)
            for (const std::filesystem::path& path : paths) std::filesystem::remove(path, error);  // empty ones only
    }
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
    // The folder is checked before it is made (a name Windows cannot hold, a file or a dangling
    // link in its place); the folders made here are removed again unless the run publishes its files.
#ifdef _WIN32
    if (const std::string problem = windowsNameProblem(options.folder); !problem.empty())
        throw ParamError("output.path", "--output '" + inputExcerpt(options.folder) + "': " + problem);
#endif
    std::error_code error;
    if (fs::is_symlink(folder, error) && !fs::exists(folder, error))
        throw ParamError("output.path", "--output '" + inputExcerpt(options.folder) + "' is a symbolic link to '" +
                                            utf8FromPath(fs::read_symlink(folder, error)) +
                                            "', which does not exist; give a folder");
    if (fs::exists(folder, error) && !fs::is_directory(folder, error))
        throw ParamError("output.path",
                         "--output '" + inputExcerpt(options.folder) + "' is a file, not a folder; explore writes a folder of files");
    MadeFolders made;  // declared before the files: removed after their temporary files
    for (fs::path at = folder; !at.empty() && !fs::exists(at, error); at = at.parent_path()) made.paths.push_back(at);
    fs::create_directories(folder, error);
    if (error)
        throw ParamError("output.path",
                         "--output '" + inputExcerpt(options.folder) + "': cannot create the folder: " + error.message());
    // The sheet and every tile's picture and parameter file: checked now, published together at the end.
    auto tileName = [](std::size_t index) {
        char name[32];
        std::snprintf(name, sizeof name, "tile_%02zu", index + 1);
        return std::string(name);
    };
    std::vector<NamedPath> outputs{{"--output", utf8FromPath(sheetPath)}};
    for (std::size_t index = 0; index < std::size_t(options.count); ++index)
        for (const char* extension : {".png", ".json"})
            outputs.push_back({"--output", utf8FromPath(folder / (tileName(index) + extension))});
    checkOutputs(outputs, options.fractal.inputs(), options.force);

    ExploreOptions exploreOptions;
    exploreOptions.seed = options.seed;
    exploreOptions.count = options.count;
    const ExploreResult found = explore(base, exploreOptions);
    if (found.tiles.empty())
        throw std::runtime_error("no constant with a non-empty slice in " + std::to_string(found.attempts) +
                                 " attempts; try fewer iterations or another slice");

    ProgressBar progress("exploring", options.quiet);
    AtomicFileSet files(existingPolicy(options.force));
    std::vector<SheetTile> tiles;
    for (std::size_t index = 0; index < found.tiles.size(); ++index) {
        Params tile = found.tiles[index];
        const std::string name = tileName(index);
        tile.output.path = utf8FromPath(folder / (name + ".png"));
        // Each tile's share of the progress bar; Ctrl-C stops between and inside tiles.
        const double start = double(index) / found.tiles.size(), share = 1.0 / found.tiles.size();
        const ProgressCallback callback = progress.callback();
        const RenderResult result = render(tile, [&](double fraction) { return callback(start + share * fraction); });
        writeImage(result.image, files.add(tile.output.path), ImageFormat::Png8);
        files.add(utf8FromPath(folder / (name + ".json"))).stream() << toJson(tile);
        tiles.push_back({result.image, name + "  " + constantText(tile.fractal.c, 3)});
    }
    progress.finish();
    SheetLayout layout;
    layout.columns = options.columns;
    writeImage(composeSheet(tiles, layout), files.add(utf8FromPath(sheetPath)), ImageFormat::Png8);
    if (interrupted()) throw Cancelled();  // a signal in the last moments of the work: write nothing
    files.commit();
    made.keep = true;
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
    command->add_option("--columns", options->columns, "Tiles per row")->check(CLI::Range(1, kMaxSheetColumns));
    command->add_option("--tile-width", options->width, "Tile width in pixels")->check(CLI::Range(16, 4096));
    command->add_option("--tile-height", options->height, "Tile height in pixels")->check(CLI::Range(16, 4096));
    command->add_option("-s,--samples", options->samples, "Anti-aliasing per tile: S x S rays a pixel")
        ->check(CLI::Range(1, 8));
    command->add_option("-o,--output", options->folder, "Folder for the sheet, tiles and parameter files");
    command->add_flag("-f,--force", options->force, "Overwrite an existing sheet, tiles and parameter files");
    command->add_flag("-q,--quiet", options->quiet, "No progress bar or summary");
    return [options] { return reportErrors("explore", [&] { return runExplore(*options); }); };
}

}  // namespace dqj::cli
