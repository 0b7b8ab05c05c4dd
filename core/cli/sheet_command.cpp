// dqjulia sheet: lay PNG images out in a labelled contact sheet.
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "contact_sheet.hpp"

namespace dqj::cli {
namespace {

struct SheetOptions {
    std::vector<std::string> images;
    std::vector<std::string> labels;
    std::string output;
    int columns = 3;
    int labelLines = 3;
    bool force = false;
};

int runSheet(const SheetOptions& options) {
    if (!options.labels.empty() && options.labels.size() != options.images.size())
        throw ParamError("label", "give one --label per --tile (" + std::to_string(options.images.size()) + " tiles, " +
                                      std::to_string(options.labels.size()) + " labels)");
    std::vector<NamedPath> inputs;
    for (const std::string& image : options.images) inputs.push_back({"--tile", image});
    checkOutputs({{"--output", options.output}}, inputs, options.force);
    std::vector<SheetTile> tiles;
    for (std::size_t index = 0; index < options.images.size(); ++index)
        tiles.push_back(
            {readPng(options.images[index]), options.labels.empty() ? options.images[index] : options.labels[index]});
    SheetLayout layout;
    layout.columns = options.columns;
    layout.labelLines = options.labelLines;
    writeImage(composeSheet(tiles, layout), options.output, ImageFormat::Png8, existingPolicy(options.force));
    return kSuccess;
}

}  // namespace

Runner addSheetCommand(CLI::App& app) {
    auto options = std::make_shared<SheetOptions>();
    CLI::App* command = app.add_subcommand("sheet", "Lay PNG images out in a contact sheet with a label under each");
    command->add_option("-t,--tile", options->images, "A PNG image (repeat, in order)")
        ->required()
        ->check(existingFile());
    command->add_option("-l,--label", options->labels, "Its label (repeat, one per --tile; \\n breaks lines)");
    command->add_option("-o,--output", options->output, "The sheet (.png)")->required();
    command->add_option("--columns", options->columns, "Tiles per row")->check(CLI::Range(1, kMaxSheetColumns));
    command->add_option("--label-lines", options->labelLines, "Text lines reserved under each tile")
        ->check(CLI::Range(0, kMaxLabelLines));
    command->add_flag("-f,--force", options->force, "Overwrite an existing sheet");
    return [options] { return reportErrors("sheet", [&] { return runSheet(*options); }); };
}

}  // namespace dqj::cli
