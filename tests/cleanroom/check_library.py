"""Checks that a libdqjulia.so is self-contained: it needs no shared library but glibc's own,
no glibc symbol version newer than the floor, no search path (RPATH, RUNPATH) but one relative to
itself ($ORIGIN), and exports nothing but the C ABI (dqj_*). With --program, the same for the
dqjulia command, whose exports are not checked.

Usage: python3 check_library.py LIBRARY [--glibc-floor 2.34] [--program]
Prints the NEEDED list, the highest GLIBC_ version and the exported symbols' count.
"""

import argparse
import re
import subprocess
import sys

# glibc's own libraries: present on every glibc-based Linux.
ALLOWED_NEEDED = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1", "ld-linux-x86-64.so.2"}


def run(*command):
    return subprocess.run(command, check=True, capture_output=True, text=True).stdout


def version_key(text):
    return tuple(int(part) for part in text.split("."))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("library")
    parser.add_argument("--glibc-floor", default="2.34")
    parser.add_argument("--program", action="store_true", help="an executable: its exports are not checked")
    args = parser.parse_args()
    failures = []

    dynamic = run("readelf", "-d", args.library)
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic)
    print("NEEDED:", " ".join(needed))
    for name in needed:
        if name not in ALLOWED_NEEDED:
            failures.append("needs %s, which is not one of glibc's own libraries" % name)
    for kind, path in re.findall(r"\((RPATH|RUNPATH)\)\s+Library \w+: \[([^\]]*)\]", dynamic):
        print("%s: %s" % (kind, path))
        if any(part and not part.startswith("$ORIGIN") for part in path.split(":")):
            failures.append("its %s %s names a folder of the build machine" % (kind, path))

    symbols = run("objdump", "-T", args.library).splitlines()
    versions = {}
    exported = []
    for line in symbols:
        fields = line.split()
        if len(fields) < 6 or not re.match(r"^[0-9a-f]{16}$", fields[0]):
            continue
        name = fields[-1]
        version = fields[-2]
        match = re.match(r"^\(?GLIBC_([0-9.]+)\)?$", version)
        if match:
            versions.setdefault(match.group(1), []).append(name)
        elif "*UND*" not in line:
            exported.append(name)
    highest = max(versions, key=version_key) if versions else "none"
    print("highest GLIBC_ version: %s (%s)" % (highest, ", ".join(sorted(versions.get(highest, [])))[:200]))
    for version, names in versions.items():
        if version_key(version) > version_key(args.glibc_floor):
            failures.append(
                "needs GLIBC_%s (above the floor %s) for %s" % (version, args.glibc_floor, ", ".join(names))
            )

    if args.program:
        exported = []
    strays = [name for name in exported if not name.startswith("dqj_")]
    print("exported symbols: %d (dqj_*), %d others" % (len(exported) - len(strays), len(strays)))
    if strays:
        failures.append("exports symbols outside the C ABI: %s" % ", ".join(sorted(strays)[:20]))

    for failure in failures:
        print("FAIL: " + failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
