"""dqjulia.exe run under Wine as a Windows user runs it, against the Linux build's dqjulia: the
default picture, a bake and a mesh, each compared with the Linux one by the Linux build's
compare_outputs (its PNG reader, the Linux OpenVDB); every output named with a drive letter and
backslashes, in a folder with spaces and letters beyond ASCII; an existing output kept without
--force and replaced with it; no temporary file left behind; names Windows cannot hold (CON, NUL,
COM1, a trailing dot, a stream) refused before the work; an input never an output; a multi-file
run replaced all together; `explore --around` giving the same documents as on Linux for a seed.

Usage: python3 cli_test.py WORK LINUX_BUILD DQJULIA_EXE EMULATOR...
"""

import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report, skip_or_fail  # noqa: E402 (tests/common/check_report.py)

FOLDER = "cli \u00e9t\u00e9 \u65e5\u672c"  # "cli été 日本"

# (name, arguments, compare_outputs kind): the default picture, and a bake and a mesh small enough
# to be quick under Wine.
OUTPUTS = (
    ("fractal.png", ["render", "-q"], "png"),
    ("fractal.vdb", ["bake", "-q", "-r", "96"], "vdb"),
    ("fractal.ply", ["mesh", "-q", "-r", "96"], "ply"),
)


def windows_path(path):
    """A Linux path as a Windows program under Wine names it: drive Z: is /."""
    return "Z:" + os.path.abspath(path).replace("/", "\\")


def run(command):
    result = subprocess.run(command, capture_output=True, text=True, encoding="utf-8", errors="replace")
    return result.returncode, result.stdout + result.stderr


def main():
    work, linux_build, exe, *emulator = sys.argv[1:]
    linux_cli = os.path.join(linux_build, "bin", "dqjulia")
    compare = os.path.join(linux_build, "bin", "compare_outputs")
    for program in (linux_cli, compare):
        if not os.access(program, os.X_OK):
            skip_or_fail("%s is missing: build the Linux tree first (scripts/build.sh)" % program)
    shutil.rmtree(work, ignore_errors=True)
    linux_dir, windows_dir = os.path.join(work, "linux"), os.path.join(work, FOLDER)
    os.makedirs(linux_dir)
    os.makedirs(windows_dir)
    checks = {}

    for name, arguments, kind in OUTPUTS:
        linux_file, windows_file = os.path.join(linux_dir, name), os.path.join(windows_dir, name)
        status, output = run([linux_cli, *arguments, "-o", linux_file])
        checks["linux dqjulia %s: exit %d %s" % (arguments[0], status, output.strip())] = status == 0
        status, output = run([*emulator, exe, *arguments, "-o", windows_path(windows_file)])
        checks["dqjulia.exe %s: exit %d %s" % (arguments[0], status, output.strip())] = status == 0
        status, output = run([compare, kind, linux_file, windows_file])
        print("%s, Linux against Windows: %s" % (name, output.strip().replace("\n", "; ")))
        checks["%s equal on Linux and Windows" % name] = status == 0

    # An existing output is kept without --force (before any work), and replaced with it.
    picture = windows_path(os.path.join(windows_dir, "fractal.png"))
    small = ["render", "-q", "-W", "48", "-H", "36", "-o", picture]
    status, output = run([*emulator, exe, *small])
    checks["without --force an existing file is kept: exit %d %s" % (status, output.strip())] = (
        status == 2 and "exists; pass --force" in output
    )
    status, output = run([*emulator, exe, *small, "--force"])
    checks["with --force it is replaced: exit %d %s" % (status, output.strip())] = status == 0
    pictures = [os.path.join(folder, "fractal.png") for folder in (linux_dir, windows_dir)]
    status, output = run([compare, "png", *pictures])
    checks["the replaced picture is the new one (48x36)"] = status == 1 and "sizes differ" in output

    names = sorted(os.listdir(windows_dir))
    checks["the folder holds the outputs and nothing else (no temporary file): %s" % names] = names == sorted(
        name for name, _, _ in OUTPUTS
    )
    checks.update(check_outputs(work, exe, emulator))
    checks.update(check_variations(work, linux_cli, exe, emulator))
    return report(checks)


def check_variations(work, linux_cli, exe, emulator):
    """`explore --around` with the same seed gives the same parameter documents, byte for byte
    but for the output path (the folder's name), on Linux and Windows (issue 38)."""
    checks = {}
    start = os.path.join(work, "start.json")
    with open(start, "w") as file:
        file.write('{"description": "start", "fractal": {"iterations": 12}}\n')
    folders = {"Linux": os.path.join(work, "around linux"), "Windows": os.path.join(work, "around windows")}
    settings = ["explore", "-q", "--seed", "5", "--strength", "large", "--lock", "variant", "--count", "4"]
    settings += ["--tile-width", "24", "--tile-height", "24"]
    for system, command in (("Linux", [linux_cli]), ("Windows", [*emulator, exe])):
        around = start if system == "Linux" else windows_path(start)
        folder = folders[system] if system == "Linux" else windows_path(folders[system])
        status, output = run([*command, *settings, "--around", around, "-o", folder])
        checks["%s explore --around: exit %d %s" % (system, status, output.strip())] = status == 0
    for tile in range(1, 5):
        documents = []
        for folder in folders.values():
            try:
                with open(os.path.join(folder, "tile_%02d.json" % tile), "rb") as file:
                    lines = file.read().split(b"\n")
            except OSError:
                lines = None
            # Byte for byte but for output.path's line: the folders differ.
            documents.append(lines and [line for line in lines if not line.lstrip().startswith(b'"path"')])
        checks["explore --around tile %d byte for byte the same on Linux and Windows" % tile] = (
            documents[0] is not None and documents[0] == documents[1]
        )
    return checks


# Names Windows cannot hold, as a file or as a folder on the way: each refused before the work.
IMPOSSIBLE = (
    ("CON.png", "reserves for a device"),
    ("nul", "reserves for a device"),
    ("Aux.tar.png", "reserves for a device"),
    ("com1.png", "reserves for a device"),
    ("LPT9.png", "reserves for a device"),
    ("CONOUT$.png", "reserves for a device"),
    ("NUL .png", "reserves for a device"),
    ("PRN\\picture.png", "reserves for a device"),
    ("picture.png.", "which Windows removes"),
    ("picture.png ", "which Windows removes"),
    ("picture.png:stream", "a colon names a data stream"),
)


def check_outputs(work, exe, emulator):
    """The rules for outputs on Windows: impossible names refused before any work (exit 2, nothing
    written), an input never an output (file identity, whatever the spelling), and a run's files
    replaced all together."""
    checks = {}
    folder = os.path.join(work, "outputs")
    os.makedirs(folder)
    here = windows_path(folder)
    for name, reason in IMPOSSIBLE:
        # A render of 1600x1200 takes many seconds under Wine: a refusal after it would show. The
        # format is given, so that names not ending in .png meet the Windows rule, not the extension's.
        render = ["render", "-q", "-W", "1600", "-H", "1200", "--format", "png8"]
        status, output = run([*emulator, exe, *render, "-o", here + "\\" + name])
        checks["%r refused before the work: exit %d %s" % (name, status, output.strip())] = (
            status == 2 and reason in output and not os.listdir(folder)
        )
    # The other writers, a reserved name in a folder of the path or in a second output.
    for arguments in (
        ["bake", "-q", "-r", "1024", "-o", here + "\\com3\\fractal.vdb"],
        ["mesh", "-q", "-r", "1024", "-o", here + "\\Nul.x\\fractal.ply"],
        ["explore", "-q", "--count", "100", "-o", here + "\\lpt1"],
        ["povray", "-q", "--df3", "--df3-resolution", "512", "-o", here + "\\CON\\scene.pov"],
        ["render", "-q", "-W", "1600", "-H", "1200", "-o", here + "\\ok.png", "--save-params", here + "\\aux.json"],
    ):
        status, output = run([*emulator, exe, *arguments])
        checks["%s %s refused before the work: exit %d %s" % (arguments[0], arguments[-1], status, output.strip())] = (
            status == 2 and "reserves for a device" in output and not os.listdir(folder)
        )
    params = os.path.join(folder, "p.json")
    with open(params, "w") as file:
        file.write('{"fractal": {"iterations": 8}}\n')
    status, output = run(
        [
            *emulator,
            exe,
            "render",
            "-q",
            "-W",
            "8",
            "-H",
            "8",
            "-p",
            here + "\\p.json",
            "-o",
            here + "\\p.png",
            "--save-params",
            here + "\\P.JSON",
            "--force",
        ]
    )
    checks["--save-params onto --params (spelt P.JSON) refused: exit %d %s" % (status, output.strip())] = (
        status == 2 and "which this run reads" in output and sorted(os.listdir(folder)) == ["p.json"]
    )
    # A POV-Ray scene with its grid and include, written and then replaced all together (--force).
    scene = ["povray", "-q", "--df3", "--df3-resolution", "8", "-o", here + "\\scene.pov"]
    for attempt, extra in (("written", []), ("replaced", ["--force"])):
        status, output = run([*emulator, exe, *scene, *extra])
        names = sorted(os.listdir(folder))
        checks["povray --df3 %s: exit %d %s; files %s" % (attempt, status, output.strip(), names)] = status == 0 and (
            names == ["dqjulia.inc", "p.json", "scene.df3", "scene.pov", "scene_df3.pov"]
        )
    return checks


if __name__ == "__main__":
    sys.exit(main())
