// dqjulia explore: a contact sheet of random constants (seeded), or of variations of a
// document (--around, variations.hpp), one parameter file per tile.
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
#include "dqjulia/variations.hpp"
#include "platform/platform.hpp"
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
    std::string around;    ///< --around FILE: variations of that document instead of random constants
    std::string strength;  ///< --strength (with --around)
    std::string lock;      ///< --lock (with --around)
    bool countGiven = false, columnsGiven = false;
};

/// The variation settings of --strength and --lock. Throws ParamError for a bad name.
VariationOptions variationOptions(const ExploreCommandOptions& options) {
    VariationOptions result;
    result.seed = options.seed;
    result.count = options.count;
    if (!options.strength.empty()) {
        const std::optional<double> strength = parseStrength(options.strength);
        if (!strength)
            throw ParamError("variations.strength", "--strength '" + inputExcerpt(options.strength) +
                                                        "': give tiny, small, medium, large, huge or a number "
                                                        "from 0.01 to 1");
        result.strength = *strength;
    }
    if (!options.lock.empty()) {
        std::string unknown;
        const std::optional<unsigned> locked = parseGroups(options.lock, &unknown);
        if (!locked)
            throw ParamError("variations.locked", "--lock: unknown group '" + inputExcerpt(unknown) +
                                                      "'; give a comma-separated list of a, b, slice (= orientation "
                                                      "and origin), orientation, origin, iterations, variant, or none");
        result.locked = *locked;
    }
    return result;
}

/// The documents of the tiles: `count` variations of the --around document (at its own render
/// size, so a pick renders as the original did), or random constants (at the tile size).
struct Tiles {
    std::vector<Params> documents;
    std::string summary;  ///< what was skipped, for the closing line
};

Tiles findTiles(const ExploreCommandOptions& options, const ProgressCallback& progress) {
    Tiles tiles;
    if (options.around.empty()) {
        Params base = options.fractal.load();
        base.render.width = options.width;
        base.render.height = options.height;
        base.render.samples = options.samples;
        validate(base);
        ExploreOptions exploreOptions;
        exploreOptions.seed = options.seed;
        exploreOptions.count = options.count;
        const ExploreResult found = explore(base, exploreOptions);
        if (found.tiles.empty())
            throw std::runtime_error("no constant with a non-empty slice in " + std::to_string(found.attempts) +
                                     " attempts; try fewer iterations or another slice");
        tiles.documents = found.tiles;
        tiles.summary = std::to_string(found.skippedEmpty) + " of " + std::to_string(found.attempts) +
                        " candidate constants skipped for empty slices";
        return tiles;
    }
    const VariationOptions settings = variationOptions(options);
    FractalOptions fractal = options.fractal;
    fractal.paramsFile = options.around;
    const Params base = stillAtFrame(fractal.load(), 1.0);  // an animated document: its first frame
    const VariationResult found = vary(base, settings, progress);
    for (const Variation& variation : found.variations) tiles.documents.push_back(variation.params);
    std::string rejected;
    for (int r = 0; r < kRejectionCount; ++r)
        if (found.rejected[r])
            rejected += (rejected.empty() ? "" : ", ") + std::to_string(found.rejected[r]) + " " +
                        std::string(rejectionName(Rejection(r)));
    tiles.summary = std::to_string(found.variations.size()) + " of " + std::to_string(found.candidates) +
                    " candidates kept (rejected: " + (rejected.empty() ? "none" : rejected) + ")";
    return tiles;
}

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

int runExplore(ExploreCommandOptions options) {
    const bool around = !options.around.empty();
    if (!around && (!options.strength.empty() || !options.lock.empty()))
        throw ParamError("variations", "--strength and --lock go with --around FILE (variations of that document)");
    if (around && !options.fractal.paramsFile.empty())
        throw ParamError("variations", "--around FILE is the document to vary; give it instead of --params, not both");
    if (around) {  // a 3 x 3 grid around the document unless asked otherwise
        if (!options.countGiven) options.count = 9;
        if (!options.columnsGiven) options.columns = 3;
        variationOptions(options);  // bad names before any file is touched
    }
    FractalOptions start = options.fractal;  // bad parameters before any file is touched
    if (around) start.paramsFile = options.around;
    start.load();

    namespace fs = std::filesystem;
    const fs::path folder = platform::pathFromUtf8(options.folder);
    const fs::path sheetPath = folder / "sheet.png";
    // The folder is checked before it is made (a name Windows cannot hold, a file or a dangling
    // link in its place); the folders made here are removed again unless the run publishes its files.
    if (const std::string problem = systemNameProblem(options.folder); !problem.empty())
        throw ParamError("output.path", "--output '" + inputExcerpt(options.folder) + "': " + problem);
    std::error_code error;
    if (fs::is_symlink(folder, error) && !fs::exists(folder, error))
        throw ParamError("output.path", "--output '" + inputExcerpt(options.folder) + "' is a symbolic link to '" +
                                            platform::utf8FromPath(fs::read_symlink(folder, error)) +
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
    std::vector<NamedPath> outputs{{"--output", platform::utf8FromPath(sheetPath)}};
    for (std::size_t index = 0; index < std::size_t(options.count); ++index)
        for (const char* extension : {".png", ".json"})
            outputs.push_back({"--output", platform::utf8FromPath(folder / (tileName(index) + extension))});
    std::vector<NamedPath> inputs = options.fractal.inputs();
    if (around) inputs.push_back({"--around", options.around});
    checkOutputs(outputs, inputs, options.force);

    ProgressBar progress("exploring", options.quiet);
    const ProgressCallback callback = progress.callback();
    // Variations take the first fifth of the bar, the tiles' pictures the rest.
    const double found = around ? 0.2 : 0.0;
    const Tiles documents = findTiles(options, [&](double fraction) { return callback(found * fraction); });
    AtomicFileSet files(existingPolicy(options.force));
    std::vector<SheetTile> tiles;
    const std::size_t count = documents.documents.size();
    for (std::size_t index = 0; index < count; ++index) {
        Params tile = documents.documents[index];
        const std::string name = tileName(index);
        const std::string picture = platform::utf8FromPath(folder / (name + ".png"));
        // A variation keeps its document's size and names its own full-size picture; a random
        // constant's document is the tile's.
        tile.output.path = around ? platform::utf8FromPath(folder / (name + "_render.png")) : picture;
        Params thumbnail = tile;
        thumbnail.render.width = options.width;
        thumbnail.render.height = options.height;
        thumbnail.render.samples = options.samples;
        // Each tile's share of the progress bar; Ctrl-C stops between and inside tiles.
        const double start = found + (1.0 - found) * double(index) / count, share = (1.0 - found) / count;
        const RenderResult result =
            render(thumbnail, [&](double fraction) { return callback(start + share * fraction); });
        writeImage(result.image, files.add(picture), ImageFormat::Png8);
        files.add(platform::utf8FromPath(folder / (name + ".json"))).stream() << toJson(tile);
        tiles.push_back({result.image, name + "  " + constantText(tile.fractal.c, 3)});
    }
    progress.finish();
    SheetLayout layout;
    layout.columns = options.columns;
    writeImage(composeSheet(tiles, layout), files.add(platform::utf8FromPath(sheetPath)), ImageFormat::Png8);
    if (interrupted()) throw Cancelled();  // a signal in the last moments of the work: write nothing
    files.commit();
    made.keep = true;
    if (!options.quiet)
        std::cerr << "wrote " << platform::utf8FromPath(sheetPath) << " and " << tiles.size()
                  << " tiles (tile_NN.png, tile_NN.json) to " << options.folder << "; " << documents.summary << "\n";
    return kSuccess;
}

}  // namespace

Runner addExploreCommand(CLI::App& app) {
    auto options = std::make_shared<ExploreCommandOptions>();
    CLI::App* command = app.add_subcommand(
        "explore",
        "Render a contact sheet of random constants (seeded, reproducible), skipping empty slices, or with\n"
        "--around FILE of variations of that document (each non-empty, not dust, not a featureless ball,\n"
        "not too small, no two alike); writes sheet.png and, per tile, tile_NN.png and tile_NN.json, a\n"
        "complete parameter file for render, bake, povray or the next --around");
    options->fractal.addTo(*command);
    command->add_option("--seed", options->seed, "Random seed (the same seed gives the same constants, or variations)");
    command
        ->add_option("--around", options->around,
                     "Variations of this parameter file instead of random constants (flags such as --c\n"
                     "override its values first)")
        ->check(existingFile());
    command->add_option("--strength", options->strength,
                        "With --around: how far the variations go: tiny (0.05, details move), small (0.15),\n"
                        "medium (0.3, the default), large (0.6), huge (1, anything reachable), or 0.01 to 1");
    command->add_option("--lock", options->lock,
                        "With --around: groups kept as they are, comma-separated: a, b (the constant's parts),\n"
                        "slice (orientation and origin), orientation, origin, iterations (N and R), variant;\n"
                        "none; default: variant");
    CLI::Option* count = command->add_option("--count", options->count, "Number of tiles (default 12; 9 with --around)")
                             ->check(CLI::Range(1, 100));
    CLI::Option* columns =
        command->add_option("--columns", options->columns, "Tiles per row (default 4; 3 with --around)")
            ->check(CLI::Range(1, kMaxSheetColumns));
    command->add_option("--tile-width", options->width, "Tile width in pixels")->check(CLI::Range(16, 4096));
    command->add_option("--tile-height", options->height, "Tile height in pixels")->check(CLI::Range(16, 4096));
    command->add_option("-s,--samples", options->samples, "Anti-aliasing per tile: S x S rays a pixel")
        ->check(CLI::Range(1, 8));
    command->add_option("-o,--output", options->folder, "Folder for the sheet, tiles and parameter files");
    command->add_flag("-f,--force", options->force, "Overwrite an existing sheet, tiles and parameter files");
    command->add_flag("-q,--quiet", options->quiet, "No progress bar or summary");
    return [options, count, columns] {
        options->countGiven = count->count() > 0;
        options->columnsGiven = columns->count() > 0;
        return reportErrors("explore", [&] { return runExplore(*options); });
    };
}

}  // namespace dqj::cli
