"""The add-on's Windows zip against the Linux one (one zip a platform, as Blender's
`extension build --split-platforms` makes them): the Windows zip holds dqjulia/lib/dqjulia.dll
and its manifest says platforms = ["windows-x64"], the Linux zip lib/libdqjulia.so and
["linux-x64"]; both hold LICENSE and their platform's THIRD-PARTY-NOTICES.txt; every other file
is the same (schema.json, written by dqjulia.exe under Wine, the same document). And native.py
from the Windows zip, told it runs on Windows (sys.platform "win32"; no Windows Python runs here),
finds lib/dqjulia.dll beside itself, adds that folder to the DLL
search path (os.add_dll_directory) before loading it, and binds every function through ctypes
(a stand-in for the DLL answers).

Usage: python3 addon_zip_test.py WINDOWS_ZIP LINUX_ZIP WORK
"""

import json
import os
import re
import shutil
import sys
import types
import zipfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report, skip_or_fail  # noqa: E402 (tests/common/check_report.py)
from package_module import load_package_module  # noqa: E402 (tests/common/package_module.py)


def platforms(archive):
    manifest = archive.read("dqjulia/blender_manifest.toml").decode()
    return re.search(r"^platforms = (.*)$", manifest, re.M).group(1)


class FakeFunction:
    def __init__(self, result):
        self.result = result

    def __call__(self, *arguments):
        return self.result


class FakeDll:
    """Answers as dqjulia.dll would: its version, every feature, and any function."""

    def __init__(self, path, version):
        self.path = path
        self.dqj_version_number = FakeFunction(version)
        self.dqj_has_feature = FakeFunction(1)

    def __getattr__(self, name):
        if not name.startswith("dqj_"):
            raise AttributeError(name)
        return FakeFunction(0)


def load_on_windows(native_path):
    """native.py's _load() as on Windows: which folder it adds and which file it loads."""
    # In a stand-in package named after nothing else loaded, so that it finds the _buildinfo.py
    # beside it as Blender's and pip's imports do.
    native = load_package_module(native_path, "dqjulia_windows_%d" % len(sys.modules))
    added, loaded = [], []
    native.sys = types.SimpleNamespace(platform="win32")
    native.os = types.SimpleNamespace(path=os.path, environ={}, add_dll_directory=added.append)

    def cdll(path):
        loaded.append(path)
        return FakeDll(path, native.EXPECTED_VERSION)

    names = {name: getattr(native.ctypes, name) for name in dir(native.ctypes) if not name.startswith("__")}
    native.ctypes = types.SimpleNamespace(**dict(names, CDLL=cdll))
    library, (features, bound) = native._load()
    return native, added, loaded, features, bound


def main():
    windows_zip, linux_zip, work = sys.argv[1:]
    if not os.path.isfile(linux_zip):
        skip_or_fail("%s is missing: build the Linux tree first (scripts/build.sh)" % linux_zip)
    checks = {}
    with zipfile.ZipFile(windows_zip) as windows, zipfile.ZipFile(linux_zip) as linux:
        windows_names, linux_names = set(windows.namelist()), set(linux.namelist())
        checks["the Windows zip holds dqjulia/lib/dqjulia.dll and no .so"] = "dqjulia/lib/dqjulia.dll" in (
            windows_names
        ) and not any(name.endswith(".so") for name in windows_names)
        checks["the Linux zip holds dqjulia/lib/libdqjulia.so and no .dll"] = "dqjulia/lib/libdqjulia.so" in (
            linux_names
        ) and not any(name.endswith(".dll") for name in linux_names)
        checks["Windows manifest: platforms = %s" % platforms(windows)] = platforms(windows) == '["windows-x64"]'
        checks["Linux manifest: platforms = %s" % platforms(linux)] = platforms(linux) == '["linux-x64"]'
        # The third-party notices are each platform's (Windows adds MinGW-w64's runtime).
        notices = "dqjulia/THIRD-PARTY-NOTICES.txt"
        checks["both zips hold LICENSE and %s" % notices] = all(
            {"dqjulia/LICENSE", notices} <= names for names in (windows_names, linux_names)
        )
        shared = (windows_names & linux_names) - {"dqjulia/blender_manifest.toml", "dqjulia/schema.json", notices}
        others = (windows_names ^ linux_names) - {"dqjulia/lib/dqjulia.dll", "dqjulia/lib/libdqjulia.so"}
        checks["the same files but the library: %s" % sorted(others)] = not others
        differing = sorted(name for name in shared if windows.read(name) != linux.read(name))
        checks["%d files the same in both: %s differ" % (len(shared), differing)] = not differing
        schema = [json.loads(archive.read("dqjulia/schema.json")) for archive in (windows, linux)]
        checks["schema.json the same document (%d fields)" % len(schema[1].get("fields", []))] = schema[0] == schema[1]
        manifests = [archive.read("dqjulia/blender_manifest.toml").decode() for archive in (windows, linux)]
        same = manifests[0].replace('"windows-x64"', '"linux-x64"') == manifests[1]
        checks["the manifests differ only in platforms"] = same
        shutil.rmtree(work, ignore_errors=True)
        windows.extractall(work)

    native, added, loaded, features, bound = load_on_windows(os.path.join(work, "dqjulia", "native.py"))
    library = os.path.join(work, "dqjulia", "lib", "dqjulia.dll")
    checks["native.py on Windows loads %s" % loaded] = loaded == [library]
    checks["native.py on Windows adds the DLL's folder first: %s" % added] = added == [os.path.dirname(library)]
    checks["native.py on Windows binds every function (%d)" % len(bound)] = bound == frozenset(native._SIGNATURES)

    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
