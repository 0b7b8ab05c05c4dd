#!/usr/bin/env python3
"""The job files of `dqjulia farm` run by the real engines, with their outputs checked against
the same bakes made here in one piece.

  farm_test.py slurm  --cli DQJULIA --work DIR --cluster scripts/slurm-local.sh
      brings up a one-node Slurm cluster on localhost (scripts/slurm-local.sh), submits a frame
      array (4 frames, 2 a task) and a tiled bake (2x2x1) with its dependent merge job, waits
      for the queue to empty (polling squeue: sbatch --wait can lag), compares every output
      with a local bake, and stops the daemons by their PIDs whatever happened. The cluster's
      folder is inside one of mode 0700 (as a checkout in /root is), which munged's user
      cannot enter.
  farm_test.py openjd --cli DQJULIA --work DIR --openjd OPENJD
      writes a template (3 frames in chunks of 2, 2 tiles each, a Merge step), has
      `openjd check` accept it and `openjd run` run it locally, and compares the merged frames.

Files are compared byte for byte but for the 36-byte random id OpenVDB writes into every
file's header. A missing engine skips the test (DQJ_TEST_SKIPPED), or fails it under CI=true.
Prints the run's timings. Cost: about 15 s (Slurm) and 10 s (OpenJD) at these small sizes.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import skip_or_fail  # noqa: E402 (tests/common/check_report.py)

ANIMATION = {
    "slice": {"rotations": [{"plane": "a.j,b.s", "degrees": 0}]},
    "animation": {
        "slice.rotations[0].degrees": [{"frame": 1, "value": 0}, {"frame": 4, "value": 30}],
        "fractal.iterations": [{"frame": 1, "value": 8}, {"frame": 4, "value": 12}],
    },
}


def run(command, **kwargs):
    """Runs a command; its stdout. Fails the test with its output if it exits non-zero."""
    result = subprocess.run(command, capture_output=True, text=True, **kwargs)
    if result.returncode != 0:
        sys.exit("FAIL (exit %d): %s\n%s\n%s" % (result.returncode, " ".join(command), result.stdout, result.stderr))
    return result.stdout


def vdb_bytes(path):
    """The file without OpenVDB's random file id (header bytes 21 to 57)."""
    with open(path, "rb") as file:
        data = bytearray(file.read())
    if len(data) < 64:
        sys.exit("FAIL: %s is not a VDB file" % path)
    data[21:57] = b"-" * 36
    return bytes(data)


def expect_same(made, reference):
    if not os.path.isfile(made):
        sys.exit("FAIL: the farm did not make %s" % made)
    if vdb_bytes(made) != vdb_bytes(reference):
        sys.exit("FAIL: %s differs from the local bake %s" % (made, reference))


def frame_path(path, frame):
    stem, extension = os.path.splitext(path)
    return "%s_%04d%s" % (stem, frame, extension)


def prepare(work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    params = os.path.join(work, "anim.json")
    with open(params, "w", encoding="utf-8") as file:
        json.dump(ANIMATION, file)
    return params


def test_slurm(args):
    for tool in ("slurmctld", "slurmd", "munged", "sbatch", "squeue"):
        if shutil.which(tool) is None:
            skip_or_fail("%s is not installed (scripts/install-deps.sh installs slurm-wlm and munge)" % tool)
    if os.geteuid() != 0:
        skip_or_fail("the local Slurm cluster needs root (munged runs as the munge user)")
    params = prepare(args.work)
    # The cluster's folder inside one of mode 0700, as a checkout in root's home on Debian is:
    # munged (the munge user) must keep its files where it can reach them all the same.
    private = os.path.join(args.work, "private")
    os.makedirs(private, mode=0o700)
    os.chmod(private, 0o700)
    cluster = os.path.join(private, "cluster")
    local = os.path.join(args.work, "local")
    os.makedirs(local)
    frames, tiles = os.path.join(args.work, "frames", "anim.vdb"), os.path.join(args.work, "tiles", "big.vdb")
    os.makedirs(os.path.dirname(frames))
    os.makedirs(os.path.dirname(tiles))
    started = time.monotonic()
    try:
        run([args.cluster, "start", cluster])
        up = time.monotonic()
        env = dict(os.environ, SLURM_CONF=os.path.join(cluster, "slurm.conf"))
        submissions = run([args.cli, "farm", "slurm", "-p", params, "--frames", "1-4", "--chunk", "2", "-r", "24",
                           "-o", frames, "--submit"], env=env)  # fmt: skip
        submissions += run([args.cli, "farm", "slurm", "-r", "40", "--grids", "surface,density",
                            "--tiles", "2x2x1", "-o", tiles, "--submit"], env=env)  # fmt: skip
        jobs = [line.split(" as job ")[1].split()[0] for line in submissions.splitlines() if " as job " in line]
        if len(jobs) != 3:
            sys.exit("FAIL: expected 3 jobs submitted (frames, tiles, merge):\n" + submissions)
        submitted = time.monotonic()
        deadline = submitted + 300
        while True:
            queue = run(["squeue", "-h", "-o", "%i %T %r"], env=env)
            if not queue.strip():
                break
            if "DependencyNeverSatisfied" in queue or time.monotonic() > deadline:
                sys.exit("FAIL: the jobs did not finish:\n" + queue)
            time.sleep(0.5)
        finished = time.monotonic()
        # Finished jobs stay known to slurmctld for MinJobAge (300 s): every task must have completed.
        states = "".join(run(["scontrol", "-o", "show", "job", job], env=env) for job in jobs)
        tasks = [line for line in states.splitlines() if line.strip()]
        if len(tasks) != 2 + 4 + 1 or any("JobState=COMPLETED" not in line for line in tasks):
            sys.exit("FAIL: not every task completed:\n" + states)
    finally:
        subprocess.run([args.cluster, "stop", cluster], check=False)
    run([args.cli, "bake", "-q", "-p", params, "--frames", "1-4", "-r", "24", "-o", os.path.join(local, "anim.vdb")])
    run([args.cli, "bake", "-q", "-r", "40", "--grids", "surface,density", "-o", os.path.join(local, "big.vdb")])
    for frame in range(1, 5):
        expect_same(frame_path(frames, frame), frame_path(os.path.join(local, "anim.vdb"), frame))
    expect_same(tiles, os.path.join(local, "big.vdb"))
    for index in range(1, 5):
        if not os.path.isfile(os.path.join(os.path.dirname(tiles), "big.tile_%d.vdb" % index)):
            sys.exit("FAIL: tile %d is missing" % index)
    print(
        "figures: Slurm: cluster up in %.1f s; a 2-task frame array (4 frames) and a 4-task tile array with its "
        "merge ran in %.1f s; %.1f s in all; 5 outputs equal to the local bakes"
        % (up - started, finished - submitted, finished - started)
    )


def test_openjd(args):
    if not args.openjd or not os.access(args.openjd, os.X_OK):
        skip_or_fail("openjd is not installed (scripts/tool-env.sh openjd installs openjd-cli)")
    params = prepare(args.work)
    output = os.path.join(args.work, "job", "anim.vdb")
    os.makedirs(os.path.dirname(output))
    started = time.monotonic()
    # Tiled: the surface and density only, which merge exactly (the colour grids within a tolerance).
    run([args.cli, "farm", "openjd", "-p", params, "--frames", "1-3", "--chunk", "2", "--tiles", "2x1x1", "-r", "24",
         "--grids", "surface,density", "-o", output])  # fmt: skip
    template = os.path.join(args.work, "job", "anim.openjd.json")
    checked = run([args.openjd, "check", template])
    if "passes validation" not in checked:
        sys.exit("FAIL: openjd check: " + checked)
    log = run([args.openjd, "run", template, "--step", "Merge", "--run-dependencies"], cwd=args.work)
    finished = time.monotonic()
    if "Session ended successfully" not in log:
        sys.exit("FAIL: openjd run:\n" + log)
    local = os.path.join(args.work, "local", "anim.vdb")
    os.makedirs(os.path.dirname(local))
    run(
        [args.cli, "bake", "-q", "-p", params, "--frames", "1-3", "-r", "24", "--grids", "surface,density", "-o", local]
    )
    for frame in range(1, 4):
        expect_same(frame_path(output, frame), frame_path(local, frame))
        for tile in (1, 2):
            name = "%s.tile_%d.vdb" % (os.path.splitext(frame_path(output, frame))[0], tile)
            if not os.path.isfile(name):
                sys.exit("FAIL: %s is missing" % name)
    print(
        "figures: Open Job Description: check, and a run of 4 bake tasks (2 chunks x 2 tiles) and 2 merge tasks, in "
        "%.1f s; 3 merged frames equal to the local bakes" % (finished - started)
    )


def engine_arguments(description):
    """The command line of the farm tests: the engine, dqjulia, a work folder and the engine's tools."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("engine", choices=("slurm", "openjd"))
    parser.add_argument("--cli", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--cluster", help="scripts/slurm-local.sh")
    parser.add_argument("--openjd", help="the openjd command (scripts/tool-env.sh openjd --print)")
    return parser


def main():
    args = engine_arguments(__doc__.splitlines()[0]).parse_args()
    (test_slurm if args.engine == "slurm" else test_openjd)(args)
    print("%s passed" % args.engine)


if __name__ == "__main__":
    main()
