"""One version: the project's VERSION file, and every place that carries it.

Usage: python3 tests/version/version_test.py SOURCE_DIR ZIP CLI LIBRARY
Checks the zip's manifest, bl_info and build info, the POV-Ray include, the add-on's source
literals (scripts/set-version.sh keeps them), `dqjulia --version`, the library's
dqj_version_string()/dqj_version_number(), and that CHANGELOG.md has a section for it.
"""

import ast
import ctypes
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
import zipfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)


def main():
    source, zip_path, cli, library = sys.argv[1:5]
    with open(source + "/VERSION") as handle:
        version = handle.read().strip()
    major, minor, patch = (int(part) for part in version.split("."))
    checks = {}

    with zipfile.ZipFile(zip_path) as archive:
        manifest = tomllib.loads(archive.read("dqjulia/blender_manifest.toml").decode())
        checks["zip manifest version %s" % manifest["version"]] = manifest["version"] == version
        init = ast.parse(archive.read("dqjulia/__init__.py").decode())
        buildinfo = archive.read("dqjulia/_buildinfo.py").decode()
    bl_info = next(
        ast.literal_eval(node.value)
        for node in init.body
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "bl_info"
    )
    checks["zip bl_info version %s" % (bl_info["version"],)] = bl_info["version"] == (major, minor, patch)
    checks["zip build info"] = (
        'PROJECT_VERSION = "%s"' % version in buildinfo
        and "DQJ_VERSION_NUMBER = %d" % (major * 10000 + minor * 100 + patch) in buildinfo
    )

    with open(source + "/blender_addon/dqjulia/blender_manifest.toml", "rb") as handle:
        checks["source manifest literal"] = tomllib.load(handle)["version"] == version
    with open(source + "/blender_addon/dqjulia/__init__.py") as handle:
        checks["source bl_info literal"] = '"version": (%d, %d, %d)' % (major, minor, patch) in handle.read()
    with open(source + "/povray/dqjulia.inc") as handle:
        match = re.search(r'#declare DQJ_Include_Version = "([0-9.]+)";', handle.read())
    checks["POV-Ray include %s" % (match.group(1) if match else None)] = bool(match) and match.group(1) == version

    output = subprocess.run([cli, "--version"], capture_output=True, text=True, check=True).stdout
    checks["dqjulia --version: %s" % output.strip()] = re.search(r"\b%s\b" % re.escape(version), output) is not None

    lib = ctypes.CDLL(library)
    lib.dqj_version_string.restype = ctypes.c_char_p
    lib.dqj_version_number.restype = ctypes.c_uint
    text, number = lib.dqj_version_string().decode(), lib.dqj_version_number()
    checks["library %s (%d)" % (text, number)] = text == version and number == major * 10000 + minor * 100 + patch

    # The bindings without their build info: in the source tree they expect the VERSION file's
    # library; a copy elsewhere cannot tell and refuses to load any library.
    probe = (
        "import sys; sys.path.insert(0, sys.argv[1]); from dqjulia import _native as n; "
        "print(n.EXPECTED_VERSION); print(n.load_error() or 'loaded')"
    )
    environment = dict(os.environ, DQJULIA_LIBRARY=library)
    lines = subprocess.run(
        [sys.executable, "-c", probe, source + "/python"], capture_output=True, text=True, check=True, env=environment
    ).stdout.splitlines()
    checks["source tree's _native.py expects %s and loads the library" % lines[0]] = lines == [
        str(major * 10000 + minor * 100 + patch),
        "loaded",
    ]
    with tempfile.TemporaryDirectory() as scratch:
        shutil.copytree(source + "/python/dqjulia", scratch + "/dqjulia")
        lines = subprocess.run(
            [sys.executable, "-c", probe, scratch], capture_output=True, text=True, check=True, env=environment
        ).stdout.splitlines()
    checks["a copy without _buildinfo.py refuses: %s" % lines[1:]] = (
        lines[0] == "None" and len(lines) == 2 and "no _buildinfo.py" in lines[1]
    )

    with open(source + "/CHANGELOG.md") as handle:
        changelog = handle.read()
    checks["CHANGELOG.md has a section for %s or Unreleased" % version] = (
        re.search(r"^## (%s|Unreleased)\b" % re.escape(version), changelog, re.M) is not None
    )

    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
