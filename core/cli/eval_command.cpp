// dqjulia eval: points on stdin, escape count and distance estimate as CSV on stdout.
#include <cstdio>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/estimate.hpp"

namespace dqj::cli {
namespace {

struct EvalOptions {
    FractalOptions fractal;
    bool sliceCoords = false;
};

/// Numbers separated by spaces, tabs or commas; false if anything else is on the line.
bool parseNumbers(const std::string& line, std::vector<double>& numbers) {
    numbers.clear();
    std::string text = line;
    for (char& ch : text)
        if (ch == ',' || ch == '\t' || ch == ';') ch = ' ';
    std::istringstream in(text);
    std::string word;
    while (in >> word) {
        try {
            std::size_t used = 0;
            const double value = std::stod(word, &used);
            if (used != word.size()) return false;
            numbers.push_back(value);
        } catch (const std::exception&) {
            return false;
        }
    }
    return true;
}

int runEval(const EvalOptions& options) {
    const Params params = options.fractal.load();
    const Slice slice = params.slice.effective();
    const std::size_t expected = options.sliceCoords ? 3 : 8;
    std::printf("n,r,ra,rb,de\n");
    std::string line;
    std::vector<double> numbers;
    for (std::size_t lineNumber = 1; std::getline(std::cin, line); ++lineNumber) {
        const std::size_t start = line.find_first_not_of(" \t\r");
        if (start == std::string::npos || line[start] == '#') continue;
        if (!parseNumbers(line, numbers) || numbers.size() != expected) {
            std::fflush(stdout);
            throw ParamError("", "stdin line " + std::to_string(lineNumber) + ": expected " + std::to_string(expected) +
                                     " numbers" +
                                     (options.sliceCoords ? " (x y z)" : " (a's s i j k, then b's s i j k)") +
                                     ", got \"" + line + "\"");
        }
        DualQuat point;
        if (options.sliceCoords) {
            point = slice.map(glm::dvec3(numbers[0], numbers[1], numbers[2]));
        } else {
            Vec8 values;
            std::copy(numbers.begin(), numbers.end(), values.begin());
            point = toDualQuat(values);
        }
        const Escape escape = evaluate(params.fractal, point);
        std::printf("%d,%.17g,%.17g,%.17g,%.17g\n", escape.n, escape.r, escape.ra, escape.rb, escape.de);
    }
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) throw std::runtime_error("cannot write to standard output");
    return kSuccess;
}

}  // namespace

Runner addEvalCommand(CLI::App& app) {
    auto options = std::make_shared<EvalOptions>();
    CLI::App* command = app.add_subcommand(
        "eval",
        "Evaluate points read from stdin (one per line: 8 numbers, or x y z with --slice-coords);\n"
        "writes CSV n,r,ra,rb,de: escape iteration (0 = inside), escape norm, |a|, |b| at exit, distance estimate");
    options->fractal.addTo(*command);
    command->add_flag("--slice-coords", options->sliceCoords, "Read 3-D points and map them through the slice");
    return [options] { return reportErrors("eval", [&] { return runEval(*options); }); };
}

}  // namespace dqj::cli
