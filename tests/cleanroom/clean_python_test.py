"""The Python of a clean Debian 12 is enough for the project's scripts: in a minimal root with
only the Python packages scripts/install-deps.sh installs (python3* of `install-deps.sh --list`;
no pyenv, whose Python has every module Debian splits off), Debian's python3 makes a venv with
pip in it (`python3 -m venv`, as scripts/bpy-env.sh and scripts/tool-env.sh do), is the CPython
the bpy wheels need (3.11), and imports every module those packages install (the tests'
numpy and pyopenvdb). A cheap stand-in for scripts/check-clean-machine.sh, which runs both
README commands in a clean root: a machine without pyenv lacked python3-venv once.

Usage: python3 clean_python_test.py SOURCE   (as root: debootstrap and chroot)
"""

import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)
from debian_roots import debian_root, require_root_tools, run_in, scratch  # noqa: E402

# Run inside the root: the top-level modules the given Debian packages install, each imported.
IMPORTS = r"""
import importlib, os, subprocess, sys
names = set()
for package in sys.argv[1:]:
    files = subprocess.run(["dpkg", "-L", package], capture_output=True, text=True, check=True).stdout.split()
    for path in files:
        folder, name = os.path.split(path)
        if folder != "/usr/lib/python3/dist-packages" or name.endswith((".egg-info", ".dist-info", ".pth")):
            continue
        if os.path.isdir(path) and not os.path.isfile(os.path.join(path, "__init__.py")):
            continue
        names.add(name.split(".")[0])
failed = []
for name in sorted(names):
    try:
        importlib.import_module(name)
    except Exception as error:
        failed.append("%s (%s)" % (name, error))
print("imported: %s" % " ".join(sorted(names)))
if failed:
    sys.exit("cannot import: %s" % "; ".join(failed))
"""


def main():
    source = os.path.abspath(sys.argv[1])
    require_root_tools()
    listed = subprocess.run(
        [os.path.join(source, "scripts", "install-deps.sh"), "--list"], capture_output=True, text=True, check=True
    ).stdout.split()
    packages = [name for name in listed if name == "python3" or name.startswith("python3-")]
    print("install-deps.sh's Python packages: %s" % " ".join(packages))
    root = debian_root("bookworm", packages)
    checks = {"install-deps.sh installs python3 itself": "python3" in packages}

    status, stdout, stderr = run_in(root, ["sh", "-c", "command -v pyenv; ls /root/.pyenv"])
    checks["the root has no pyenv"] = not stdout.strip()
    status, stdout, stderr = run_in(root, ["python3", "-c", "import sys; print(sys.executable, sys.version)"])
    found = (stdout + stderr).strip()
    checks["python3 is Debian's CPython 3.11, which the bpy wheels need (%s)" % found] = (
        status == 0 and found.startswith("/usr/bin/python3 3.11.")
    )

    with scratch(root) as (here, inside):
        status, stdout, stderr = run_in(
            root, ["sh", "-c", "python3 -m venv %s/venv && %s/venv/bin/python -m pip --version" % (inside, inside)]
        )
        output = (stdout + stderr).strip()
        checks["python3 -m venv makes a venv with pip: %s" % output] = status == 0 and output.startswith("pip ")
        with open(os.path.join(here, "imports.py"), "w") as file:
            file.write(IMPORTS)
        others = [name for name in packages if name not in ("python3", "python3-venv")]
        status, stdout, stderr = run_in(root, ["python3", inside + "/imports.py", *others])
        output = (stdout + stderr).strip()
        checks["the modules of %s import: %s" % (", ".join(others), output)] = status == 0 and "imported: " in output
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
