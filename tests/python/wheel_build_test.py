"""scripts/build-wheels.py on this build: the Linux wheel and the sdist, written twice with the same
bytes; the wheel read as an installer reads it (wheel_support.check_wheel); the sdist holding
what a build from source needs and nothing of the tests; bad build trees refused. Leaves the
files in WORK/dist for the install tests (wheel_install_test.py, wheel_tools_test.py).

Usage: python3 wheel_build_test.py SOURCE BUILD WORK
"""

import os
import re
import shutil
import subprocess
import sys
import tarfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)
from wheel_support import check_wheel  # noqa: E402

PLATFORM = "manylinux_2_34_x86_64"
SDIST_NEEDS = (
    "pyproject.toml",
    "PKG-INFO",
    "LICENSE",
    "VERSION",
    "CMakeLists.txt",
    "cmake/StaticDeps.cmake",
    "core/CMakeLists.txt",
    "core/include/dqjulia/dqjulia.h",
    "python/CMakeLists.txt",
    "python/README.md",
    "python/buildinfo.py.in",
    "python/dqjulia/_native.py",
    "python/dqjulia/py.typed",
    "povray/dqjulia.inc",
    "scripts/build-deps.sh",
)


def build_wheels(source, arguments):
    result = subprocess.run(
        [sys.executable, os.path.join(source, "scripts", "build-wheels.py"), *arguments], capture_output=True, text=True
    )
    return result.returncode, result.stdout, result.stderr


def main():
    source, build, work = (os.path.abspath(path) for path in sys.argv[1:4])
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    with open(os.path.join(source, "VERSION")) as file:
        version = file.read().strip()
    epoch = int(
        subprocess.run(["git", "-C", source, "log", "-1", "--format=%ct"], capture_output=True, text=True).stdout
    )
    checks = {}

    runs = []
    for name in ("a", "b"):
        status, stdout, stderr = build_wheels(source, ["--linux-build", build, "--out", os.path.join(work, name)])
        runs.append(sorted(os.path.basename(line) for line in stdout.split()))
        checks["build-wheels.py run %s exits 0 %s" % (name, stderr.strip()[-300:])] = status == 0
    expected = ["dqjulia-%s-py3-none-%s.whl" % (version, PLATFORM), "dqjulia-%s.tar.gz" % version]
    checks["it prints the paths of the wheel and the sdist: %s" % runs[0]] = runs[0] == sorted(expected)
    for name in expected:
        first, second = os.path.join(work, "a", name), os.path.join(work, "b", name)
        same = os.path.isfile(first) and os.path.isfile(second)
        if same:
            with open(first, "rb") as one, open(second, "rb") as other:
                same = one.read() == other.read()
        checks["two runs write the same bytes: %s" % name] = same
    checks["nothing else is written (no temporary file)"] = sorted(os.listdir(os.path.join(work, "a"))) == sorted(
        expected
    )

    wheel = os.path.join(work, "a", expected[0])
    if os.path.isfile(wheel):
        checks.update(check_wheel(wheel, source, version, PLATFORM, epoch))

    sdist = os.path.join(work, "a", expected[1])
    if os.path.isfile(sdist):
        with tarfile.open(sdist) as archive:
            members = archive.getmembers()
            top = "dqjulia-%s/" % version
            names = [member.name for member in members]
            inside = {name[len(top) :] for name in names if name.startswith(top)}
            checks["the sdist's files are all under %s" % top] = len(inside) == len(names)
            missing = [name for name in SDIST_NEEDS if name not in inside]
            checks["the sdist holds what a build from source needs (missing: %s)" % missing] = not missing
            checks["the sdist holds no tests, benchmarks or pictures"] = not any(
                name.startswith(("tests/", "bench/", "docs/")) for name in inside
            )
            checks["sdist entries sorted, time SOURCE_DATE_EPOCH, owner root"] = names == sorted(names) and all(
                member.mtime == epoch and member.uid == 0 and member.gid == 0 and member.uname == "root"
                for member in members
            )
            pkg_info = archive.extractfile(top + "PKG-INFO").read().decode()
            with open(os.path.join(source, "pyproject.toml"), "rb") as file:
                pyproject = file.read()
            checks["the sdist's pyproject.toml is the source's"] = (
                archive.extractfile(top + "pyproject.toml").read() == pyproject
            )
        checks["PKG-INFO: Name dqjulia, Version %s" % version] = (
            re.search(r"^Name: dqjulia$", pkg_info, re.M) is not None
            and re.search(r"^Version: %s$" % re.escape(version), pkg_info, re.M) is not None
        )

    # Bad input: the Linux tree as the Windows build, a folder that is no build tree.
    status, _, stderr = build_wheels(source, ["--windows-build", build, "--no-sdist", "--out", os.path.join(work, "c")])
    checks["a Linux tree given as --windows-build is refused: %s" % stderr.strip()] = (
        status != 0 and "not for Windows" in stderr
    )
    status, _, stderr = build_wheels(source, ["--linux-build", work, "--no-sdist", "--out", os.path.join(work, "c")])
    checks["a folder that is no build tree is refused: %s" % stderr.strip()] = status != 0 and "CMakeCache" in stderr
    refused = os.path.join(work, "c")
    checks["a refused run leaves no file"] = not os.path.isdir(refused) or not os.listdir(refused)

    shutil.copytree(os.path.join(work, "a"), os.path.join(work, "dist"))
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
