"""The Linux wheel as a user installs it: `pip install` into a fresh venv of one CPython, then the
`dqjulia` command and the Python API against this build's command, which must give the same
results: eval values, PNG bytes, VDB grids and active voxel counts, mesh bytes.

  - without NumPy: the package imports, the command runs (exec: its exit status, Ctrl-C's 130,
    no file left), the array functions say NumPy is needed;
  - on a glibc below the floor (os.confstr made to say 2.31): `import dqjulia` and the command
    fail with a message naming glibc 2.34, before any native code is loaded;
  - with NumPy (a pinned release from a wheel cache outside the checkout, downloaded once):
    api_run.py's render, evaluation, bake and mesh, parameters from a dict, JSON and a file,
    errors, progress, cancel, the empty slice's warning, and Ctrl-C during a render.

Usage: python3 wheel_install_test.py PYTHON DIST CLI COMPARE_OUTPUTS EXAMPLES WORK
PYTHON is 3.9 ... 3.13 (pyenv's, or python3.X on PATH; a machine without it skips the test,
saying so) or debian (Debian's /usr/bin/python3, always there).
"""

import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)
from wheel_support import find_python, read_ply, read_png  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
# The NumPy of each CPython's venv: the newest release that supports it, pinned, from a wheel cache.
NUMPY = {"3.9": "2.0.2"}
NUMPY_DEFAULT = "2.2.6"
WHEEL_CACHE = os.path.join(
    os.environ.get("DQJ_WHEEL_CACHE")
    or os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "dqjulia", "wheels")
)


def run(command, **options):
    result = subprocess.run(command, capture_output=True, text=True, **options)
    return result.returncode, result.stdout, result.stderr


def interrupt_after(command, seconds, ready=None, **options):
    """Runs a command and sends it SIGINT (with SIGINT's default action, as a terminal gives it)
    `seconds` after it started, or after it printed the line `ready`; its exit status and output."""
    default_sigint = (
        "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); os.execv(sys.argv[1], sys.argv[1:])"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", default_sigint, *command],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **options,
    )
    first = process.stdout.readline() if ready is not None else wait_for_sigint_handler(process.pid, command[0])
    time.sleep(seconds)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=300)
    return process.returncode, first + stdout, stderr


def wait_for_sigint_handler(pid, command):
    """Waits until the process runs the native program named like `command` (after any exec of
    Python scripts on the way) and that program has installed its SIGINT handler, so a loaded
    machine's slow start cannot turn the test's Ctrl-C into SIGINT's default action; returns ""."""
    name = os.path.basename(command)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        try:
            exe = os.path.basename(os.readlink("/proc/%d/exe" % pid))
            with open("/proc/%d/status" % pid) as status:
                caught = next(int(line.split()[1], 16) for line in status if line.startswith("SigCgt:"))
        except (OSError, StopIteration):
            return ""  # gone already: the caller sees its exit status
        if exe == name and caught & (1 << (signal.SIGINT - 1)):
            return ""
        time.sleep(0.02)
    return ""


def files_equal(first, second):
    if not (os.path.isfile(first) and os.path.isfile(second)):
        return False
    with open(first, "rb") as one, open(second, "rb") as other:
        return one.read() == other.read()


def install_numpy(python, venv_python, checks):
    """NumPy into the venv from the wheel cache, downloaded into it the first time."""
    minor = ".".join(map(str, sys_version(python)[:2]))
    version = NUMPY.get(minor, NUMPY_DEFAULT)
    cache = os.path.join(WHEEL_CACHE, "numpy-%s" % version)
    pip = [venv_python, "-m", "pip", "--disable-pip-version-check", "--no-input", "-q"]
    status, stdout, stderr = run(pip + ["install", "--no-index", "--find-links", cache, "numpy==" + version])
    if status != 0:
        os.makedirs(cache, exist_ok=True)
        status, stdout, stderr = run(pip + ["download", "--only-binary", ":all:", "-d", cache, "numpy==" + version])
        if status == 0:
            status, stdout, stderr = run(pip + ["install", "--no-index", "--find-links", cache, "numpy==" + version])
    checks["NumPy %s installs (wheel cache %s) %s" % (version, cache, stderr.strip()[-300:])] = status == 0
    return status == 0


def sys_version(python):
    status, stdout, _ = run([python, "-c", "import sys; print(*sys.version_info[:3])"])
    return tuple(int(part) for part in stdout.split()) if status == 0 else (0, 0, 0)


def main():
    version, dist, cli, compare, examples, work = sys.argv[1:7]
    python = find_python(version)
    if python is None:
        # The rule: the CPythons of 3.9 - 3.13 that this machine has; Debian's is always tested.
        print("DQJ_TEST_SKIPPED: no CPython %s on this machine (pyenv versions, python%s on PATH)" % (version, version))
        return 0
    found = sys_version(python)
    print("CPython %s: %s" % (".".join(map(str, found)), python))
    wheels = (
        [name for name in os.listdir(dist) if name.endswith("manylinux_2_34_x86_64.whl")] if os.path.isdir(dist) else []
    )
    checks = {"the Linux wheel was built (release.wheel_build): %s" % wheels: len(wheels) == 1}
    if not wheels:
        return report(checks)
    checks["CPython %s is a %s" % (".".join(map(str, found)), version)] = version == "debian" or (
        ".".join(map(str, found[:2])) == version
    )
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    started = time.monotonic()

    venv = os.path.join(work, "venv")
    status, stdout, stderr = run([python, "-m", "venv", venv])
    checks["python -m venv %s" % stderr.strip()[-200:]] = status == 0
    venv_python = os.path.join(venv, "bin", "python")
    command = os.path.join(venv, "bin", "dqjulia")
    status, stdout, stderr = run(
        [
            venv_python,
            "-m",
            "pip",
            "--disable-pip-version-check",
            "--no-input",
            "-q",
            "install",
            "--no-index",
            os.path.join(dist, wheels[0]),
        ]
    )
    checks["pip install the wheel %s" % stderr.strip()[-300:]] = status == 0
    if status != 0:
        return report(checks)

    # The command, without NumPy: exec'ed, so its own exit status and signals.
    reference_version = run([cli, "--version"])[1]
    status, stdout, _ = run([command, "--version"])
    checks["`dqjulia --version` from the venv: %s" % stdout.strip()] = status == 0 and stdout == reference_version
    status, _, stderr = run([command, "render", "--no-such-flag"])
    checks["bad input: exit status 2, as the build's command (%s)" % stderr.strip()[:60]] = status == 2
    status, stdout, stderr = run([venv_python, "-m", "dqjulia", "--version"])
    checks["python -m dqjulia is the command"] = status == 0 and stdout == reference_version
    status, stdout, stderr = run(
        [venv_python, "-c", "import dqjulia, os; p = dqjulia.command_path(); print(p, os.access(p, os.X_OK))"]
    )
    checks["command_path() is the bundled, executable command: %s" % stdout.strip()] = (
        status == 0 and stdout.strip().endswith("site-packages/dqjulia/bin/dqjulia True")
    )
    big = os.path.join(work, "interrupted.png")
    status, stdout, stderr = interrupt_after([command, "render", "-W", "2400", "-H", "1800", "-s", "4", "-o", big], 2.0)
    checks["Ctrl-C stops the command: exit status 130, no file (%d)" % status] = status == 130 and not os.path.exists(
        big
    )
    status, stdout, stderr = run(
        [
            venv_python,
            "-c",
            "import dqjulia, sys; f = dqjulia.Fractal(); f.render_to_file(sys.argv[1]); print('numpy' in sys.modules)",
            os.path.join(work, "without-numpy.png"),
        ]
    )
    checks["without NumPy: the package imports and renders a file, NumPy never imported"] = (
        status == 0 and stdout.strip() == "False"
    )
    status, stdout, stderr = run([venv_python, "-c", "import dqjulia; dqjulia.Fractal().evaluate([[0] * 8])"])
    last = stderr.strip().splitlines()[-1:]
    checks["without NumPy: evaluate() says to install NumPy: %s" % last] = (
        status != 0 and bool(last) and last[0].startswith("ImportError: ") and "install NumPy" in last[0]
    )

    # Below the glibc floor (os.confstr told to say 2.31): plain words, no loader error.
    old_glibc = "import os, sys; os.confstr = lambda name: 'glibc 2.31'; "
    status, stdout, stderr = run([venv_python, "-c", old_glibc + "import dqjulia"])
    checks["glibc 2.31: import dqjulia raises ImportError naming glibc 2.34: %s" % stderr.strip().splitlines()[-1:]] = (
        status != 0 and "ImportError" in stderr and "glibc 2.34 or newer" in stderr and "glibc 2.31" in stderr
    )
    status, stdout, stderr = run(
        [
            venv_python,
            "-c",
            old_glibc + "sys.argv = [%r]; import runpy; runpy.run_path(%r, run_name='__main__')" % (command, command),
        ]
    )
    checks["glibc 2.31: the command says so in one line, exit status 1: %s" % stderr.strip()] = (
        status == 1 and stderr.startswith("dqjulia: ") and "glibc 2.34" in stderr and "Traceback" not in stderr
    )

    if not install_numpy(python, venv_python, checks):
        return report(checks)

    # The same parameters for both: an example, small.
    with open(os.path.join(examples, "paper-test2-2.json"), encoding="utf-8") as file:
        document = json.load(file)
    document.setdefault("render", {}).update({"width": 160, "height": 120})
    document.setdefault("bake", {}).update({"resolution": 48})
    document.pop("output", None)
    params = os.path.join(work, "params.json")
    with open(params, "w", encoding="utf-8") as file:
        json.dump(document, file)
    generator = random.Random(36)
    points8 = [[generator.uniform(-1.2, 1.2) for _ in range(8)] for _ in range(300)]
    points3 = [[generator.uniform(-1.5, 1.5) for _ in range(3)] for _ in range(300)]
    paths = {}
    for name, points in (("points8", points8), ("points3", points3)):
        paths[name] = os.path.join(work, name + ".txt")
        with open(paths[name], "w") as file:
            file.write("".join(" ".join(repr(x) for x in point) + "\n" for point in points))

    reference, from_venv = os.path.join(work, "build"), os.path.join(work, "venv-command")
    os.makedirs(reference)
    os.makedirs(from_venv)
    outputs = {}
    for folder, program in ((reference, cli), (from_venv, command)):
        made = outputs[folder] = {}
        for kind, arguments in (
            ("png", ["render", "-q", "-p", params, "-o", os.path.join(folder, "out.png")]),
            ("vdb", ["bake", "-p", params, "-o", os.path.join(folder, "out.vdb")]),
            ("ply", ["mesh", "-q", "-p", params, "-o", os.path.join(folder, "out.ply")]),
            ("stl", ["mesh", "-q", "-p", params, "-o", os.path.join(folder, "out.stl")]),
            ("3mf", ["mesh", "-q", "-p", params, "-o", os.path.join(folder, "out.3mf")]),
        ):
            status, stdout, stderr = run([program, *arguments])
            made[kind] = stdout + stderr
            checks["%s %s exits 0 %s" % (os.path.basename(folder), kind, stderr.strip()[:200])] = status == 0
        for name, extra in (("points8", []), ("points3", ["--slice-coords"])):
            with open(paths[name]) as points:
                status, stdout, _ = run([program, "eval", "-p", params, *extra], stdin=points)
            made[name] = stdout
    checks["the venv's command: the same PNG bytes"] = files_equal(
        os.path.join(reference, "out.png"), os.path.join(from_venv, "out.png")
    )
    checks["the venv's command: the same PLY bytes"] = files_equal(
        os.path.join(reference, "out.ply"), os.path.join(from_venv, "out.ply")
    )
    for name in ("points8", "points3"):
        checks["the venv's command: the same eval CSV (%s)" % name] = (
            outputs[reference][name] == outputs[from_venv][name] and outputs[reference][name].count("\n") == 301
        )
    status, stdout, _ = run([compare, "vdb", os.path.join(reference, "out.vdb"), os.path.join(from_venv, "out.vdb")])
    checks["the venv's command: the same VDB grids (compare_outputs)"] = status == 0
    active = re.search(r"(\d+) active voxels", outputs[reference]["vdb"])
    checks["the venv's command: the same active voxel count (%s)" % (active and active.group(1))] = (
        active is not None and active.group(0) in outputs[from_venv]["vdb"]
    )

    # The API.
    api = os.path.join(work, "api")
    os.makedirs(api)
    empty = os.path.join(examples, "paper-test2-1.json")
    status, stdout, stderr = run(
        [venv_python, os.path.join(HERE, "api_run.py"), params, empty, paths["points8"], paths["points3"], api]
    )
    checks["api_run.py exits 0 %s" % stderr.strip()[-800:]] = status == 0
    if status != 0:
        return report(checks)
    with open(os.path.join(api, "api.json"), encoding="utf-8") as file:
        result = json.load(file)
    checks.update({"API: %s" % name: ok for name, ok in result["checks"].items()})
    checks["API: version %s, the library's %s" % tuple(result["version"])] = (
        result["version"][0] == result["version"][1]
    )
    checks["API: render_to_file writes the command's PNG bytes"] = files_equal(
        os.path.join(api, "api.png"), os.path.join(reference, "out.png")
    )
    width, height, channels, pixels = read_png(os.path.join(reference, "out.png"))
    with open(os.path.join(api, "api_render.rgba"), "rb") as file:
        rgba = file.read()
    same = channels == 3 and result["render_shape"] == [height, width, 4] and len(rgba) == width * height * 4
    same = same and all(
        rgba[4 * index : 4 * index + 3] == pixels[3 * index : 3 * index + 3] for index in range(width * height)
    )
    checks["API: render()'s RGB is the command's PNG's pixels (%d x %d)" % (width, height)] = same
    coverage = set(rgba[3::4])
    checks["API: render()'s alpha is the surface's coverage: 0 on the background, 255 on the surface"] = {
        0,
        255,
    } <= coverage
    for name, key in (("points8", "evaluate"), ("points3", "evaluate_slice")):
        rows = [line.split(",") for line in outputs[reference][name].strip().splitlines()[1:]]
        values = result[key]
        equal = len(rows) == len(values) == 300 and all(
            int(row[0]) == value[0] and all(float(text) == float(number) for text, number in zip(row[1:], value[1:]))
            for row, value in zip(rows, values)
        )
        checks["API: %s() equals `dqjulia eval` exactly (%s, 300 points)" % (key, name)] = equal
    status, stdout, _ = run([compare, "vdb", os.path.join(reference, "out.vdb"), os.path.join(api, "api.vdb")])
    checks["API: bake() writes the command's VDB grids (compare_outputs)"] = status == 0
    checks["API: bake()'s active voxels are the command's (%s)" % result["bake_stats"]["active_voxels"]] = (
        active is not None and int(active.group(1)) == result["bake_stats"]["active_voxels"]
    )
    for extension in ("ply", "stl", "3mf"):  # the format by the path's extension
        checks["API: mesh_to_file writes the command's %s bytes" % extension.upper()] = files_equal(
            os.path.join(api, "api." + extension), os.path.join(reference, "out." + extension)
        )
    floats, colors, faces = read_ply(os.path.join(reference, "out.ply"))
    arrays = {}
    for name in ("vertices", "normals", "quads", "triangles"):
        with open(os.path.join(api, "api_mesh_%s.bin" % name), "rb") as file:
            arrays[name] = file.read()
    shapes = result["mesh_shapes"]
    vertex_count = len(colors)
    interleaved = b"".join(
        arrays["vertices"][12 * index : 12 * index + 12] + arrays["normals"][12 * index : 12 * index + 12]
        for index in range(vertex_count)
    )
    checks["API: mesh() vertices and normals are the PLY's (%d vertices)" % vertex_count] = (
        shapes["vertices"] == [[vertex_count, 3], "float32"] and interleaved == floats
    )
    import struct

    quads = [list(struct.unpack_from("<4I", arrays["quads"], 16 * i)) for i in range(shapes["quads"][0][0])]
    triangles = [list(struct.unpack_from("<3I", arrays["triangles"], 12 * i)) for i in range(shapes["triangles"][0][0])]
    checks["API: mesh() faces are the PLY's (%d quads, %d triangles)" % (len(quads), len(triangles))] = (
        sorted(quads + triangles) == sorted(faces) and shapes["quads"][1] == "uint32"
    )

    # Ctrl-C during the API's render: KeyboardInterrupt once the call returns, no file.
    interrupted = os.path.join(work, "api-interrupted.png")
    script = (
        "import dqjulia, os, sys\n"
        "f = dqjulia.Fractal({'render': {'width': 2400, 'height': 1800, 'samples': 4}})\n"
        "print('ready', flush=True)\n"
        "try:\n    f.render_to_file(sys.argv[1])\n"
        "except KeyboardInterrupt:\n    print('KeyboardInterrupt', os.path.exists(sys.argv[1]))\n    sys.exit(130)\n"
    )
    status, stdout, stderr = interrupt_after([venv_python, "-c", script, interrupted], 1.0, ready="ready")
    checks["API: Ctrl-C cancels a render, raises KeyboardInterrupt, no file (%d %s)" % (status, stdout.split())] = (
        status == 130 and stdout.split() == ["ready", "KeyboardInterrupt", "False"] and "ctypes callback" not in stderr
    )

    print("CPython %s with NumPy %s: %.1f s" % (".".join(map(str, found)), result["numpy"], time.monotonic() - started))
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
