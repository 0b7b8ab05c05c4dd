"""The add-on's library on a Linux that has none of the project's build dependencies.

In a minimal Debian 12 root with python3 (scripts/debian-root.sh bookworm --with python3, made
once and cached outside the checkout), unpacks the add-on zip and, inside the root
(scripts/in-root.sh), loads the library through the add-on's own native.py and bakes a VDB and a
mesh (bake_with_native.py). The same script then runs on the build machine; the two must make
the same files (sizes, active voxels, mesh counts).

Usage: python3 cleanroom_test.py ZIP WORK   (as root: debootstrap and chroot need it)
"""

import json
import os
import re
import shutil
import subprocess
import sys
import zipfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)
from debian_roots import debian_root, require_root_tools, run_in, scratch  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def bake(command, root=None):
    """Runs bake_with_native.py (here, or inside ROOT) and returns its JSON line."""
    if root:
        status, stdout, stderr = run_in(root, command)
    else:
        result = subprocess.run(command, capture_output=True, text=True)
        status, stdout, stderr = result.returncode, result.stdout, result.stderr
    if status != 0:
        raise SystemExit("FAIL: %s\n%s%s" % (" ".join(command), stdout, stderr))
    return json.loads(stdout.strip().splitlines()[-1])


def main():
    zip_path, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    require_root_tools()
    root = debian_root("bookworm", ["python3"])

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

    with scratch(root) as (here, inside):
        with zipfile.ZipFile(zip_path) as archive:
            archive.extractall(here)
        os.chmod(os.path.join(here, "dqjulia", "lib", "libdqjulia.so"), 0o755)
        shutil.copy(os.path.join(HERE, "bake_with_native.py"), here)
        shutil.copy(os.path.join(HERE, "..", "common", "package_module.py"), here)
        clean = bake(
            ["/usr/bin/python3", inside + "/bake_with_native.py", inside + "/dqjulia", inside + "/work"], root=root
        )
        host = bake(
            [
                sys.executable,
                os.path.join(HERE, "bake_with_native.py"),
                os.path.join(here, "dqjulia"),
                os.path.join(work, "host"),
            ]
        )

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
