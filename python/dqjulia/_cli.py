"""The `dqjulia` command of the Python package: the console-script entry point that runs the
native command the wheel carries (dqjulia/bin/dqjulia, dqjulia.exe on Windows).

On POSIX the Python process is replaced by the command (exec): the same process id, so its exit
status, its signals (Ctrl-C stops it with status 130) and its standard streams are the command's
own, and nothing of Python stays in memory. Windows has no exec: the command runs as a child in
the same console, which delivers Ctrl-C and Ctrl-Break to both; this process ignores them and
returns the child's exit status, so the command alone decides how to stop.
"""

from __future__ import annotations

import os
import sys

from . import _native

__all__ = ["command_path", "main"]


def command_path() -> str:
    """The path of the native `dqjulia` command the package runs (for subprocess calls, or job
    files of a render farm): bin/ beside the package's modules in the wheel, or an install tree's
    own bin/dqjulia (_native.bundled_file)."""
    return _native.bundled_file("bin", "bin", "dqjulia.exe" if os.name == "nt" else "dqjulia")


def _fail(message: str) -> int:
    print("dqjulia: %s" % message, file=sys.stderr)
    return 1


def main(argv: list[str] | None = None) -> int:
    """Runs the native command with `argv` (default: this process's arguments) and returns its
    exit status (on POSIX it does not return: the command replaces this process)."""
    arguments = sys.argv[1:] if argv is None else list(argv)
    problem = _native.platform_problem()
    if problem is not None:
        return _fail(problem)
    path = command_path()
    if not os.path.isfile(path):
        return _fail("the native command is missing from %s: expected %s; %s" % (_native.HOST, path, _native.REINSTALL))
    if os.name != "nt":
        sys.stdout.flush()
        sys.stderr.flush()
        try:
            os.execv(path, [path, *arguments])
        except OSError as error:
            return _fail("could not run %s: %s" % (path, error))
    import signal
    import subprocess

    for name in ("SIGINT", "SIGBREAK"):  # the console sends them to the command too, which handles them
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    try:
        return subprocess.call([path, *arguments])
    except OSError as error:
        return _fail("could not run %s: %s" % (path, error))
