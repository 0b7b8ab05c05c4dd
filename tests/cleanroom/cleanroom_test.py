"""The add-on's library on a Linux that has none of the project's build dependencies.

Makes (once, cached outside the checkout) a minimal Debian root with debootstrap
--variant=minbase plus python3, unpacks the add-on zip into it, and in it (chroot) loads the
library through the add-on's own native.py and bakes a VDB and a mesh
(bake_with_native.py). The same script then runs on the build machine; the two must make
the same files (sizes, active voxels, mesh counts).

Usage: python3 cleanroom_test.py ZIP WORK   (as root: debootstrap and chroot need it)
The root lives in $DQJ_CLEANROOM_CACHE (default ~/.cache/dqjulia/cleanroom); it is only a
cache: a missing one is made again (about a minute).
"""

import json
import os
import re
import shutil
import subprocess
import sys
import zipfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from check_report import report  # noqa: E402 (tests/check_report.py)

HERE = os.path.dirname(os.path.abspath(__file__))
SUITE = "bookworm"


def mirror():
    """The Debian mirror this machine's apt uses (the clean room comes from the same one)."""
    for path in ("/etc/apt/sources.list.d/debian.sources", "/etc/apt/sources.list"):
        if os.path.isfile(path):
            with open(path) as sources:
                for line in sources:
                    match = re.match(r"^\s*(?:URIs:|deb)\s+(\S+)", line)
                    if match and "security" not in match.group(1):
                        return match.group(1)
    raise SystemExit("no Debian mirror found in the apt sources of this machine")


def clean_root():
    cache = os.environ.get("DQJ_CLEANROOM_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "dqjulia", "cleanroom"
    )
    root = os.path.join(cache, SUITE + "-minbase-python3")
    if os.path.isfile(os.path.join(root, ".complete")):
        return root
    os.makedirs(cache, exist_ok=True)
    partial = root + ".partial"
    shutil.rmtree(partial, ignore_errors=True)
    print("making the clean root %s (debootstrap --variant=minbase)" % root, flush=True)
    subprocess.run(
        ["debootstrap", "--variant=minbase", "--include=python3", SUITE, partial, mirror()],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    open(os.path.join(partial, ".complete"), "w").close()
    shutil.rmtree(root, ignore_errors=True)
    os.rename(partial, root)
    return root


def bake(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit("FAIL: %s\n%s%s" % (" ".join(command), result.stdout, result.stderr))
    return json.loads(result.stdout.strip().splitlines()[-1])


def main():
    zip_path, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if os.geteuid() != 0:
        if os.environ.get("CI"):
            raise SystemExit("FAIL: the clean-room test needs root (debootstrap, chroot)")
        print("SKIPPED: the clean-room test needs root (debootstrap, chroot)")
        return 0
    if not shutil.which("debootstrap"):
        raise SystemExit("FAIL: debootstrap is missing: scripts/install-deps.sh installs it")
    root = clean_root()

    # The root really lacks the build's dependencies. (It has libstdc++ and zlib, which apt
    # needs; check_library.py shows the library does not use them.)
    system_libs = os.path.join(root, "usr/lib/x86_64-linux-gnu")
    present = [
        name
        for name in os.listdir(system_libs)
        if re.match(r"lib(openvdb|tbb|OpenEXR|Imath|png16|hwy|boost|freetype)", name)
    ]
    checks = {
        "the clean root has no OpenVDB, TBB, OpenEXR, Imath, libpng, Highway, Boost or FreeType%s"
        % (" (found %s)" % ", ".join(present) if present else ""): not present
    }

    inside = os.path.join(root, "tmp", "dqjulia-cleanroom")
    shutil.rmtree(inside, ignore_errors=True)
    os.makedirs(inside)
    with zipfile.ZipFile(zip_path) as archive:
        archive.extractall(inside)
    os.chmod(os.path.join(inside, "dqjulia", "lib", "libdqjulia.so"), 0o755)
    shutil.copy(os.path.join(HERE, "bake_with_native.py"), inside)
    clean = bake(
        [
            "chroot",
            root,
            "/usr/bin/python3",
            "/tmp/dqjulia-cleanroom/bake_with_native.py",
            "/tmp/dqjulia-cleanroom/dqjulia",
            "/tmp/dqjulia-cleanroom/work",
        ]
    )
    host = bake(
        [
            sys.executable,
            os.path.join(HERE, "bake_with_native.py"),
            os.path.join(inside, "dqjulia"),
            os.path.join(work, "host"),
        ]
    )
    shutil.rmtree(inside, ignore_errors=True)

    print("clean root: %s" % json.dumps(clean, sort_keys=True))
    print("this machine: %s" % json.dumps(host, sort_keys=True))
    for key in ("vdb_bytes", "active_voxels", "voxels_evaluated", "mesh_vertices", "mesh_triangles", "ply_bytes"):
        checks["%s equal (%s)" % (key, clean[key])] = clean[key] == host[key] and clean[key] > 0
    checks["library version %s" % clean["version"]] = clean["version"] == host["version"]
    checks["errors explained (%s)" % clean["error_message"]] = (
        clean["error_message"] == host["error_message"] and "iterations" in clean["error_message"]
    )
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
