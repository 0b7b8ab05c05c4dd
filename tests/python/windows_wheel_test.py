"""The Windows wheel (no Windows Python exists here): scripts/build-wheels.py on the Windows build,
twice with the same bytes; its contents, tags, metadata and RECORD (wheel_support.check_wheel);
`twine check`; and, unpacked as pip installs it, its entry point as on Windows (os.name "nt"):
it finds dqjulia/bin/dqjulia.exe, runs it (under Wine) with the arguments, returns its exit
status and ignores Ctrl-C and Ctrl-Break meanwhile, and the picture it renders equals the Linux
build's (compare_outputs); its _native.py, told it runs on Windows, loads dqjulia/lib/dqjulia.dll.

Usage: python3 windows_wheel_test.py SOURCE WINDOWS_BUILD LINUX_BUILD TWINE WORK EMULATOR...
"""

import os
import shutil
import signal
import subprocess
import sys
import types
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "common"))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "windows"))
from addon_zip_test import load_on_windows  # noqa: E402 (tests/windows: native.py's loading as on Windows)
from check_report import report, skip_or_fail  # noqa: E402 (tests/common/check_report.py)
from package_module import load_package_module  # noqa: E402 (tests/common/package_module.py)
from wheel_support import check_wheel  # noqa: E402

PLATFORM = "win_amd64"


def windows_path(path):
    """A Linux path as a Windows program under Wine names it: drive Z: is /."""
    return "Z:" + os.path.abspath(path).replace("/", "\\")


def load_cli(package):
    """The wheel's dqjulia._cli as on Windows: os.name "nt" (its _native and _buildinfo imported
    from the same folder, the package's __init__ not run: it would load nothing on Linux)."""
    cli = load_package_module(os.path.join(package, "_cli.py"), "dqjulia_windows")
    cli.os = types.SimpleNamespace(name="nt", path=os.path)
    return cli


def main():
    source, windows_build, linux_build, twine, work, *emulator = sys.argv[1:]
    compare = os.path.join(linux_build, "bin", "compare_outputs")
    linux_cli = os.path.join(linux_build, "bin", "dqjulia")
    for program in (compare, linux_cli):
        if not os.access(program, os.X_OK):
            skip_or_fail("%s is missing: build the Linux tree first (scripts/build.sh)" % program)
    with open(os.path.join(source, "VERSION")) as file:
        version = file.read().strip()
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    checks = {}
    name = "dqjulia-%s-py3-none-%s.whl" % (version, PLATFORM)
    made = []
    for run in ("a", "b"):
        result = subprocess.run(
            [
                sys.executable,
                os.path.join(source, "scripts", "build-wheels.py"),
                "--windows-build",
                windows_build,
                "--no-sdist",
                "--out",
                os.path.join(work, run),
            ],
            capture_output=True,
            text=True,
        )
        checks["build-wheels.py --windows-build (run %s) %s" % (run, result.stderr.strip()[-300:])] = (
            result.returncode == 0 and os.path.basename(result.stdout.strip()) == name
        )
        path = os.path.join(work, run, name)
        if os.path.isfile(path):
            with open(path, "rb") as file:
                made.append(file.read())
    checks["two runs write the same bytes"] = len(made) == 2 and made[0] == made[1]
    wheel = os.path.join(work, "a", name)
    if not os.path.isfile(wheel):
        return report(checks)
    epoch = int(
        subprocess.run(["git", "-C", source, "log", "-1", "--format=%ct"], capture_output=True, text=True).stdout
    )
    checks.update(check_wheel(wheel, source, version, PLATFORM, epoch))

    if os.access(twine, os.X_OK):
        result = subprocess.run([twine, "check", "--strict", wheel], capture_output=True, text=True)
        checks["twine check --strict: %s" % result.stdout.strip().splitlines()[-1:]] = result.returncode == 0
    else:
        skip_or_fail("twine is not installed (scripts/tool-env.sh twine installs it)")

    # Unpacked as pip installs it, the entry point as on Windows.
    site = os.path.join(work, "site-packages")
    with zipfile.ZipFile(wheel) as archive:
        archive.extractall(site)
    package = os.path.join(site, "dqjulia")
    cli = load_cli(package)
    exe = os.path.join(package, "bin", "dqjulia.exe")
    checks["command_path() on Windows is dqjulia/bin/dqjulia.exe"] = cli.command_path() == exe

    calls = []
    real_call = subprocess.call

    def call_under_wine(command, **options):
        """subprocess.call as Windows runs the command: here through Wine, recording the handlers."""
        calls.append(
            {
                "command": command,
                "sigint ignored": signal.getsignal(signal.SIGINT) is signal.SIG_IGN,
                "output": subprocess.run([*emulator, *command], capture_output=True, text=True),
            }
        )
        return calls[-1]["output"].returncode

    png = os.path.join(work, "wheel.png")
    reference = os.path.join(work, "linux.png")
    saved = signal.getsignal(signal.SIGINT)
    subprocess.call = call_under_wine
    try:
        statuses = {
            "version": cli.main(["--version"]),
            "bad flag": cli.main(["render", "--no-such-flag"]),
            "render": cli.main(["render", "-q", "-W", "96", "-H", "72", "-o", windows_path(png)]),
        }
    finally:
        subprocess.call = real_call
        signal.signal(signal.SIGINT, saved)
    checks["the entry point runs bin/dqjulia.exe with the arguments"] = [call["command"][0] for call in calls] == [
        exe
    ] * 3 and calls[0]["command"][1:] == ["--version"]
    checks["dqjulia --version through the entry point: %s" % calls[0]["output"].stdout.strip()] = (
        statuses["version"] == 0 and calls[0]["output"].stdout.strip() == "dqjulia %s" % version
    )
    checks["the command's exit status is returned (bad input: %s)" % statuses["bad flag"]] = statuses["bad flag"] == 2
    checks["Ctrl-C is left to the command while it runs (SIGINT ignored)"] = all(
        call["sigint ignored"] for call in calls
    )
    subprocess.run([linux_cli, "render", "-q", "-W", "96", "-H", "72", "-o", reference], check=True)
    result = subprocess.run([compare, "png", png, reference], capture_output=True, text=True)
    checks["the picture rendered through the entry point equals Linux's (%s)" % result.stdout.strip()[-80:]] = (
        statuses["render"] == 0 and result.returncode == 0
    )

    native, added, loaded, features, bound = load_on_windows(os.path.join(package, "_native.py"))
    library = os.path.join(package, "lib", "dqjulia.dll")
    checks["_native.py on Windows loads the wheel's dqjulia/lib/dqjulia.dll: %s" % loaded] = loaded == [library]
    checks["_native.py on Windows adds the DLL's folder to the search path"] = added == [os.path.dirname(library)]
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
