// Shared pieces of the dqjulia command: the fractal options every subcommand takes,
// loading parameters with flag overrides, errors and the progress bar.
#pragma once

#include <memory>
#include <optional>
#include <streambuf>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj::cli {

/// Exit codes: 0 success, 1 failure while working, 2 bad input, 130 interrupted.
enum ExitCode { kSuccess = 0, kFailure = 1, kBadInput = 2, kInterrupted = 130 };

/// A file a run reads or writes, with the flag (or the words) that name it in messages.
struct NamedPath {
    std::string flag;
    std::string path;
};

/// --params and the fractal and slice flags, shared by render, eval and inspect.
struct FractalOptions {
    std::string paramsFile;
    std::vector<double> constant;
    std::string variant;
    std::optional<int> iterations;
    std::optional<double> bailout;
    std::string sliceAxes;
    std::vector<double> sliceOrigin;
    std::vector<std::string> rotations;

    void addTo(CLI::App& command);
    /// Defaults, then the file, then the flags; validated at the end. Throws ParamError.
    Params load() const;
    /// Applies the flags to `params` without validating. Throws ParamError for malformed flags.
    void applyTo(Params& params) const;
    /// The files the flags read: --params, if given.
    std::vector<NamedPath> inputs() const;
};

/// Checks an output path before any long work starts: refuses an empty name, an existing file
/// unless `force`, a folder, device or FIFO, and a folder that is missing or where no file can
/// be created (tried). Throws ParamError naming `flag`.
void checkOutputPath(const std::string& path, bool force, const std::string& flag = "--output");

/// Refuses two outputs of one run that name the same file (one would silently replace the
/// other). Throws ParamError naming both flags.
void checkDistinctOutputs(const std::vector<NamedPath>& outputs);

/// Refuses, with or without --force, an output that is one of the run's inputs: the same file by
/// its identity (fileIdentity), so a symbolic or hard link to an input is caught too. --force
/// consents to replacing an old output, never an input of the same run. Throws ParamError naming
/// both. Costs a stat of each path.
void checkInputsKept(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs);

/// Every output of a run checked before the work: none is one of its inputs (checkInputsKept),
/// no two name one file (checkDistinctOutputs), and each passes checkOutputPath.
void checkOutputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs, bool force);

/// What writers do with a file that exists when they publish: without --force it is kept (and
/// the write fails), even if it appeared while the work ran.
inline Existing existingPolicy(bool force) { return force ? Existing::Replace : Existing::Keep; }

/// While it lives, every character written to std::cout, std::cerr and std::clog (the command's
/// messages, the argument parser's and any library's) goes through printableText(), so no name
/// or value can drive the terminal: control characters arrive as \xNN. Only the progress bar
/// draws its own control codes, through the buffer standard error had before (its label escaped).
class MessageEscaping {
public:
    MessageEscaping();
    ~MessageEscaping();
    MessageEscaping(const MessageEscaping&) = delete;
    MessageEscaping& operator=(const MessageEscaping&) = delete;

private:
    std::streambuf* out_;
    std::streambuf* err_;
    std::streambuf* log_;
    std::unique_ptr<std::streambuf> escapedOut_;
    std::unique_ptr<std::streambuf> escapedErr_;
};

/// Runs `body`, printing "dqjulia: <message>" for errors and returning the exit code.
int reportErrors(const std::string& command, const std::function<int()>& body);

/// A progress bar with ETA on stderr when it is a terminal (and not quiet); silent otherwise.
/// Returns false once SIGINT, SIGTERM or SIGHUP arrived, which cancels the work.
class ProgressBar {
public:
    ProgressBar(std::string label, bool quiet);
    ~ProgressBar();
    ProgressCallback callback();
    void finish();
    /// Text drawn after the bar from the next update on (e.g. "sampling, 1.2M of 16.8M voxels").
    void setStatus(std::string status) { status_ = std::move(status); }

private:
    bool update(double fraction);
    std::string label_;
    std::string status_;
    bool enabled_;
    double startSeconds_;
    double lastDrawSeconds_ = -1.0;
    bool drawn_ = false;
};

/// Installs SIGINT/SIGTERM/SIGHUP handlers that ask running work to stop (see interrupted()); on
/// Windows, a console handler for Ctrl-C, Ctrl-Break and a closed console.
void installInterruptHandlers();
bool interrupted();

/// CLI11's ExistingFile for the command's UTF-8 file names (CLI11's own reads them in the ANSI
/// code page on Windows), with its messages.
CLI::Validator existingFile();

}  // namespace dqj::cli
