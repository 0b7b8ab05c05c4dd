"""The Linux archive (an install tree: bin/, lib/, include/, ...) unpacked into minimal Debian
roots (scripts/debian-root.sh SUITE --with python3), as a user on another Linux unpacks it:

- Debian 12 and 13 (glibc 2.36, 2.41): its bin/dqjulia, run from the unpacked tree and through
  a symbolic link on PATH, renders, bakes and meshes; the files are the build machine's (the
  build's own command, same arguments): PNG and PLY byte for byte, VDBs byte for byte but for
  the random id OpenVDB writes into the header, and the same grids and active voxels
  (compare_outputs);
- Debian 11 (glibc 2.31, below the floor): bin/dqjulia fails with exit status 1 and a message
  naming this glibc and the floor, not the loader's "GLIBC_2.34 not found", and writes nothing;
  the command itself (libexec/dqjulia/dqjulia) is refused by the loader there, which is why the
  launcher exists.

Usage: python3 archive_test.py ARCHIVE --reference DQJULIA --compare COMPARE_OUTPUTS --work DIR
       [--floor 2.34]   (as root: debootstrap and chroot)
ARCHIVE: dqjulia-<version>-linux-x64.tar.gz, one top folder holding the tree (or the tree at its
top); DQJULIA: the build's command; COMPARE_OUTPUTS: the build's tests/windows/compare_outputs.
"""

import argparse
import os
import shutil
import subprocess
import sys
import tarfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)
from debian_roots import VERSIONS, debian_root, require_root_tools, run_in, scratch  # noqa: E402

# (file, the command's arguments, compare_outputs kind): as tests/windows/cli_test.py makes them.
OUTPUTS = (
    ("fractal.png", ["render", "-q"], "png"),
    ("fractal.vdb", ["bake", "-q", "-r", "96"], "vdb"),
    ("fractal.ply", ["mesh", "-q", "-r", "96"], "ply"),
)
VDB_ID = slice(21, 57)  # the 36-byte random id (a UUID's text) in every OpenVDB file's header


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    return result.returncode, result.stdout + result.stderr


def unpack(archive, folder):
    """Unpacks ARCHIVE into FOLDER; returns the tree's top (the folder holding bin/dqjulia)."""
    with tarfile.open(archive) as tar:
        if hasattr(tarfile, "tar_filter"):  # Python 3.12, and 3.11 since 3.11.4
            tar.extractall(folder, filter="tar")
        else:
            tar.extractall(folder)
    for top in (folder, *(os.path.join(folder, name) for name in sorted(os.listdir(folder)))):
        if os.path.isfile(os.path.join(top, "bin", "dqjulia")):
            return top
    raise SystemExit("FAIL: %s has no bin/dqjulia (at its top or in one top folder)" % archive)


def same_bytes(kind, made, reference):
    with open(made, "rb") as file:
        a = bytearray(file.read())
    with open(reference, "rb") as file:
        b = bytearray(file.read())
    if kind == "vdb" and len(a) > VDB_ID.stop and len(b) > VDB_ID.stop:
        a[VDB_ID] = b[VDB_ID] = b"-" * 36
    return a == b and len(a) > 0


def glibc_of(root):
    status, stdout, _ = run_in(root, ["getconf", "GNU_LIBC_VERSION"])
    return stdout.strip() if status == 0 else "unknown"


def check_works(args, suite, reference, checks):
    """The archive in a root of a suite at or above the floor: same files as the build's."""
    root = debian_root(suite, ["python3"])
    name = "%s (%s)" % (VERSIONS[suite], glibc_of(root))
    with scratch(root) as (here, inside):
        top = unpack(args.archive, here)
        command = "/" + os.path.relpath(os.path.join(top, "bin", "dqjulia"), root)
        # A link on PATH, as a user makes one: the launcher finds the command through it.
        link = os.path.join(root, "usr", "local", "bin", "dqjulia")
        if os.path.lexists(link):
            os.remove(link)
        os.symlink(command, link)
        try:
            status, stdout, stderr = run_in(root, ["dqjulia", "--version"])
        finally:
            os.remove(link)
        _, version = run([args.reference, "--version"])
        checks["%s: dqjulia --version through a link on PATH: %s" % (name, (stdout + stderr).strip())] = (
            status == 0 and stdout.strip() == version.strip()
        )
        for file, arguments, kind in OUTPUTS:
            made = os.path.join(here, file)
            status, stdout, stderr = run_in(root, [command, *arguments, "-o", inside + "/" + file])
            output = (stdout + stderr).strip()
            checks["%s: dqjulia %s: exit %d%s" % (name, arguments[0], status, " " + output if output else "")] = (
                status == 0
            )
            if status != 0:
                continue
            equal = same_bytes(kind, made, reference[file])
            _, compared = run([args.compare, kind, reference[file], made])
            compared = compared.strip().replace("\n", "; ")
            what = "byte for byte but the VDB's random id" if kind == "vdb" else "byte for byte"
            checks["%s: %s equal to the build machine's, %s (%s)" % (name, file, what, compared)] = equal


def check_refused(args, suite, checks):
    """The archive in a root below the floor: a plain message, not the loader's."""
    root = debian_root(suite, ["python3"])
    glibc = glibc_of(root)
    name = "%s (%s)" % (VERSIONS[suite], glibc)
    with scratch(root) as (here, inside):
        top = unpack(args.archive, here)
        inside_top = "/" + os.path.relpath(top, root)
        for arguments in (["--version"], ["render", "-q", "-o", inside + "/refused.png"]):
            status, stdout, stderr = run_in(root, [inside_top + "/bin/dqjulia", *arguments])
            message = (stdout + stderr).strip()
            checks["%s: dqjulia %s: exit %d, %r" % (name, arguments[0], status, message)] = (
                status == 1
                and "glibc %s" % args.floor in message
                and glibc.replace("glibc ", "") in message
                and "not found" not in message
                and "GLIBC_" not in message
            )
        checks["%s: nothing written" % name] = not os.path.exists(os.path.join(here, "refused.png"))
        status, stdout, stderr = run_in(root, [inside_top + "/libexec/dqjulia/dqjulia", "--version"])
        message = (stdout + stderr).strip()
        first = message.splitlines()[0].split(": ", 1)[-1] if message else ""
        checks["%s: the command itself, without the launcher, is refused by the loader (%s)" % (name, first)] = (
            status != 0 and "GLIBC_" in message
        )


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("archive")
    parser.add_argument("--reference", required=True)
    parser.add_argument("--compare", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--floor", default="2.34")
    args = parser.parse_args()
    args.archive = os.path.abspath(args.archive)
    require_root_tools()
    if not os.path.isfile(args.archive):
        raise SystemExit("FAIL: no archive %s" % args.archive)

    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    reference, checks = {}, {}
    for file, arguments, _ in OUTPUTS:
        reference[file] = os.path.join(args.work, file)
        status, output = run([args.reference, *arguments, "-o", reference[file]])
        if status != 0:
            raise SystemExit("FAIL: the build's dqjulia %s: %s" % (arguments[0], output))
    for suite in ("bookworm", "trixie"):
        check_works(args, suite, reference, checks)
    check_refused(args, "bullseye", checks)
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
