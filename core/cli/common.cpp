#include "common.hpp"

#ifdef _WIN32
#include <windows.h>
#else
#include <unistd.h>
#endif

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <system_error>

#include "dqjulia/estimate.hpp"
#include "file_names.hpp"
#include "message_text.hpp"

namespace dqj::cli {
namespace {

std::atomic<bool> interruptRequested{false};

#ifdef _WIN32
/// Ctrl-C, Ctrl-Break and a closed console window (Windows stops the process shortly after that one).
BOOL WINAPI onConsoleEvent(DWORD event) {
    if (event != CTRL_C_EVENT && event != CTRL_BREAK_EVENT && event != CTRL_CLOSE_EVENT) return FALSE;
    interruptRequested.store(true);
    return TRUE;
}

/// Whether stderr is a console that draws the bar's escape codes (Windows 10 and later, once asked).
bool stderrIsTerminal() {
    const HANDLE console = ::GetStdHandle(STD_ERROR_HANDLE);
    DWORD mode = 0;
    return ::GetConsoleMode(console, &mode) && ::SetConsoleMode(console, mode | ENABLE_VIRTUAL_TERMINAL_PROCESSING);
}
#else
extern "C" void onInterrupt(int) { interruptRequested.store(true); }

bool stderrIsTerminal() { return isatty(STDERR_FILENO); }
#endif

double nowSeconds() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

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
#ifdef _WIN32
    ::SetConsoleCtrlHandler(onConsoleEvent, TRUE);
#else
    struct sigaction action {};
    action.sa_handler = onInterrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
    sigaction(SIGHUP, &action, nullptr);  // a closed terminal or a dropped SSH session: stop cleanly as for SIGTERM
#endif
}

bool interrupted() { return interruptRequested.load(); }

CLI::Validator existingFile() {
    return CLI::Validator(
        [](std::string& name) -> std::string {
            std::error_code error;
            std::filesystem::file_status status;
            try {
                status = std::filesystem::status(pathFromUtf8(name), error);
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
    command.add_option("-p,--params", paramsFile, "Parameter file (JSON, see README); flags override its values")
        ->check(existingFile());
    command.add_option("--c", constant, "Constant: 8 numbers, a's s i j k then b's s i j k")->expected(8);
    command.add_option("--variant", variant, "Algebra: paper, paper-coupled or dual")
        ->check(CLI::IsMember({"paper", "paper-coupled", "dual"}));
    command.add_option("-n,--iterations", iterations, "Iterations N (1..100000)");
    command.add_option("--bailout", bailout, "Bailout radius R (at least the containment radius r_K)");
    command.add_option("--slice", sliceAxes, "Slice axes by name, e.g. a.s,a.i,a.j or a.i,a.j,b.s");
    command.add_option("--slice-origin", sliceOrigin, "Slice origin: 8 numbers")->expected(8);
    command.add_option("--rotate", rotations, "Turn the slice: PLANE:DEGREES, e.g. a.j,b.s:30 (repeatable)");
}

void FractalOptions::applyTo(Params& params) const {
    if (!constant.empty()) {
        Vec8 values;
        std::copy(constant.begin(), constant.end(), values.begin());
        params.fractal.c = toDualQuat(values);
    }
    if (!variant.empty()) params.fractal.variant = *parseVariant(variant);
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

void checkOutputPath(const std::string& path, bool force, const std::string& flag) {
    namespace fs = std::filesystem;
    std::error_code error;
    if (path.empty()) throw ParamError("output.path", flag + " is empty; give a file name");
    const fs::path target = pathFromUtf8(path);
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
        throw ParamError("output.path", flag + " '" + shown + "': the folder '" + inputExcerpt(utf8FromPath(folder)) +
                                            "' does not exist");
#ifndef _WIN32  // Windows: access() does not read a folder's permissions (ACLs); the probe below tries
    if (::access(folder.c_str(), W_OK) != 0)
        throw ParamError("output.path",
                         flag + " '" + shown + "': the folder '" + inputExcerpt(folder.string()) + "' is not writable");
#endif
    try {
        checkWritable(path);  // not a device or FIFO, and a file can really be created there
    } catch (const std::runtime_error& failure) {
        throw ParamError("output.path", flag + ": " + failure.what());
    }
}

void checkDistinctOutputs(const std::vector<std::pair<std::string, std::string>>& outputs) {
    namespace fs = std::filesystem;
    std::vector<fs::path> resolved;
    for (const auto& [flag, path] : outputs) {
        std::error_code error;
        fs::path canonical = fs::weakly_canonical(fs::absolute(pathFromUtf8(path), error), error);
        resolved.push_back(error ? pathFromUtf8(path).lexically_normal() : canonical);
    }
    for (std::size_t a = 0; a < outputs.size(); ++a)
        for (std::size_t b = 0; b < a; ++b)
            if (resolved[a] == resolved[b])
                throw ParamError("output.path", outputs[b].first + " and " + outputs[a].first + " both name '" +
                                                    inputExcerpt(outputs[a].second) + "'; give them different files");
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
    : label_(std::move(label)), enabled_(!quiet && stderrIsTerminal()), startSeconds_(nowSeconds()) {}

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
    std::cerr << "\r" << label_ << " [" << bar << "] " << percent << "  " << formatDuration(elapsed) << eta
              << (status_.empty() ? "" : "  ") << status_ << "\x1b[K" << std::flush;
    drawn_ = true;
    return true;
}

void ProgressBar::finish() {
    if (drawn_) std::cerr << "\n";
    drawn_ = false;
}

}  // namespace dqj::cli
