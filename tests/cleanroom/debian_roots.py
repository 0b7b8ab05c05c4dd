"""What the clean-room tests share: a minimal Debian root of a suite (scripts/debian-root.sh,
made once and cached outside the checkout), a command run inside one (scripts/in-root.sh: its
own /proc, /dev and /run, a clean environment), and a scratch folder inside one that is removed
afterwards. Roots need root (debootstrap, chroot): without it the tests skip, or fail under CI."""

import contextlib
import os
import shutil
import subprocess
import tempfile

from check_report import skip_or_fail

SCRIPTS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "scripts")
VERSIONS = {"bullseye": "Debian 11", "bookworm": "Debian 12", "trixie": "Debian 13"}


def require_root_tools():
    if os.geteuid() != 0:
        skip_or_fail("the clean-room tests need root (debootstrap, chroot)")
    for tool in ("debootstrap", "unshare", "chroot"):
        if not shutil.which(tool):
            skip_or_fail("%s is missing: scripts/install-deps.sh installs it" % tool)


def debian_root(suite, packages=()):
    """The path of the cached minimal root of SUITE with PACKAGES (made the first time)."""
    command = [os.path.join(SCRIPTS, "debian-root.sh"), suite]
    if packages:
        command += ["--with", *packages]
    result = subprocess.run(command, stdout=subprocess.PIPE, text=True)
    if result.returncode != 0:
        raise SystemExit("FAIL: scripts/debian-root.sh %s could not make the root" % " ".join(command[1:]))
    return result.stdout.strip()


def run_in(root, command, env=()):
    """Runs COMMAND (a list) inside ROOT; returns (exit status, stdout, stderr)."""
    options = [part for name in env for part in ("--env", name)]
    result = subprocess.run(
        [os.path.join(SCRIPTS, "in-root.sh"), root, *options, "--", *command], capture_output=True, text=True
    )
    return result.returncode, result.stdout, result.stderr


@contextlib.contextmanager
def scratch(root):
    """A new folder under ROOT's /tmp: yields (its path here, its path inside the root)."""
    path = tempfile.mkdtemp(prefix="dqjulia-test.", dir=os.path.join(root, "tmp"))
    try:
        yield path, "/" + os.path.relpath(path, root)
    finally:
        shutil.rmtree(path, ignore_errors=True)
