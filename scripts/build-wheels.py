#!/usr/bin/env python3
"""Writes the Python package's wheels and its sdist from the build trees, reproducibly.

  scripts/build-wheels.py [--linux-build DIR] [--windows-build DIR] [--no-sdist] --out DIR

  --linux-build DIR    a Linux build tree (scripts/build.sh: build/) ->
                       dqjulia-VERSION-py3-none-manylinux_2_34_x86_64.whl
  --windows-build DIR  the Windows cross build tree (scripts/build-windows.sh: build-windows/) ->
                       dqjulia-VERSION-py3-none-win_amd64.whl
  (no --no-sdist)      the source tree (this script's checkout) -> dqjulia-VERSION.tar.gz
  --out DIR            where they are written (made if missing); prints each file's path

A wheel holds what `cmake --install BUILD --component python` and `--component python_native`
install (python/CMakeLists.txt: the modules of python/dqjulia/ with _buildinfo.py, the stripped
library in dqjulia/lib/ and the command in dqjulia/bin/), and a .dist-info with the metadata of
pyproject.toml's [project] table, the console script `dqjulia`, the licences (BUILD/licenses/:
LICENSE, the platform's third-party notices, THIRD-PARTY.json) and a RECORD of every file's
SHA-256 and size. Its tag is py3-none-PLATFORM: the package loads the library with ctypes, so one
wheel a platform serves every CPython from 3.9 on.

The sdist holds the files of the source tree that git knows (committed or not ignored), less
pyproject.toml's sdist.exclude, and PKG-INFO: what scikit-build-core (pyproject.toml's build
backend) needs to build the wheel from source (python/README.md, "Building from source").

Reproducible: every entry's time is SOURCE_DATE_EPOCH (default: the source tree's last commit's
time), entries are sorted, modes are 0644 or 0755, owners root, no user or host names; two runs
on the same build trees write the same bytes (scripts/pack.py writes them, aside, renamed into
place when whole).
Needs Python 3.11 (tomllib) and cmake.
"""

import argparse
import base64
import csv
import hashlib
import io
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

from build_tree import SOURCE, BuildTreeError, check_build
from pack import PackError, write_tar_gz, write_zip

# CMAKE_SYSTEM_NAME -> the wheel's platform tag and the native files its package holds.
PLATFORMS = {
    "Linux": ("manylinux_2_34_x86_64", ("lib/libdqjulia.so", "bin/dqjulia")),
    "Windows": ("win_amd64", ("lib/dqjulia.dll", "bin/dqjulia.exe")),
}
COMPONENTS = ("python", "python_native")


class BuildError(Exception):
    pass


def log(message):
    print("build-wheels: %s" % message, file=sys.stderr)


def source_date_epoch(source):
    value = os.environ.get("SOURCE_DATE_EPOCH")
    if value:
        if not value.isdigit():
            raise BuildError("SOURCE_DATE_EPOCH must be a number of seconds, not %r" % value)
        return int(value)
    result = subprocess.run(["git", "-C", str(source), "log", "-1", "--format=%ct"], capture_output=True, text=True)
    if result.returncode != 0 or not result.stdout.strip().isdigit():
        raise BuildError("set SOURCE_DATE_EPOCH: %s has no git commit to take the time from" % source)
    return int(result.stdout.strip())


def project_version(source):
    match = re.fullmatch(r"([0-9]+\.[0-9]+\.[0-9]+)\s*", (source / "VERSION").read_text(encoding="utf-8"))
    if match is None:
        raise BuildError("%s/VERSION must hold one line MAJOR.MINOR.PATCH" % source)
    return match.group(1)


def core_metadata(pyproject, version, license_files):
    """The core metadata (version 2.4) of pyproject.toml's [project] table, as METADATA and PKG-INFO hold it."""
    project = pyproject["project"]
    lines = [
        ("Metadata-Version", "2.4"),
        ("Name", project["name"]),
        ("Version", version),
        ("Summary", project["description"]),
    ]
    if project.get("keywords"):
        lines.append(("Keywords", ",".join(project["keywords"])))
    for author in project.get("authors", []):
        lines.append(("Author", author["name"]))
    lines.append(("License-Expression", project["license"]))
    lines += [("License-File", name) for name in license_files]
    lines += [("Classifier", classifier) for classifier in project.get("classifiers", [])]
    lines.append(("Requires-Python", project["requires-python"]))
    for extra, requirements in sorted(project.get("optional-dependencies", {}).items()):
        lines.append(("Provides-Extra", extra))
        lines += [("Requires-Dist", '%s; extra == "%s"' % (requirement, extra)) for requirement in requirements]
    readme = (SOURCE / project["readme"]).read_text(encoding="utf-8")
    lines.append(("Description-Content-Type", "text/markdown; charset=UTF-8"))
    text = "".join("%s: %s\n" % (key, value) for key, value in lines)
    return (text + "\n" + readme).encode("utf-8")


def stage(build, system, into):
    """Installs the package's components of a build tree for `system` into `into`; returns the
    wheel's platform tag."""
    check_build(build, system)
    for component in COMPONENTS:
        result = subprocess.run(
            ["cmake", "--install", str(build), "--component", component, "--prefix", str(into)],
            capture_output=True,
            text=True,
        )
        if result.returncode != 0:
            raise BuildError(
                "cmake --install %s --component %s failed (is the build complete?):\n%s"
                % (build, component, (result.stdout + result.stderr).strip())
            )
    platform, native = PLATFORMS[system]
    for part in native:
        if not (into / "dqjulia" / part).is_file():
            raise BuildError("%s: the install left no dqjulia/%s" % (build, part))
    return platform


def files_under(folder):
    """(name relative to folder with /, path) of every file under it, sorted by name."""
    found = []
    for root, _dirs, files in os.walk(folder):
        for name in files:
            path = Path(root) / name
            if path.is_symlink():
                raise BuildError("%s is a symbolic link, which a package cannot hold" % path)
            found.append((path.relative_to(folder).as_posix(), path))
    return sorted(found)


def mode_of(path):
    return 0o755 if path.stat().st_mode & 0o111 else 0o644


def record_hash(data):
    return "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()


def build_wheel(build, system, pyproject, version, epoch, out):
    project = pyproject["project"]
    name = project["name"]
    with tempfile.TemporaryDirectory(prefix="dqjulia-wheel-") as scratch:
        staged = Path(scratch)
        platform = stage(build, system, staged)
        buildinfo = (staged / name / "_buildinfo.py").read_text(encoding="utf-8")
        if 'PROJECT_VERSION = "%s"' % version not in buildinfo:
            raise BuildError("%s was built from another version than %s (VERSION): rebuild it" % (build, version))
        entries = [(relative, path.read_bytes(), mode_of(path)) for relative, path in files_under(staged)]

        info = "%s-%s.dist-info" % (name, version)
        # The build's licences/ (the top-level CMakeLists.txt: LICENSE, the third-party notices of
        # this platform, THIRD-PARTY.json), as every package of the release carries them.
        licenses = build / "licenses"
        license_paths = files_under(licenses)
        if "LICENSE" not in [relative for relative, _ in license_paths]:
            raise BuildError("%s has no LICENSE: is the build complete?" % licenses)
        for relative, path in license_paths:
            entries.append(("%s/licenses/%s" % (info, relative), path.read_bytes(), 0o644))
        entries.append(("%s/METADATA" % info, core_metadata(pyproject, version, [r for r, _ in license_paths]), 0o644))
        tag = "py3-none-%s" % platform
        wheel = (
            "Wheel-Version: 1.0\nGenerator: dqjulia scripts/build-wheels.py\nRoot-Is-Purelib: false\nTag: %s\n" % tag
        )
        entries.append(("%s/WHEEL" % info, wheel.encode(), 0o644))
        scripts = "".join("%s = %s\n" % item for item in sorted(project.get("scripts", {}).items()))
        entries.append(("%s/entry_points.txt" % info, ("[console_scripts]\n" + scripts).encode(), 0o644))

        record = io.StringIO()
        writer = csv.writer(record, lineterminator="\n")
        for entry_name, data, _mode in entries:
            writer.writerow([entry_name, record_hash(data), len(data)])
        writer.writerow(["%s/RECORD" % info, "", ""])
        entries.append(("%s/RECORD" % info, record.getvalue().encode(), 0o644))

        wheel_path = out / ("%s-%s-%s.whl" % (name, version, tag))
        write_zip(wheel_path, entries, epoch)
        return wheel_path


def sdist_files(source, excluded):
    """The source tree's files that git knows (committed, or new and not ignored), less `excluded`
    (pyproject.toml's sdist.exclude: folders end in /)."""
    result = subprocess.run(
        ["git", "-C", str(source), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        capture_output=True,
    )
    if result.returncode != 0:
        raise BuildError("the sdist is made from a git checkout: %s" % result.stderr.decode(errors="replace").strip())
    names = sorted({name for name in result.stdout.decode().split("\0") if name})
    kept = []
    for name in names:
        if any(name.startswith(pattern) if pattern.endswith("/") else name == pattern for pattern in excluded):
            continue
        if (source / name).is_file():  # a file git knows but that was deleted is left out
            kept.append(name)
    return kept


def build_sdist(pyproject, version, epoch, out):
    name = pyproject["project"]["name"]
    top = "%s-%s" % (name, version)
    excluded = pyproject.get("tool", {}).get("scikit-build", {}).get("sdist", {}).get("exclude", [])
    members = [(top + "/PKG-INFO", core_metadata(pyproject, version, ["LICENSE"]), 0o644)]
    for relative in sdist_files(SOURCE, excluded):
        path = SOURCE / relative
        if path.is_symlink():
            raise BuildError("%s is a symbolic link, which the sdist does not hold" % path)
        members.append(("%s/%s" % (top, relative), path.read_bytes(), mode_of(path)))
    members.sort()
    path = out / (top + ".tar.gz")
    write_tar_gz(path, members, epoch)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--linux-build", type=Path, help="a Linux build tree (build/)")
    parser.add_argument("--windows-build", type=Path, help="the Windows cross build tree (build-windows/)")
    parser.add_argument("--no-sdist", action="store_true", help="leave out the sdist")
    parser.add_argument("--out", type=Path, required=True, help="where the files are written")
    args = parser.parse_args()
    builds = [
        (build.resolve(), system)
        for build, system in ((args.linux_build, "Linux"), (args.windows_build, "Windows"))
        if build is not None
    ]
    if not builds and args.no_sdist:
        parser.error("nothing to write: give --linux-build, --windows-build, or leave out --no-sdist")
    if shutil.which("cmake") is None and builds:
        raise SystemExit("build-wheels: cmake is needed (scripts/install-deps.sh installs it)")
    try:
        with (SOURCE / "pyproject.toml").open("rb") as file:
            pyproject = tomllib.load(file)
        version = project_version(SOURCE)
        epoch = source_date_epoch(SOURCE)
        # The installs' strip too: MinGW's strip writes the time into a PE header, SOURCE_DATE_EPOCH's if set.
        os.environ["SOURCE_DATE_EPOCH"] = str(epoch)
        args.out.mkdir(parents=True, exist_ok=True)
        written = [build_wheel(build, system, pyproject, version, epoch, args.out) for build, system in builds]
        if not args.no_sdist:
            written.append(build_sdist(pyproject, version, epoch, args.out))
    except (BuildError, BuildTreeError, PackError, OSError) as error:
        raise SystemExit("build-wheels: %s" % error) from None
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
