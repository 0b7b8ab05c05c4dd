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
// Every name and path goes into the files through job_files.hpp's writers, quoted for the
// format's own parser or refused (exit 2) before anything is written.
// Cost: writing two or three small files; checking the frames (keyframes.hpp's checkFrames).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "files/atomic_file.hpp"
#include "bake_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/dqjulia.h"
#include "dqjulia/threads.hpp"
#include "dqjulia/tiles.hpp"
#include "platform/platform.hpp"
#include "job_files.hpp"

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
    std::string nameFlag;  // where the name came from, for messages
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

std::string withoutExtension(const std::string& path) {
    return platform::utf8FromPath(platform::pathFromUtf8(path).parent_path() / platform::pathFromUtf8(path).stem());
}

/// `path` relative to the folder of `file`.
std::string relativeTo(const std::string& path, const std::string& file) {
    return platform::utf8FromPath(platform::pathFromUtf8(path).lexically_relative(
        fs::absolute(platform::pathFromUtf8(file)).parent_path().lexically_normal()));
}

/// Plans the job and checks its files: the parameter file every task reads and `jobFiles`. Throws ParamError.
FarmPlan plan(const FarmFlags& flags, std::vector<NamedPath> jobFiles) {
    const BakeFlags& bake = flags.bake;
    FarmPlan plan;
    plan.params = bake.load();
    const Params& params = plan.params;
    plan.output = platform::utf8FromPath(fs::absolute(platform::pathFromUtf8(bake.output)).lexically_normal());
    if (AtomicFile::lowercaseExtension(plan.output) != ".vdb")
        throw ParamError("output.path", "--output '" + inputExcerpt(bake.output) + "' must end in .vdb");
    plan.frames = bake.frameRange();
    plan.chunk = flags.chunk;
    plan.tiling = bake.tiling();
    if (plan.tiling) {
        plan.tiling->index = 1;
        checkTile(params, *plan.tiling);
    }
    const FrameRange range = plan.frames.value_or(FrameRange{});
    checkFrames(params, range.first, range.last);  // every frame valid before anything is submitted
    plan.name = flags.name.empty() ? "dqjulia-" + platform::utf8FromPath(platform::pathFromUtf8(plan.output).stem())
                                   : flags.name;
    plan.nameFlag = flags.name.empty() ? "--output (its file name names the job: give --name)" : "--name";
    plan.dqjulia = platform::executablePath();
    plan.paramsPath = withoutExtension(plan.output) + ".params.json";
    jobFiles.insert(jobFiles.begin(), {"the parameter file", plan.paramsPath});
    checkOutputs(jobFiles, bake.fractal.inputs(), bake.force);
    return plan;
}

/// The shell lines that set $first and $last (the chunk's frames) from a task number.
void addChunkLines(SlurmScript& script, const FarmPlan& plan, const std::string& chunkExpression) {
    if (!plan.frames) return;
    script.command("first=$((" + std::to_string(plan.frames->first) + " + (" + chunkExpression + ") * " +
                   std::to_string(plan.chunk) + "))");
    script.command("last=$((first + " + std::to_string(plan.chunk - 1) + "))");
    script.command("if [ \"$last\" -gt " + std::to_string(plan.frames->last) +
                   " ]; then last=" + std::to_string(plan.frames->last) + "; fi");
}

/// The script's comments and #SBATCH lines.
SlurmScript sbatchHeader(const FarmFlags& flags, const FarmPlan& plan, const std::string& name, int tasks,
                         const std::string& what) {
    SlurmScript script;
    script.comment(what);
    script.comment(std::string("Written by dqjulia ") + dqj_version_string() +
                   " (dqjulia farm slurm). Every machine needs the same dqjulia at the path below and this folder "
                   "on shared storage;");
    script.comment("submitting again redoes only what is missing (--skip-existing).");
    script.directive("--job-name", name, plan.nameFlag);
    script.directive("--array", "0-" + std::to_string(tasks - 1), "--frames");
    script.directive("--cpus-per-task", std::to_string(flags.cpus), "--cpus-per-task");
    script.directive("--output", SlurmScript::logPattern(withoutExtension(plan.output), ".slurm-%A_%a.log", "--output"),
                     "--output");
    if (!flags.partition.empty()) script.directive("--partition", flags.partition, "--partition");
    if (!flags.time.empty()) script.directive("--time", flags.time, "--time");
    if (!flags.memory.empty()) script.directive("--mem", flags.memory, "--mem");
    for (const std::string& option : flags.sbatchOptions) script.argument(option, "--sbatch");
    script.command("set -eu");
    return script;
}

std::string slurmBakeScript(const FarmFlags& flags, const FarmPlan& plan) {
    const int tasks = plan.chunks() * plan.tiles();
    SlurmScript script = sbatchHeader(flags, plan, plan.name, tasks,
                                      "Bakes " + plan.describe() + ": " + std::to_string(tasks) + " array tasks.");
    addChunkLines(script, plan,
                  plan.tiling ? "SLURM_ARRAY_TASK_ID / " + std::to_string(plan.tiles()) : "SLURM_ARRAY_TASK_ID");
    std::string line = "exec " + shellWord(plan.dqjulia) + " bake -p " + shellWord(plan.paramsPath);
    if (plan.frames) line += " --frames \"$first-$last\"";
    if (plan.tiling)
        line += " --tiles " + tilingText(*plan.tiling) + " --tile $((SLURM_ARRAY_TASK_ID % " +
                std::to_string(plan.tiles()) + " + 1))";
    script.command(line + " -o " + shellWord(plan.output) + " --skip-existing");
    return script.text();
}

std::string slurmMergeScript(const FarmFlags& flags, const FarmPlan& plan) {
    SlurmScript script = sbatchHeader(flags, plan, plan.name + "-merge", plan.chunks(),
                                      "Merges the tiles of " + plan.describe() + ": " + std::to_string(plan.chunks()) +
                                          " array tasks, after the bake's (--dependency=afterok).");
    addChunkLines(script, plan, "SLURM_ARRAY_TASK_ID");
    std::string line = "exec " + shellWord(plan.dqjulia) + " merge --tiles " + tilingText(*plan.tiling);
    if (plan.frames) line += " --frames \"$first-$last\"";
    script.command(line + " -o " + shellWord(plan.output) + " --skip-existing");
    return script.text();
}

/// Runs `command` through the shell; its standard output. Throws std::runtime_error when it fails.
std::string runCapturing(const std::string& command) {
    const platform::CommandOutput result = platform::runCommand(command);
    if (result.exitCode != 0)
        throw std::runtime_error(command + " failed (exit " + std::to_string(result.exitCode) + "): " + result.output);
    return result.output;
}

/// --file, or the output's absolute path with `extension` for its own (out.vdb: out.slurm).
std::string jobFile(const FarmFlags& flags, const std::string& extension) {
    if (!flags.file.empty()) return flags.file;
    return withoutExtension(platform::utf8FromPath(fs::absolute(platform::pathFromUtf8(flags.bake.output)))) +
           extension;
}

int runSlurm(const FarmFlags& flags) {
    const std::string script = jobFile(flags, ".slurm");
    const std::string mergeScript =
        withoutExtension(script) + ".merge" + platform::utf8FromPath(platform::pathFromUtf8(script).extension());
    std::vector<NamedPath> jobFiles{{"--script", script}};
    if (!flags.bake.tiles.empty()) jobFiles.push_back({"the merge script", mergeScript});
    FarmPlan job = plan(flags, jobFiles);
    SlurmScript::checkJobName(job.name + (job.tiling ? "-merge" : ""), job.nameFlag);
    // Every text before the first file, so a value the format cannot carry leaves nothing behind.
    const std::string bakeText = slurmBakeScript(flags, job);
    const std::string mergeText = job.tiling ? slurmMergeScript(flags, job) : "";
    if (job.chunks() * job.tiles() > kSlurmMaxArraySize)
        std::cerr << "dqjulia farm slurm: warning: " << job.chunks() * job.tiles()
                  << " array tasks: more than Slurm's default MaxArraySize allows (" << kSlurmMaxArraySize
                  << "); raise --chunk, or the cluster's MaxArraySize\n";
    AtomicFileSet files(existingPolicy(flags.bake.force));  // all of them or none
    files.add(job.paramsPath).stream() << toJson(job.params);
    files.add(script).stream() << bakeText;
    if (job.tiling) files.add(mergeScript).stream() << mergeText;
    files.commit();
    std::cerr << "wrote " << job.paramsPath << ", " << script << (job.tiling ? " and " + mergeScript : "") << " ("
              << job.describe() << ")\n";
    const std::string submitBake = "sbatch --parsable " + shellWord(script);
    if (!flags.submit) {
        std::cout << "submit with:\n  ";
        if (job.tiling)
            std::cout << "job=$(" << submitBake << ") && sbatch --dependency=afterok:${job%%;*} "
                      << shellWord(mergeScript) << "\n";
        else
            std::cout << submitBake << "\n";
        std::cout << "(or add --submit)\n";
        return kSuccess;
    }
    std::string id = runCapturing(submitBake);
    id = id.substr(0, id.find_first_of(";\n"));
    std::cout << "submitted " << script << " as job " << id << "\n";
    if (job.tiling) {
        std::string merge = runCapturing("sbatch --parsable --dependency=afterok:" + id + " " + shellWord(mergeScript));
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
    const std::string file = jobFile(flags, ".openjd.json");
    FarmPlan job = plan(flags, {{"--template", file}});
    if (job.chunks() > kMaxOpenJdChunks)
        throw ParamError("frames", std::to_string(job.chunks()) +
                                       " chunks of frames: an Open Job Description task "
                                       "parameter holds at most " +
                                       std::to_string(kMaxOpenJdChunks) + " values; raise --chunk");
    // Names and paths are job parameters' values, never format-string text (job_files.hpp).
    const std::string name =
        OpenJd::jobName(flags.name.empty() ? OpenJd::shortenedName(job.name) : job.name, job.nameFlag);
    const std::string dqjulia = OpenJd::parameterValue(job.dqjulia, "this dqjulia's path");
    const std::string params = OpenJd::parameterValue(relativeTo(job.paramsPath, file), "the parameter file's path");
    const std::string output = OpenJd::parameterValue(relativeTo(job.output, file), "--output");
    nlohmann::ordered_json document = {
        {"specificationVersion", "jobtemplate-2023-09"},
        {"name", "{{Param.JobName}}"},
        {"description", "Bakes " + job.describe() + " with dqjulia " + dqj_version_string() +
                            " (dqjulia farm openjd); every task skips the files that exist"},
        // A PATH parameter's default is relative to the template's folder (and mapped between
        // machines by the farm); the command is a plain string.
        {"parameterDefinitions",
         {{{"name", "Dqjulia"},
           {"type", "STRING"},
           {"default", dqjulia},
           {"description", "The dqjulia command, the same version on every machine"}},
          {{"name", "Params"},
           {"type", "PATH"},
           {"objectType", "FILE"},
           {"dataFlow", "IN"},
           {"default", params},
           {"description", "The complete parameter file of the bake"}},
          {{"name", "Output"},
           {"type", "PATH"},
           {"objectType", "FILE"},
           {"dataFlow", "OUT"},
           {"default", output},
           {"description", "The bake's output (frames: NAME_0001.vdb, ...), on shared storage"}},
          {{"name", "JobName"},
           {"type", "STRING"},
           {"minLength", 1},
           {"maxLength", OpenJd::kMaxNameCharacters},
           {"default", name},
           {"description", "The job's name"}}}},
        {"steps", nlohmann::ordered_json::array({openJdStep("Bake", job, false)})}};
    if (job.tiling) document["steps"].push_back(openJdStep("Merge", job, true));
    const std::string text = document.dump(2) + "\n";
    AtomicFileSet files(existingPolicy(flags.bake.force));  // both or neither
    files.add(job.paramsPath).stream() << toJson(job.params);
    files.add(file).stream() << text;
    files.commit();
    std::cerr << "wrote " << job.paramsPath << " and " << file << " (" << job.describe() << ")\n";
    std::cout << "check and run it locally with:\n  openjd check " << shellWord(file) << "\n  openjd run "
              << shellWord(file) << (job.tiling ? " --step Merge --run-dependencies" : " --step Bake") << "\n"
              << "or submit it to a farm that runs Open Job Description (AWS Deadline Cloud: deadline bundle submit)\n";
    return kSuccess;
}

void addCommonFlags(CLI::App& command, FarmFlags& flags) {
    flags.bake.addTo(command, BakeCommand::Farm);
    command.add_option("--chunk", flags.chunk, "Frames a task bakes, one after another (default 1)")
        ->check(CLI::Range(1, 1000000));
    command.add_option("--name", flags.name,
                       "The job's name (default: dqjulia-NAME; Open Job Description keeps 128 characters of it)");
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
        ->check(CLI::Range(1, kMaxThreadCount));
    slurmCommand->add_option("--partition", slurm->partition, "sbatch --partition");
    slurmCommand->add_option("--time", slurm->time, "sbatch --time, a task's time limit");
    slurmCommand->add_option("--mem", slurm->memory, "sbatch --mem, a task's memory");
    slurmCommand->add_option("--sbatch", slurm->sbatchOptions,
                             "Another #SBATCH line: one sbatch option a flag, e.g. --sbatch=--qos=low (repeatable)");
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
