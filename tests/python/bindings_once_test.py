"""One set of Python bindings: the add-on zip's dqjulia/native.py is the Python package's
python/dqjulia/_native.py, byte for byte (blender_addon/package.cmake copies it), and no other
Python file of the add-on or the package binds the C ABI's functions itself.

Usage: python3 bindings_once_test.py SOURCE ADDON_ZIP
"""

import glob
import os
import re
import sys
import zipfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)


def main():
    source, addon_zip = sys.argv[1:3]
    bindings = os.path.join(source, "python", "dqjulia", "_native.py")
    with open(bindings, "rb") as file:
        original = file.read()
    with zipfile.ZipFile(addon_zip) as archive:
        copy = archive.read("dqjulia/native.py") if "dqjulia/native.py" in archive.namelist() else None
    checks = {
        "the add-on zip's dqjulia/native.py is python/dqjulia/_native.py": copy == original,
        "the add-on's source has no native.py of its own": not os.path.exists(
            os.path.join(source, "blender_addon", "dqjulia", "native.py")
        ),
    }
    # A binding loads the library or declares a C function's types.
    others = []
    for path in sorted(glob.glob(os.path.join(source, "blender_addon", "**", "*.py"), recursive=True)) + sorted(
        glob.glob(os.path.join(source, "python", "**", "*.py"), recursive=True)
    ):
        if os.path.samefile(path, bindings):
            continue
        with open(path, encoding="utf-8") as file:
            if re.search(r"\.(argtypes|restype)\s*=|\b(CDLL|cdll|WinDLL|CFUNCTYPE|LoadLibrary)\b", file.read()):
                others.append(os.path.relpath(path, source))
    checks["no other file binds the C ABI (%s)" % others] = not others
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
