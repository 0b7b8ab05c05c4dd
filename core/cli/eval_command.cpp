// dqjulia eval: points on stdin, escape count and distance estimate as CSV on stdout.
#include <cstdio>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/estimate.hpp"
#include "files/message_text.hpp"
#include "files/text_input.hpp"

namespace dqj::cli {
namespace {

struct EvalOptions {
    FractalOptions fractal;
    bool sliceCoords = false;
};

/// The longest line of points read: a line holds 8 numbers (a few hundred bytes), or a comment.
constexpr std::size_t kMaxLineBytes = std::size_t(1) << 16;

/// Numbers separated by spaces, tabs, commas or semicolons; false if anything else is on the line.
bool parseNumbers(const std::string& line, std::vector<double>& numbers) {
    numbers.clear();
    const char* const separators = " \t,;";
    for (std::size_t start = line.find_first_not_of(separators); start != std::string::npos;) {
        const std::size_t end = std::min(line.find_first_of(separators, start), line.size());
        try {
            const std::string word = line.substr(start, end - start);
            std::size_t used = 0;
            numbers.push_back(std::stod(word, &used));
            if (used != word.size()) return false;
        } catch (const std::invalid_argument&) {
            return false;
        } catch (const std::out_of_range&) {
            return false;
        }
        start = line.find_first_not_of(separators, end);
    }
    return true;
}

int runEval(const EvalOptions& options) {
    const Params params = options.fractal.load();
    const Slice slice = params.slice.effective();
    const std::size_t expected = options.sliceCoords ? 3 : 8;
    const std::string what = options.sliceCoords ? " (x y z)" : " (a's s i j k, then b's s i j k)";
    std::printf("n,r,ra,rb,de\n");
    // The rows go out as the points come in; a bad line or a read error ends the output there,
    // with the message and a failing exit status (2 or 1), never as if the input had ended.
    LineReader input(0, "standard input", kMaxLineBytes);
    std::string line;
    std::vector<double> numbers;
    for (LineReader::Result result; (result = input.next(line)) != LineReader::Result::End;) {
        const std::string where = "standard input, line " + std::to_string(input.lineNumber());
        if (result == LineReader::Result::TooLong) {
            std::fflush(stdout);
            throw ParamError("", where + ": longer than " + std::to_string(kMaxLineBytes) +
                                     " bytes, the most a line of " + std::to_string(expected) +
                                     " numbers may have; it starts \"" + inputExcerpt(line, false) + "\"");
        }
        const std::size_t start = line.find_first_not_of(" \t");
        if (start == std::string::npos || line[start] == '#') continue;
        if (!parseNumbers(line, numbers) || numbers.size() != expected) {
            std::fflush(stdout);
            throw ParamError("", where + ": expected " + std::to_string(expected) + " numbers" + what + ", got \"" +
                                     inputExcerpt(line) + "\"");
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
