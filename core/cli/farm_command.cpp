// dqjulia farm slurm | openjd: the job files that bake a sequence (and tiles) on a render farm,
// for the engines people already run; dqjulia schedules nothing itself.
//
// Both write the complete parameter file of the bake (flags applied) beside the output, which
// every task reads, and name this dqjulia by its absolute path: the output's folder must be
// on storage every machine shares, and every machine must run the same dqjulia (the merge
// checks it). Frames go in chunks of --chunk frames a task (Slurm starts array tasks in waves
// a few seconds apart, so short frames are grouped); with --tiles each chunk is baked tile by
// tile and a dependent step merges each frame's tiles. Every task passes --skip-existing, so
// submitting the same job again redoes only what is missing.
//   slurm:  an sbatch array script (task = chunk x tile) and, with --tiles, a merge array
//           script submitted with --dependency=afterok on the first; --submit submits both.
//   openjd: an Open Job Description job template (jobtemplate-2023-09): a Bake step whose task
//           parameters are the frame chunks (and the tiles) and a Merge step depending on it.
// Cost: writing two or three small files.
#ifdef _WIN32
#include <windows.h>
#else
#include <sys/wait.h>
#endif

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "atomic_file.hpp"
#include "bake_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/dqjulia.h"
#include "dqjulia/tiles.hpp"
#include "file_names.hpp"

namespace dqj::cli {
namespace {

namespace fs = std::filesystem;

constexpr int kMaxOpenJdChunks = 1024;    // a task parameter's list holds at most 1024 values
constexpr int kSlurmMaxArraySize = 1001;  // Slurm's default MaxArraySize

struct FarmFlags {
    BakeFlags bake;  // the parameters, --output, --frames, --tiles, --force
    int chunk = 1;
    std::string name;
    std::string file;  // --script / --template
    // Slurm
    int cpus = 1;
    std::string partition, time, memory;
    std::vector<std::string> sbatchOptions;
    bool submit = false;
};

/// What the job does, with every path absolute.
struct FarmPlan {
    Params params;  // the bake's, flags applied
    std::string dqjulia, paramsPath, output, name;
    std::optional<FrameRange> frames;
    int chunk = 1;
    std::optional<Tile> tiling;

    int chunks() const { return frames ? (frames->last - frames->first) / chunk + 1 : 1; }
    int tiles() const { return tiling ? tileCount(*tiling) : 1; }
    /// "1-4", "5-8", ...: the frames of each chunk.
    std::vector<std::string> chunkRanges() const {
        std::vector<std::string> ranges;
        for (int first = frames->first; first <= frames->last; first += chunk)
            ranges.push_back(std::to_string(first) + "-" + std::to_string(std::min(first + chunk - 1, frames->last)));
        return ranges;
    }
    std::string describe() const {
        std::string text = frames ? "frames " + std::to_string(frames->first) + "-" + std::to_string(frames->last) +
                                        " in " + std::to_string(chunks()) + " chunks of " + std::to_string(chunk)
                                  : "one frame";
        if (tiling) text += ", each in " + std::to_string(tiles()) + " tiles (" + tilingText(*tiling) + ")";
        return text;
    }
};

/// `text` in single quotes for sh.
std::string shellQuote(const std::string& text) {
    std::string quoted = "'";
    for (const char ch : text) quoted += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return quoted + "'";
}

std::string withoutExtension(const std::string& path) {
    return utf8FromPath(pathFromUtf8(path).parent_path() / pathFromUtf8(path).stem());
}

/// `path` relative to the folder of `file`.
std::string relativeTo(const std::string& path, const std::string& file) {
    return utf8FromPath(
        pathFromUtf8(path).lexically_relative(fs::absolute(pathFromUtf8(file)).parent_path().lexically_normal()));
}

std::string thisExecutable() {
#ifdef _WIN32
    std::wstring self(32768, L'\0');
    const DWORD length = ::GetModuleFileNameW(nullptr, self.data(), DWORD(self.size()));
    if (length == 0 || length >= self.size()) throw std::runtime_error("cannot find this dqjulia's path");
    self.resize(length);
    return utf8FromPath(fs::path(self));
#else
    std::error_code error;
    const fs::path self = fs::read_symlink("/proc/self/exe", error);
    if (error) throw std::runtime_error("cannot find this dqjulia's path (/proc/self/exe): " + error.message());
    return self.string();
#endif
}

/// Plans the job and checks its files: the parameter file every task reads and `jobFiles`. Throws ParamError.
FarmPlan plan(const FarmFlags& flags, std::vector<NamedPath> jobFiles) {
    const BakeFlags& bake = flags.bake;
    FarmPlan plan;
    plan.params = bake.load();
    const Params& params = plan.params;
    plan.output = utf8FromPath(fs::absolute(pathFromUtf8(bake.output)).lexically_normal());
    if (AtomicFile::lowercaseExtension(plan.output) != ".vdb")
        throw ParamError("output.path", "--output '" + bake.output + "' must end in .vdb");
    plan.frames = bake.frameRange();
    plan.chunk = flags.chunk;
    plan.tiling = bake.tiling();
    if (plan.tiling) {
        plan.tiling->index = 1;
        checkTile(params, *plan.tiling);
    }
    for (int frame = plan.frames ? plan.frames->first : 1; frame <= (plan.frames ? plan.frames->last : 1); ++frame)
        paramsAtFrame(params, frame);  // every frame valid before anything is submitted
    plan.name = flags.name.empty() ? "dqjulia-" + utf8FromPath(pathFromUtf8(plan.output).stem()) : flags.name;
    plan.dqjulia = thisExecutable();
    plan.paramsPath = withoutExtension(plan.output) + ".params.json";
    jobFiles.insert(jobFiles.begin(), {"the parameter file", plan.paramsPath});
    checkOutputs(jobFiles, bake.fractal.inputs(), bake.force);
    return plan;
}

/// The shell lines that set $first and $last (the chunk's frames) from a task number.
std::string chunkLines(const FarmPlan& plan, const std::string& chunkExpression) {
    if (!plan.frames) return "";
    std::ostringstream lines;
    lines << "first=$((" << plan.frames->first << " + (" << chunkExpression << ") * " << plan.chunk << "))\n"
          << "last=$((first + " << plan.chunk - 1 << "))\n"
          << "if [ \"$last\" -gt " << plan.frames->last << " ]; then last=" << plan.frames->last << "; fi\n";
    return lines.str();
}

std::string sbatchHeader(const FarmFlags& flags, const FarmPlan& plan, const std::string& name, int tasks,
                         const std::string& what) {
    std::ostringstream text;
    text << "#!/bin/bash\n"
         << "# " << what << "\n"
         << "# Written by dqjulia " << dqj_version_string()
         << " (dqjulia farm slurm). Every machine needs the same dqjulia at the path below and this folder on shared "
            "storage;\n"
         << "# submitting again redoes only what is missing (--skip-existing).\n"
         << "#SBATCH --job-name=" << name << "\n"
         << "#SBATCH --array=0-" << tasks - 1 << "\n"
         << "#SBATCH --cpus-per-task=" << flags.cpus << "\n"
         << "#SBATCH --output=" << withoutExtension(plan.output) << ".slurm-%A_%a.log\n";
    if (!flags.partition.empty()) text << "#SBATCH --partition=" << flags.partition << "\n";
    if (!flags.time.empty()) text << "#SBATCH --time=" << flags.time << "\n";
    if (!flags.memory.empty()) text << "#SBATCH --mem=" << flags.memory << "\n";
    for (const std::string& option : flags.sbatchOptions) text << "#SBATCH " << option << "\n";
    text << "set -eu\n";
    return text.str();
}

std::string slurmBakeScript(const FarmFlags& flags, const FarmPlan& plan) {
    std::ostringstream text;
    const int tasks = plan.chunks() * plan.tiles();
    text << sbatchHeader(flags, plan, plan.name, tasks,
                         "Bakes " + plan.describe() + ": " + std::to_string(tasks) + " array tasks.");
    text << chunkLines(plan,
                       plan.tiling ? "SLURM_ARRAY_TASK_ID / " + std::to_string(plan.tiles()) : "SLURM_ARRAY_TASK_ID");
    text << "exec " << shellQuote(plan.dqjulia) << " bake -p " << shellQuote(plan.paramsPath);
    if (plan.frames) text << " --frames \"$first-$last\"";
    if (plan.tiling)
        text << " --tiles " << tilingText(*plan.tiling) << " --tile $((SLURM_ARRAY_TASK_ID % " << plan.tiles()
             << " + 1))";
    text << " -o " << shellQuote(plan.output) << " --skip-existing\n";
    return text.str();
}

std::string slurmMergeScript(const FarmFlags& flags, const FarmPlan& plan) {
    std::ostringstream text;
    text << sbatchHeader(flags, plan, plan.name + "-merge", plan.chunks(),
                         "Merges the tiles of " + plan.describe() + ": " + std::to_string(plan.chunks()) +
                             " array tasks, after the bake's (--dependency=afterok).");
    text << chunkLines(plan, "SLURM_ARRAY_TASK_ID");
    text << "exec " << shellQuote(plan.dqjulia) << " merge --tiles " << tilingText(*plan.tiling);
    if (plan.frames) text << " --frames \"$first-$last\"";
    text << " -o " << shellQuote(plan.output) << " --skip-existing\n";
    return text.str();
}

/// Runs `command` through sh; its standard output. Throws std::runtime_error when it fails.
std::string runCapturing(const std::string& command) {
#ifdef _WIN32
    FILE* pipe = ::_popen((command + " 2>&1").c_str(), "r");
#else
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
#endif
    if (!pipe) throw std::runtime_error("cannot run " + command);
    std::string output;
    char buffer[512];
    while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
#ifdef _WIN32
    const int status = ::_pclose(pipe);
    const int code = status;
#else
    const int status = ::pclose(pipe);
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
#endif
    if (status != 0) throw std::runtime_error(command + " failed (exit " + std::to_string(code) + "): " + output);
    return output;
}

int runSlurm(const FarmFlags& flags) {
    const std::string script =
        flags.file.empty() ? withoutExtension(utf8FromPath(fs::absolute(pathFromUtf8(flags.bake.output)))) + ".slurm"
                           : flags.file;
    const std::string mergeScript =
        withoutExtension(script) + ".merge" + utf8FromPath(pathFromUtf8(script).extension());
    std::vector<NamedPath> jobFiles{{"--script", script}};
    if (!flags.bake.tiles.empty()) jobFiles.push_back({"the merge script", mergeScript});
    FarmPlan job = plan(flags, jobFiles);
    if (job.chunks() * job.tiles() > kSlurmMaxArraySize)
        std::cerr << "dqjulia farm slurm: warning: " << job.chunks() * job.tiles()
                  << " array tasks: more than Slurm's default MaxArraySize allows (" << kSlurmMaxArraySize
                  << "); raise --chunk, or the cluster's MaxArraySize\n";
    AtomicFileSet files(existingPolicy(flags.bake.force));  // all of them or none
    files.add(job.paramsPath).stream() << toJson(job.params);
    files.add(script).stream() << slurmBakeScript(flags, job);
    if (job.tiling) files.add(mergeScript).stream() << slurmMergeScript(flags, job);
    files.commit();
    std::cerr << "wrote " << job.paramsPath << ", " << script << (job.tiling ? " and " + mergeScript : "") << " ("
              << job.describe() << ")\n";
    const std::string submitBake = "sbatch --parsable " + shellQuote(script);
    if (!flags.submit) {
        std::cout << "submit with:\n  ";
        if (job.tiling)
            std::cout << "job=$(" << submitBake << ") && sbatch --dependency=afterok:${job%%;*} "
                      << shellQuote(mergeScript) << "\n";
        else
            std::cout << submitBake << "\n";
        std::cout << "(or add --submit)\n";
        return kSuccess;
    }
    std::string id = runCapturing(submitBake);
    id = id.substr(0, id.find_first_of(";\n"));
    std::cout << "submitted " << script << " as job " << id << "\n";
    if (job.tiling) {
        std::string merge =
            runCapturing("sbatch --parsable --dependency=afterok:" + id + " " + shellQuote(mergeScript));
        merge = merge.substr(0, merge.find_first_of(";\n"));
        std::cout << "submitted " << mergeScript << " as job " << merge << " (after job " << id << ")\n";
    }
    return kSuccess;
}

nlohmann::ordered_json openJdStep(const std::string& name, const FarmPlan& plan, bool merge) {
    nlohmann::ordered_json args = nlohmann::ordered_json::array();
    nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
    if (merge)
        args = {"merge", "--tiles", tilingText(*plan.tiling)};
    else
        args = {"bake", "-p", "{{Param.Params}}"};
    if (plan.frames) {
        args.push_back("--frames");
        args.push_back("{{Task.Param.Frames}}");
        parameters.push_back({{"name", "Frames"}, {"type", "STRING"}, {"range", plan.chunkRanges()}});
    }
    if (plan.tiling && !merge) {
        const std::string tiling = tilingText(*plan.tiling);  // outlives the loop (a temporary's c_str() did not)
        for (const std::string& arg :
             {std::string("--tiles"), tiling, std::string("--tile"), std::string("{{Task.Param.Tile}}")})
            args.push_back(arg);
        parameters.push_back({{"name", "Tile"}, {"type", "INT"}, {"range", "1-" + std::to_string(plan.tiles())}});
    }
    for (const char* arg : {"-o", "{{Param.Output}}", "--skip-existing"}) args.push_back(arg);
    nlohmann::ordered_json step = {{"name", name}};
    if (!parameters.empty()) step["parameterSpace"] = {{"taskParameterDefinitions", parameters}};
    if (merge) step["dependencies"] = {{{"dependsOn", "Bake"}}};
    step["script"] = {{"actions", {{"onRun", {{"command", "{{Param.Dqjulia}}"}, {"args", args}}}}}};
    return step;
}

int runOpenJd(const FarmFlags& flags) {
    const std::string file =
        flags.file.empty()
            ? withoutExtension(utf8FromPath(fs::absolute(pathFromUtf8(flags.bake.output)))) + ".openjd.json"
            : flags.file;
    FarmPlan job = plan(flags, {{"--template", file}});
    if (job.chunks() > kMaxOpenJdChunks)
        throw ParamError("frames", std::to_string(job.chunks()) +
                                       " chunks of frames: an Open Job Description task "
                                       "parameter holds at most " +
                                       std::to_string(kMaxOpenJdChunks) + " values; raise --chunk");
    nlohmann::ordered_json document = {
        {"specificationVersion", "jobtemplate-2023-09"},
        {"name", job.name},
        {"description", "Bakes " + job.describe() + " with dqjulia " + dqj_version_string() +
                            " (dqjulia farm openjd); every task skips the files that exist"},
        // A PATH parameter's default is relative to the template's folder (and mapped between
        // machines by the farm); the command is a plain string.
        {"parameterDefinitions",
         {{{"name", "Dqjulia"},
           {"type", "STRING"},
           {"default", job.dqjulia},
           {"description", "The dqjulia command, the same version on every machine"}},
          {{"name", "Params"},
           {"type", "PATH"},
           {"objectType", "FILE"},
           {"dataFlow", "IN"},
           {"default", relativeTo(job.paramsPath, file)},
           {"description", "The complete parameter file of the bake"}},
          {{"name", "Output"},
           {"type", "PATH"},
           {"objectType", "FILE"},
           {"dataFlow", "OUT"},
           {"default", relativeTo(job.output, file)},
           {"description", "The bake's output (frames: NAME_0001.vdb, ...), on shared storage"}}}},
        {"steps", nlohmann::ordered_json::array({openJdStep("Bake", job, false)})}};
    if (job.tiling) document["steps"].push_back(openJdStep("Merge", job, true));
    AtomicFileSet files(existingPolicy(flags.bake.force));  // both or neither
    files.add(job.paramsPath).stream() << toJson(job.params);
    files.add(file).stream() << document.dump(2) << "\n";
    files.commit();
    std::cerr << "wrote " << job.paramsPath << " and " << file << " (" << job.describe() << ")\n";
    std::cout << "check and run it locally with:\n  openjd check " << shellQuote(file) << "\n  openjd run "
              << shellQuote(file) << (job.tiling ? " --step Merge --run-dependencies" : " --step Bake") << "\n"
              << "or submit it to a farm that runs Open Job Description (AWS Deadline Cloud: deadline bundle submit)\n";
    return kSuccess;
}

void addCommonFlags(CLI::App& command, FarmFlags& flags) {
    flags.bake.addTo(command, BakeCommand::Farm);
    command.add_option("--chunk", flags.chunk, "Frames a task bakes, one after another (default 1)")
        ->check(CLI::Range(1, 1000000));
    command.add_option("--name", flags.name, "The job's name (default: dqjulia-NAME)");
}

}  // namespace

Runner addFarmCommand(CLI::App& app) {
    auto slurm = std::make_shared<FarmFlags>();
    auto openjd = std::make_shared<FarmFlags>();
    CLI::App* farm =
        app.add_subcommand("farm",
                           "Write the job files that bake frames (and tiles) on a farm: Slurm, Open Job Description");
    farm->require_subcommand(1);
    CLI::App* slurmCommand =
        farm->add_subcommand("slurm", "An sbatch array script (and a dependent merge job for --tiles)");
    addCommonFlags(*slurmCommand, *slurm);
    slurmCommand->add_option("--script", slurm->file,
                             "The array script to write (default: NAME.slurm beside --output)");
    slurmCommand->add_option("--cpus-per-task", slurm->cpus, "CPUs a task gets, and the threads it uses (default 1)")
        ->check(CLI::Range(1, 4096));
    slurmCommand->add_option("--partition", slurm->partition, "sbatch --partition");
    slurmCommand->add_option("--time", slurm->time, "sbatch --time, a task's time limit");
    slurmCommand->add_option("--mem", slurm->memory, "sbatch --mem, a task's memory");
    slurmCommand->add_option("--sbatch", slurm->sbatchOptions,
                             "Another #SBATCH line, e.g. --sbatch=--qos=low (repeatable)");
    slurmCommand->add_flag("--submit", slurm->submit, "Submit the job(s) with sbatch");
    CLI::App* openjdCommand = farm->add_subcommand(
        "openjd", "An Open Job Description job template: frame chunks as a task parameter, tiles and a merge step");
    addCommonFlags(*openjdCommand, *openjd);
    openjdCommand->add_option("--template", openjd->file,
                              "The job template to write (default: NAME.openjd.json beside --output)");
    for (CLI::App* command : {slurmCommand, openjdCommand})
        command->footer(
            "The tasks' exit status: 0 done; 1 failed while working, a retry may help; 2 bad input, a "
            "retry cannot help; 130 interrupted (preempted), a retry helps. Retried or resubmitted "
            "tasks skip the files that exist.");
    return [slurm, openjd, slurmCommand] {
        if (slurmCommand->parsed()) return reportErrors("farm slurm", [&] { return runSlurm(*slurm); });
        return reportErrors("farm openjd", [&] { return runOpenJd(*openjd); });
    };
}

}  // namespace dqj::cli
