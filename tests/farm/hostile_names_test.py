#!/usr/bin/env python3
"""Hostile names through the job files of `dqjulia farm`, read by the engines' own parsers.

  hostile_names_test.py slurm  --cli DQJULIA --work DIR --cluster scripts/slurm-local.sh [--cases N] [--seed S]
  hostile_names_test.py openjd --cli DQJULIA --work DIR --openjd OPENJD [--cases N] [--seed S]

Makes N names (seeded, so every run tries the same ones) from fragments a name should never be
able to use against a job file: spaces, both quotes, `#`, `$`, `$(...)`, backquotes, `;`,
backslashes, line breaks, tabs, carriage returns, escape sequences, `{{ }}`, Slurm's `%`
patterns, an `#SBATCH` line, non-ASCII and very long names. Each is used as the job's name
(--name), as the output's folder and file name (the job's default name then comes from it), or
both, with this dqjulia hard-linked into a folder of that name too (the job files name dqjulia by
its path). For each case:

- A name the format cannot carry is refused: exit 2, the character or limit named in the
  message, no file written. What each format cannot carry is decided here from the formats'
  rules (job_files.hpp), independently of dqjulia's code.
- Otherwise, after dqjulia is replaced by a stub that records its arguments and environment:
  slurm: every script is run by bash for each array task with xtrace on, and must run exactly its
    own commands, ending in one `exec` of the stub with exactly the intended arguments; then all
    scripts are submitted to a one-node Slurm cluster (scripts/slurm-local.sh), so the real
    sbatch parses them, and every task must run once: the job name Slurm gives the task
    (SLURM_JOB_NAME), the array (task ids and count), the CPUs and the arguments must be the
    intended ones, and each task's log must be exactly at the intended path.
  openjd: `openjd check` must accept the template, `openjd summary` must give the intended job
    name and parameter values, and `openjd run` must run each task's command once with exactly
    the intended arguments.
- No file named INJECTED (what the fragments' commands would make) appears anywhere.

A missing engine skips the test (DQJ_TEST_SKIPPED), or fails it under CI=true. Prints figures.
Cost: 2 to 4 s a case (Slurm starts array tasks in waves; `openjd run` starts a session per run):
31 cases in about 100 s (slurm) and 85 s (openjd) on a busy 2-core machine.
"""

import json
import os
import random
import shutil
import stat
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import skip_or_fail  # noqa: E402 (tests/common/check_report.py)
from farm_test import engine_arguments  # noqa: E402 (beside this file)

FRAGMENTS = [
    "a", "Z", "7", " ", "  ", "'", '"', "#", "$", "$HOME", "$(touch INJECTED)", "`touch INJECTED`", ";", "&&",
    "|", "*", "?", "[x]", "~", "!", "=", ":", "-", "--", ",", "\\", "\\n", "\\\"", "'\\''", "\n",
    "\ntouch INJECTED\n", "\t", "\r", "\x1b[31m", "\x7f", "\u0085", "{{", "}}", "{{Param.Output}}",
    "{{ Task.Param.Frames }}", "%", "%A", "%%", "%j_%a", "hetjob", "#SBATCH --array=0-99", "é", "日本語", "😀",
]  # fmt: skip
FIXED = [
    "My Projects",
    'it\'s "quoted" #1',
    "{{Param.JobName}}",
    "line one\nline two",
    "tab\there",
    "x" * 130,  # over Open Job Description's 128 characters for a name
    "y" * 1100,  # over Slurm's 1024 bytes for a name (and too long for a file name: --name only)
    "ümlaut-日本-😀",
]
MAX_FILE_NAME = 120  # bytes of a folder or file name made from a case (file systems allow 255)
FRAMES, CHUNK, TILES = (1, 5), 3, "2x1x1"  # chunks 1-3 and 4-5 (the last one clipped)


def make_cases(count, seed):
    """(kind, text) pairs: kind is "name", "path" or "both"; deterministic for a seed."""
    rng = random.Random(seed)
    texts = list(FIXED)
    while len(texts) < count:
        texts.append("".join(rng.choice(FRAGMENTS) for _ in range(rng.randint(1, 6))))
    kinds = ("name", "path", "both")
    cases = [(kinds[index % 3], text) for index, text in enumerate(texts[:count])]
    # Bytes that are not UTF-8 in a file name: Slurm carries them, a JSON template cannot.
    cases.append(("path", os.fsdecode(b"latin1-caf\xe9")))
    return cases


def file_name(text):
    """A folder or file name made from `text`: no "/" or NUL, at most MAX_FILE_NAME bytes."""
    name = text.replace("/", "_").replace("\0", "_")
    while len(os.fsencode(name)) > MAX_FILE_NAME:
        name = name[:-1]
    return "n" + name if name in ("", ".", "..") or name.startswith("-") else name


def is_cc(char):
    """Unicode's Cc category: C0, DEL and C1."""
    return ord(char) < 0x20 or 0x7F <= ord(char) < 0xA0


def utf8(text):
    try:
        text.encode("utf-8")
        return True
    except UnicodeEncodeError:  # surrogate escapes of bytes that are not UTF-8
        return False


class Case:
    """One hostile name in its places, and what each format must make of it."""

    def __init__(self, work, index, kind, text, cli, engine):
        self.index, self.kind, self.text = index, kind, text
        self.root = os.path.join(work, "case%03d" % index)
        hostile_path = kind in ("path", "both")
        folder = os.path.join(self.root, file_name(text) if hostile_path else "out")
        stem = file_name(text) if hostile_path else "job"
        self.output = os.path.join(folder, stem + ".vdb")
        self.base = os.path.join(folder, stem)
        self.name = text if kind in ("name", "both") else None
        self.tiles = index % 4 == 3  # every fourth case with tiles and a merge job
        bin_folder = os.path.join(self.root, "bin " + file_name(text) if hostile_path else "bin")
        self.dqjulia = os.path.join(bin_folder, "dqjulia")
        os.makedirs(folder)
        os.makedirs(bin_folder)
        try:
            os.link(cli, self.dqjulia)  # /proc/self/exe names the link
        except OSError:
            shutil.copy2(cli, self.dqjulia)
        self.engine = engine
        self.file = self.base + (".slurm" if engine == "slurm" else ".openjd.json")
        self.merge_file = self.base + ".merge.slurm"
        self.params = self.base + ".params.json"

    def job_name(self):
        return self.name if self.name is not None else "dqjulia-" + os.path.basename(self.base)

    def refusal(self):
        """What the format cannot carry here (a word the message must hold), or None."""
        name = self.job_name()
        if self.engine == "slurm":
            if "\n" in name or "\n" in self.output:
                return "line break"
            if "\\" in self.base:
                return "backslash"
            if len(os.fsencode(name + ("-merge" if self.tiles else ""))) > 1024:
                return "1024"
            return None
        if not utf8(self.output) or not utf8(self.dqjulia):
            return "not UTF-8"
        if self.name is None:
            name = name[:128]  # a default name is shortened, a given one refused
        for char in name:
            if is_cc(char):
                return "(U+%04X) at character %d" % (ord(char), name.index(char) + 1)
        if len(name) > 128:
            return "128"
        return None

    def command(self):
        args = [self.dqjulia, "farm", self.engine, "-r", "24", "--grids", "surface,density", "--frames",
                "%d-%d" % FRAMES, "--chunk", str(CHUNK), "-o", self.output]  # fmt: skip
        if self.tiles:
            args += ["--tiles", TILES]
        if self.name is not None:
            args += ["--name", self.name]
        return args

    def tasks(self):
        """(task id, first frame, last frame, tile or None) of the bake job's array."""
        chunks = [(first, min(first + CHUNK - 1, FRAMES[1])) for first in range(FRAMES[0], FRAMES[1] + 1, CHUNK)]
        if not self.tiles:
            return [(index, first, last, None) for index, (first, last) in enumerate(chunks)]
        return [
            (index * 2 + tile - 1, first, last, tile) for index, (first, last) in enumerate(chunks) for tile in (1, 2)
        ]

    def bake_args(self, first, last, tile):
        args = ["bake", "-p", self.params, "--frames", "%d-%d" % (first, last)]
        if tile is not None:
            args += ["--tiles", TILES, "--tile", str(tile)]
        return args + ["-o", self.output, "--skip-existing"]

    def merge_args(self, first, last):
        return ["merge", "--tiles", TILES, "--frames", "%d-%d" % (first, last), "-o", self.output, "--skip-existing"]

    def make_stub(self, record):
        """Replaces this case's dqjulia by a stub that records its arguments, cwd and Slurm's variables."""
        os.remove(self.dqjulia)
        with open(self.dqjulia, "w", encoding="utf-8") as file:
            file.write(STUB % {"record": repr(record)})
        os.chmod(self.dqjulia, stat.S_IRWXU | stat.S_IRGRP | stat.S_IXGRP | stat.S_IROTH | stat.S_IXOTH)


STUB = """#!/usr/bin/python3
import json, os, sys
keys = ("SLURM_JOB_NAME", "SLURM_ARRAY_JOB_ID", "SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_COUNT",
        "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_MAX", "SLURM_CPUS_PER_TASK", "STUB_TAG")
entry = {"argv": [os.fsencode(a).decode("utf-8", "surrogateescape") for a in sys.argv[1:]], "cwd": os.getcwd(),
         "env": {key: os.environ.get(key) for key in keys}}
with open(%(record)s, "a", encoding="utf-8", errors="surrogateescape") as file:
    file.write(json.dumps(entry) + "\\n")
print("stub ran")
"""


def read_text(path):
    """The text of the file at `path`, or None if there is none."""
    if not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as file:
        return file.read()


def records(path):
    if not os.path.exists(path):
        return []
    with open(path, encoding="utf-8", errors="surrogateescape") as file:
        return [json.loads(line) for line in file if line.strip()]


def fail(case, message):
    sys.exit("FAIL (case %d, %s, %r): %s" % (case.index, case.kind, case.text[:200], message))


def write_job_files(case):
    """Runs `dqjulia farm`; checks a refusal. True if the files were written."""
    result = subprocess.run(case.command(), capture_output=True, cwd=case.root)
    err = result.stderr.decode("utf-8", "replace")
    refusal = case.refusal()
    written = [path for path in (case.file, case.merge_file, case.params) if os.path.lexists(path)]
    if refusal is not None:
        if result.returncode != 2:
            fail(case, "expected a refusal (%s), got exit %d: %s" % (refusal, result.returncode, err))
        if refusal not in err:
            fail(case, "the refusal does not say %r: %s" % (refusal, err))
        if written:
            fail(case, "refused, but wrote %s" % written)
        return False
    if result.returncode != 0:
        fail(case, "exit %d: %s" % (result.returncode, err))
    return True


def check_no_injection(work):
    for folder, _, files in os.walk(work):
        if "INJECTED" in files:
            sys.exit("FAIL: a name ran a command: %s" % os.path.join(folder, "INJECTED"))


def run_script_locally(case, script, task, expected, record, token):
    """Runs `script` as array task `task` in bash with xtrace; checks the commands it ran."""
    env = {"PATH": "/nonexistent", "SLURM_ARRAY_TASK_ID": str(task), "STUB_TAG": "local"}
    before = len(records(record))
    # PS4 set inside (bash ignores it from the environment when run as root); every traced
    # simple command starts with the token, whatever its arguments hold.
    trace = subprocess.run(
        ["/bin/bash", "-c", 'PS4="+%s "; set -x; . "$1"' % token, "bash", script],
        capture_output=True, env=env, cwd=case.root,
    )  # fmt: skip
    if trace.returncode != 0:
        fail(case, "%s, task %d: bash exit %d: %s" % (script, task, trace.returncode, trace.stderr[-2000:]))
    commands = trace.stderr.decode("utf-8", "replace").split("+" + token + " ")[2:]  # after the `.` itself
    verbs = [command.split("=")[0].split(" ")[0] for command in commands]
    allowed = ["set", "first", "last", "'['", "last", "exec"]
    if verbs[0] != "set" or verbs[-1] != "exec" or any(verb not in allowed for verb in verbs) or len(verbs) > 6:
        fail(case, "%s, task %d ran other commands: %s" % (script, task, verbs))
    ran = records(record)[before:]
    if len(ran) != 1 or ran[0]["argv"] != expected:
        fail(case, "%s, task %d ran %s, expected one run of %s" % (script, task, ran, expected))


def test_slurm(args, cases):
    for tool in ("slurmctld", "slurmd", "munged", "sbatch", "squeue"):
        if shutil.which(tool) is None:
            skip_or_fail("%s is not installed (scripts/install-deps.sh installs slurm-wlm and munge)" % tool)
    if os.geteuid() != 0:
        skip_or_fail("the local Slurm cluster needs root (munged runs as the munge user)")
    accepted = [case for case in cases if write_job_files(case)]
    record = os.path.join(args.work, "record.jsonl")
    token = "TRACE%08x" % random.Random(args.seed).getrandbits(32)
    for case in accepted:
        case.make_stub(record)
        for task, first, last, tile in case.tasks():
            run_script_locally(case, case.file, task, case.bake_args(first, last, tile), record, token)
        if case.tiles:
            chunks = sorted({(first, last) for _, first, last, _ in case.tasks()})
            for task, (first, last) in enumerate(chunks):
                run_script_locally(case, case.merge_file, task, case.merge_args(first, last), record, token)
    check_no_injection(args.work)
    local_runs = len(records(record))

    cluster = os.path.join(args.work, "cluster")
    started = time.monotonic()
    jobs = {}  # job id -> (case, script)
    try:
        subprocess.run([args.cluster, "start", cluster], check=True, capture_output=True)
        env = dict(os.environ, SLURM_CONF=os.path.join(cluster, "slurm.conf"), STUB_TAG="slurm")
        for case in accepted:
            scripts = [case.file] + ([case.merge_file] if case.tiles else [])
            for script in scripts:  # the merge script alone too: sbatch parses it the same way
                submitted = subprocess.run(
                    ["sbatch", "--parsable", script], capture_output=True, env=env, cwd=case.root
                )
                if submitted.returncode != 0:
                    fail(case, "sbatch %s: %s" % (script, submitted.stderr.decode("utf-8", "replace")))
                jobs[submitted.stdout.decode().strip().split(";")[0]] = (case, script)
        deadline = time.monotonic() + 600
        while True:
            queue = subprocess.run(["squeue", "-h", "-o", "%i %T %r"], capture_output=True, env=env, text=True)
            if queue.returncode == 0 and not queue.stdout.strip():
                break
            if time.monotonic() > deadline:
                sys.exit("FAIL: the jobs did not finish:\n" + queue.stdout)
            time.sleep(0.5)
    finally:
        subprocess.run([args.cluster, "stop", cluster], check=False)
    finished = time.monotonic()

    ran = [entry for entry in records(record) if entry["env"]["STUB_TAG"] == "slurm"]
    tasks = 0
    for job, (case, script) in jobs.items():
        merge = script == case.merge_file
        chunks = sorted({(first, last) for _, first, last, _ in case.tasks()})
        expected = (
            {task: case.merge_args(first, last) for task, (first, last) in enumerate(chunks)}
            if merge
            else {task: case.bake_args(first, last, tile) for task, first, last, tile in case.tasks()}
        )
        mine = [entry for entry in ran if entry["env"]["SLURM_ARRAY_JOB_ID"] == job]
        got = {int(entry["env"]["SLURM_ARRAY_TASK_ID"]): entry for entry in mine}
        if len(mine) != len(expected) or set(got) != set(expected):
            fail(case, "%s: job %s ran tasks %s, expected %s" % (script, job, sorted(got), sorted(expected)))
        for task, entry in got.items():
            env = entry["env"]
            name = case.job_name() + ("-merge" if merge else "")
            if env["SLURM_JOB_NAME"] != name:
                fail(case, "%s: Slurm named the job %r, not %r" % (script, env["SLURM_JOB_NAME"], name))
            array = (str(len(expected)), "0", str(len(expected) - 1))
            if (env["SLURM_ARRAY_TASK_COUNT"], env["SLURM_ARRAY_TASK_MIN"], env["SLURM_ARRAY_TASK_MAX"]) != array:
                fail(case, "%s: Slurm's array is %s, not %s" % (script, env, array))
            if env["SLURM_CPUS_PER_TASK"] != "1":
                fail(case, "%s: %s CPUs a task" % (script, env["SLURM_CPUS_PER_TASK"]))
            if entry["argv"] != expected[task]:
                fail(case, "%s, task %d: ran %s, expected %s" % (script, task, entry["argv"], expected[task]))
            log = "%s.slurm-%s_%d.log" % (case.base, job, task)
            if read_text(log) != "stub ran\n":
                fail(case, "%s, task %d: no log at %r; the folder holds %s"
                     % (script, task, log, sorted(os.listdir(os.path.dirname(case.base)))))  # fmt: skip
            tasks += 1
    check_no_injection(args.work)
    print(
        "figures: Slurm: %d cases, %d refused as the format requires, %d accepted: %d local runs of the scripts "
        "by bash, %d jobs (%d tasks) parsed by sbatch and run by Slurm in %.1f s, every name, array, argument "
        "list and log path as intended"
        % (len(cases), len(cases) - len(accepted), len(accepted), local_runs, len(jobs), tasks, finished - started)
    )


def test_openjd(args, cases):
    if not args.openjd or not os.access(args.openjd, os.X_OK):
        skip_or_fail("openjd is not installed (scripts/tool-env.sh openjd installs openjd-cli)")
    accepted = [case for case in cases if write_job_files(case)]
    record = os.path.join(args.work, "record.jsonl")
    started = time.monotonic()
    for case in accepted:
        checked = subprocess.run([args.openjd, "check", case.file], capture_output=True, text=True)
        if checked.returncode != 0 or "passes validation" not in checked.stdout:
            fail(case, "openjd check: %s %s" % (checked.stdout, checked.stderr))
        summary = subprocess.run([args.openjd, "summary", case.file, "--output", "json"], capture_output=True)
        if summary.returncode != 0:
            fail(case, "openjd summary: %s" % summary.stderr.decode("utf-8", "replace"))
        summary = json.loads(summary.stdout)
        name = case.job_name() if case.name is not None else case.job_name()[:128]
        if summary["name"] != name:
            fail(case, "the job's name is %r, not %r" % (summary["name"], name))
        values = {parameter["name"]: parameter["value"] for parameter in summary["parameter_definitions"]}
        intended = {"Dqjulia": case.dqjulia, "Params": case.params, "Output": case.output, "JobName": name}
        for key, value in intended.items():
            got = os.path.normpath(values[key]) if key in ("Params", "Output") else values[key]
            if got != value:
                fail(case, "parameter %s is %r, not %r" % (key, values[key], value))
        case.make_stub(record)
        before = len(records(record))
        step = ["--step", "Merge", "--run-dependencies"] if case.tiles else ["--step", "Bake"]
        log = subprocess.run([args.openjd, "run", case.file] + step, capture_output=True, cwd=case.root,
                             env=dict(os.environ, STUB_TAG="openjd"))  # fmt: skip
        if log.returncode != 0:
            fail(case, "openjd run: %s" % log.stdout.decode("utf-8", "replace")[-3000:])
        ran = records(record)[before:]
        expected = [case.bake_args(first, last, tile) for _, first, last, tile in case.tasks()]
        if case.tiles:
            chunks = sorted({(first, last) for _, first, last, _ in case.tasks()})
            expected += [case.merge_args(first, last) for first, last in chunks]
        # PATH parameters arrive absolute (mapped from the template's folder): compare them as paths.
        got = [[os.path.normpath(arg) if arg.startswith("/") else arg for arg in entry["argv"]] for entry in ran]
        if sorted(got) != sorted(expected):
            fail(case, "openjd run ran %s, expected %s" % (got, expected))
    finished = time.monotonic()
    check_no_injection(args.work)
    print(
        "figures: Open Job Description: %d cases, %d refused as the format requires, %d accepted: each template "
        "checked, summarised (name and parameters as intended) and run (every task once, exactly its arguments) "
        "in %.1f s" % (len(cases), len(cases) - len(accepted), len(accepted), finished - started)
    )


def main():
    parser = engine_arguments(__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=30)
    parser.add_argument("--seed", type=int, default=35)
    args = parser.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    cases = [
        Case(args.work, index, kind, text, args.cli, args.engine)
        for index, (kind, text) in enumerate(make_cases(args.cases, args.seed))
    ]
    (test_slurm if args.engine == "slurm" else test_openjd)(args, cases)
    print("%s passed" % args.engine)


if __name__ == "__main__":
    main()
