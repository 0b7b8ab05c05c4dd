#!/usr/bin/env python3
"""Checks that the includes between the folders of core/src run one way (CONTRIBUTING.md, "Layout").

    scripts/check-layout.py              check core/src (and that core/, tests/, bench/ name the folder)
    scripts/check-layout.py --self-test  plant includes that break the rules in a copy and expect them caught

A source in core/src/FOLDER/ may include the internal headers of its own folder and of the folders
ALLOWED[FOLDER] names; c_api.cpp, at the top, may include any. An internal header is always included
by its folder ("files/atomic_file.hpp", relative to core/src), from core/src as from core/cli, tests/ and
bench/. The public headers (core/include/dqjulia/, "dqjulia/...") are the installed API: any folder may
include them. Run by scripts/check-style.sh. Exit status: 0 clean, 1 findings.
"""

from __future__ import annotations

import pathlib
import re
import shutil
import sys
import tempfile

# Lowest first. Each folder may include itself and these (the rule table of CONTRIBUTING.md).
ALLOWED = {
    "platform": set(),  # threads, per-thread scratch, parallel loops with progress, glibc floor
    "files": {"platform"},  # atomic files, file names, messages, text input, VDB files
    "params": {"platform", "files"},  # the schema, the parameter file, keyframes
    "kernel": {"platform", "files", "params"},  # the escape iteration, SIMD batches, slices, colouring, inspect
    "render": {"platform", "files", "params", "kernel"},  # the renderer, images, POV-Ray scenes
    "bake": {"platform", "files", "params", "kernel"},  # bakes, level sets, meshes, attribute grids
    "tiles": {"platform", "files", "params", "kernel", "bake"},  # tiled bakes and their merge
    "explore": {"platform", "files", "params", "kernel"},  # variations around a document
}
TOP = ""  # core/src itself: c_api.cpp, over everything
ALLOWED[TOP] = set(ALLOWED)

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
SOURCES = (".c", ".cpp", ".h", ".hpp")


def folder_of(source: pathlib.Path, src: pathlib.Path) -> str:
    parts = source.relative_to(src).parts
    return parts[0] if len(parts) > 1 else TOP


def check(root: pathlib.Path) -> list[str]:
    src = root / "core" / "src"
    internal = {p.name: p.relative_to(src).as_posix() for p in src.rglob("*") if p.suffix in (".hpp", ".h")}
    findings = []
    for path in sorted(src.rglob("*")):
        if path.suffix not in SOURCES:
            continue
        folder = folder_of(path, src)
        if folder not in ALLOWED:
            findings.append(f"{path.relative_to(root)}: folder {folder!r} is not in the rule table of {__file__}")
            continue
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            match = INCLUDE.match(line)
            if not match or match.group(1).startswith("dqjulia/") or match.group(1) == "dqjulia.inc":
                continue
            name = match.group(1)
            where = f"{path.relative_to(root)}:{number}"
            if "/" not in name:
                hint = f' (write "{internal[name]}")' if name in internal else ""
                findings.append(f'{where}: #include "{name}" does not name its folder{hint}')
                continue
            target = name.split("/")[0]
            if not (src / name).is_file():
                findings.append(f'{where}: #include "{name}": no such file in core/src')
            elif target != folder and target not in ALLOWED[folder]:
                findings.append(
                    f'{where}: #include "{name}" runs against the layout: {folder or "core/src"}/ may include '
                    f"{', '.join(sorted(ALLOWED[folder])) or 'nothing else'} (CONTRIBUTING.md, Layout)"
                )
    # Outside core/src, an internal header is named by its folder too.
    for base in ("core/cli", "tests", "bench"):
        for path in sorted((root / base).rglob("*")):
            if path.suffix not in SOURCES:
                continue
            for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
                match = INCLUDE.match(line)
                if match and match.group(1) in internal:
                    findings.append(
                        f'{path.relative_to(root)}:{number}: #include "{match.group(1)}" does not name its '
                        f'folder (write "{internal[match.group(1)]}")'
                    )
    return findings


def self_test(root: pathlib.Path) -> int:
    """The check passes on the tree, and catches includes planted in a copy of core/src."""
    failures = []
    if check(root):
        failures.append("the tree itself has findings")
    plants = {
        "files/atomic_file.cpp": '#include "render/image_writer.hpp"',  # upwards: files -> render
        "render/render.cpp": '#include "bake/level_set.hpp"',  # sideways: render -> bake
        "platform/threads.cpp": '#include "thread_scratch.hpp"',  # no folder named
        "kernel/slice.cpp": '#include "files/no_such_file.hpp"',  # no such file
    }
    for target, include in plants.items():
        with tempfile.TemporaryDirectory() as scratch:
            copy = pathlib.Path(scratch)
            shutil.copytree(root / "core" / "src", copy / "core" / "src")
            for base in ("core/cli", "tests", "bench"):
                (copy / base).mkdir(parents=True, exist_ok=True)
            planted = copy / "core" / "src" / target
            planted.write_text(include + "\n" + planted.read_text())
            found = [f for f in check(copy) if f.startswith(f"core/src/{target}:1:")]
            if len(found) != 1:
                failures.append(f"{include} in {target}: expected one finding, got {found}")
    for failure in failures:
        print(f"check-layout self-test: FAIL: {failure}")
    if not failures:
        print(f"check-layout self-test: the tree is clean and all {len(plants)} planted includes were caught")
    return 1 if failures else 0


def main() -> int:
    root = pathlib.Path(__file__).resolve().parent.parent
    if sys.argv[1:] == ["--self-test"]:
        return self_test(root)
    if sys.argv[1:]:
        print(__doc__, file=sys.stderr)
        return 2
    findings = check(root)
    for finding in findings:
        print(finding)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
