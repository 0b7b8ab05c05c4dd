#include "common.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <system_error>

#include "files/atomic_file.hpp"
#include "dqjulia/estimate.hpp"
#include "platform/platform.hpp"
#include "files/message_text.hpp"
#include "schema_options.hpp"

namespace dqj::cli {
namespace {

std::atomic<bool> interruptRequested{false};

double nowSeconds() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

/// A stream buffer that passes text on to another with its control characters escaped
/// (printableText). A trailing first byte of a C1 control (0xc2) waits for the next write.
class EscapingBuffer : public std::streambuf {
public:
    explicit EscapingBuffer(std::streambuf* target) : target_(target) {}
    ~EscapingBuffer() override {
        if (!pending_.empty()) target_->sputn(pending_.data(), std::streamsize(pending_.size()));
    }

protected:
    int_type overflow(int_type ch) override {
        if (traits_type::eq_int_type(ch, traits_type::eof())) return traits_type::not_eof(ch);
        const char byte = traits_type::to_char_type(ch);
        return xsputn(&byte, 1) == 1 ? ch : traits_type::eof();
    }
    std::streamsize xsputn(const char* data, std::streamsize count) override {
        std::string text = std::move(pending_);
        pending_.clear();
        text.append(data, std::size_t(count));
        if (!text.empty() && static_cast<unsigned char>(text.back()) == 0xc2) {
            pending_ = text.substr(text.size() - 1);
            text.pop_back();
        }
        const std::string escaped = printableText(text);
        return target_->sputn(escaped.data(), std::streamsize(escaped.size())) == std::streamsize(escaped.size())
                   ? count
                   : 0;
    }
    int sync() override { return target_->pubsync(); }

private:
    std::streambuf* target_;
    std::string pending_;
};

/// Where the progress bar draws: standard error's own buffer, not the escaping one.
std::streambuf* terminalBuffer = nullptr;

std::string formatDuration(double seconds) {
    const long total = long(seconds + 0.5);
    char text[32];
    if (total >= 3600)
        std::snprintf(text, sizeof text, "%ldh%02ldm", total / 3600, (total / 60) % 60);
    else if (total >= 60)
        std::snprintf(text, sizeof text, "%ldm%02lds", total / 60, total % 60);
    else
        std::snprintf(text, sizeof text, "%lds", total);
    return text;
}

}  // namespace

void installInterruptHandlers() {
    platform::onInterrupt([] { interruptRequested.store(true); });
}

bool interrupted() { return interruptRequested.load(); }

CLI::Validator existingFile() {
    return CLI::Validator(
        [](std::string& name) -> std::string {
            std::error_code error;
            std::filesystem::file_status status;
            try {
                status = std::filesystem::status(platform::pathFromUtf8(name), error);
            } catch (const std::filesystem::filesystem_error&) {
                return "File name is not valid UTF-8: " + inputExcerpt(name);
            }
            if (!std::filesystem::exists(status)) return "File does not exist: " + inputExcerpt(name);
            if (std::filesystem::is_directory(status)) return "File is actually a directory: " + inputExcerpt(name);
            return "";
        },
        "FILE", "EXISTING_FILE");
}

void FractalOptions::addTo(CLI::App& command) {
    command
        .add_option("-p,--params", paramsFile,
                    "Parameter file (JSON, see docs: Parameter file); flags override its values")
        ->check(existingFile());
    schemaOption(command, "--c", "fractal.c", constant);
    schemaOption(command, "--variant", "fractal.variant", variant);
    schemaOption(command, "-n,--iterations", "fractal.iterations", iterations);
    schemaOption(command, "--bailout", "fractal.bailout", bailout);
    schemaOption(command, "--slice", "slice.axes", sliceAxes, "Here by name only, e.g. a.s,a.i,a.j or a.i,a.j,b.s");
    schemaOption(command, "--slice-origin", "slice.origin", sliceOrigin);
    schemaOption(command, "--rotate", "slice.rotations", rotations,
                 "Here one rotation as PLANE:DEGREES, e.g. a.j,b.s:30 (repeatable)");
}

void FractalOptions::applyTo(Params& params) const {
    if (!constant.empty()) {
        Vec8 values;
        std::copy(constant.begin(), constant.end(), values.begin());
        params.fractal.c = toDualQuat(values);
    }
    if (!variant.empty()) params.fractal.variant = schemaChoice<Variant>("fractal.variant", variant);
    if (iterations) params.fractal.iterations = *iterations;
    if (bailout) params.fractal.bailout = *bailout;
    if (!sliceAxes.empty()) {
        try {
            const Vec8 origin = params.slice.base.origin;
            params.slice.base = sliceFromAxisNames(sliceAxes);
            params.slice.base.origin = origin;
            params.slice.rotations.clear();
        } catch (const std::invalid_argument& error) {
            throw ParamError("slice.axes", std::string("--slice: ") + error.what());
        }
    }
    if (!sliceOrigin.empty()) std::copy(sliceOrigin.begin(), sliceOrigin.end(), params.slice.base.origin.begin());
    for (const std::string& text : rotations) {
        const std::size_t colon = text.rfind(':');
        const std::size_t comma = text.find(',');
        const auto first = parseAxisName(text.substr(0, std::min(comma, colon)));
        // No comma: the empty name, which names no axis (an optional in a ?: made GCC 12 warn).
        const auto second = parseAxisName(comma < colon ? text.substr(comma + 1, colon - comma - 1) : std::string());
        double degrees = 0.0;
        bool numberOk = colon != std::string::npos;
        if (numberOk) {
            try {
                std::size_t used = 0;
                degrees = std::stod(text.substr(colon + 1), &used);
                numberOk = used == text.size() - colon - 1 && std::isfinite(degrees);
            } catch (const std::exception&) {
                numberOk = false;
            }
        }
        if (!first || !second || *first == *second || !numberOk)
            throw ParamError("slice.rotations",
                             "--rotate \"" + inputExcerpt(text) +
                                 "\": expected PLANE:DEGREES with two different axes, e.g. a.j,b.s:30");
        params.slice.rotations.push_back({*first, *second, degrees});
    }
}

Params FractalOptions::load() const {
    Params params = paramsFile.empty() ? Params{} : loadParams(paramsFile, Validation::TypesOnly);
    applyTo(params);
    validate(params);
    return params;
}

std::vector<NamedPath> FractalOptions::inputs() const {
    if (paramsFile.empty()) return {};
    return {{"--params", paramsFile}};
}

void checkOutputPath(const std::string& path, bool force, const std::string& flag) {
    namespace fs = std::filesystem;
    std::error_code error;
    if (path.empty()) throw ParamError("output.path", flag + " is empty; give a file name");
    if (const std::string problem = systemNameProblem(path); !problem.empty())
        throw ParamError("output.path", flag + " '" + inputExcerpt(path) + "': " + problem);
    const fs::path target = platform::pathFromUtf8(path);
    const std::string shown = inputExcerpt(path);
    if (fs::is_directory(target, error))
        throw ParamError("output.path", flag + " '" + shown + "' is a folder; give a file name");
    if (fs::exists(target, error) && !fs::is_regular_file(target, error))
        throw ParamError("output.path", flag + " '" + shown +
                                            "' is not a regular file (a device, FIFO or socket); "
                                            "dqjulia writes only regular files");
    if (fs::exists(target, error) && !force)
        throw ParamError("output.path", flag + " '" + shown + "' exists; pass --force to overwrite it");
    const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(folder, error))
        throw ParamError("output.path", flag + " '" + shown + "': the folder '" +
                                            inputExcerpt(platform::utf8FromPath(folder)) + "' does not exist");
    if (!platform::folderWritable(platform::utf8FromPath(folder)))  // Windows cannot say (ACLs): the probe below tries
        throw ParamError("output.path", flag + " '" + shown + "': the folder '" +
                                            inputExcerpt(platform::utf8FromPath(folder)) + "' is not writable");
    try {
        checkWritable(path);  // not a device or FIFO, and a file can really be created there
    } catch (const std::runtime_error& failure) {
        throw ParamError("output.path", flag + ": " + failure.what());
    }
}

void checkDistinctOutputs(const std::vector<NamedPath>& outputs) {
    namespace fs = std::filesystem;
    std::map<fs::path, std::size_t> seen;
    for (std::size_t index = 0; index < outputs.size(); ++index) {
        const std::string& path = outputs[index].path;
        std::error_code error;
        fs::path canonical = fs::weakly_canonical(fs::absolute(platform::pathFromUtf8(path), error), error);
        const auto [at, added] =
            seen.emplace(error ? platform::pathFromUtf8(path).lexically_normal() : canonical, index);
        if (!added)
            throw ParamError("output.path", outputs[at->second].flag + " and " + outputs[index].flag + " both name '" +
                                                inputExcerpt(path) + "'; give them different files");
    }
}

void checkInputsKept(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs) {
    std::map<platform::FileIdentity, const NamedPath*> read;
    for (const NamedPath& input : inputs)
        if (const auto identity = platform::fileIdentity(input.path)) read.emplace(*identity, &input);
    if (read.empty()) return;
    for (const NamedPath& output : outputs) {
        const auto identity = platform::fileIdentity(output.path);
        const auto found = identity ? read.find(*identity) : read.end();
        if (found == read.end()) continue;
        const NamedPath& input = *found->second;
        throw ParamError("output.path",
                         output.flag + " '" + inputExcerpt(output.path) + "' is " +
                             (input.path == output.path ? "" : "the same file as ") + input.flag + " '" + inputExcerpt(input.path) +
                             "', which this run reads: a run never writes over its own input, not even with "
                             "--force; write to another name");
    }
}

void checkOutputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs, bool force) {
    checkInputsKept(outputs, inputs);  // first: "exists; pass --force" would be the wrong advice
    checkDistinctOutputs(outputs);
    for (const NamedPath& output : outputs) checkOutputPath(output.path, force, output.flag);
}

MessageEscaping::MessageEscaping()
    : out_(std::cout.rdbuf()),
      err_(std::cerr.rdbuf()),
      log_(std::clog.rdbuf()),
      escapedOut_(std::make_unique<EscapingBuffer>(out_)),
      escapedErr_(std::make_unique<EscapingBuffer>(err_)) {
    terminalBuffer = err_;
    std::cout.rdbuf(escapedOut_.get());
    std::cerr.rdbuf(escapedErr_.get());
    std::clog.rdbuf(escapedErr_.get());  // a library's log lines too (its own object, the same stderr)
}

MessageEscaping::~MessageEscaping() {
    std::cout.flush();
    std::cerr.flush();
    std::clog.flush();
    std::cout.rdbuf(out_);
    std::cerr.rdbuf(err_);
    std::clog.rdbuf(log_);
    terminalBuffer = nullptr;
}

int reportErrors(const std::string& command, const std::function<int()>& body) {
    try {
        return body();
    } catch (const Cancelled&) {
        std::cerr << "dqjulia " << command << ": interrupted; nothing was written\n";
        return kInterrupted;
    } catch (const std::exception& error) {
        if (interrupted()) {  // e.g. a read of the parameter file cut short by Ctrl-C: not bad input
            std::cerr << "dqjulia " << command << ": interrupted; nothing was written\n";
            return kInterrupted;
        }
        if (const auto* param = dynamic_cast<const ParamError*>(&error)) {
            std::cerr << "dqjulia " << command << ": " << param->what() << "\n";
            return kBadInput;
        }
        const auto* system = dynamic_cast<const std::system_error*>(&error);
        if (system && (system->code() == std::errc::resource_unavailable_try_again ||
                       system->code() == std::errc::not_enough_memory)) {
            std::cerr << "dqjulia " << command << ": " << exceptionMessage(error)
                      << ": the system refused this process a thread or memory (see ulimit -u, ulimit -v and the "
                         "container's limits); a retry may help\n";
            return kFailure;
        }
        if (dynamic_cast<const std::bad_alloc*>(&error)) {
            std::cerr << "dqjulia " << command
                      << ": out of memory: the work needs more memory than this process may use (see ulimit -v and the "
                         "container's memory limit); try a smaller resolution or size\n";
            return kFailure;
        }
        std::cerr << "dqjulia " << command << ": " << exceptionMessage(error) << "\n";
        return kFailure;
    }
}

ProgressBar::ProgressBar(std::string label, bool quiet)
    : label_(std::move(label)), enabled_(!quiet && platform::stderrIsTerminal()), startSeconds_(nowSeconds()) {}

ProgressBar::~ProgressBar() {
    if (drawn_) std::cerr << "\n";
}

ProgressCallback ProgressBar::callback() {
    return [this](double fraction) { return update(fraction); };
}

bool ProgressBar::update(double fraction) {
    if (interrupted()) return false;
    if (!enabled_) return true;
    const double now = nowSeconds();
    if (fraction < 1.0 && now - lastDrawSeconds_ < 0.1) return true;
    lastDrawSeconds_ = now;
    const double elapsed = now - startSeconds_;
    constexpr int kWidth = 30;
    const int filled = int(fraction * kWidth);
    std::string bar(filled, '#');
    bar.resize(kWidth, '.');
    std::string eta =
        fraction > 0.02 && fraction < 1.0 ? " ETA " + formatDuration(elapsed / fraction * (1.0 - fraction)) : "";
    char percent[16];
    std::snprintf(percent, sizeof percent, "%3d%%", int(fraction * 100.0));
    // Drawn past the messages' escaping (its own \r and erase-line codes), the label and status escaped here.
    std::ostream terminal(terminalBuffer ? terminalBuffer : std::cerr.rdbuf());
    terminal << "\r" << printableText(label_) << " [" << bar << "] " << percent << "  " << formatDuration(elapsed)
             << eta << (status_.empty() ? "" : "  ") << printableText(status_) << "\x1b[K" << std::flush;
    drawn_ = true;
    return true;
}

void ProgressBar::finish() {
    if (drawn_) std::cerr << "\n";
    drawn_ = false;
}

}  // namespace dqj::cli
