#!/usr/bin/env python3
"""Checks that the includes between the folders of core/src run one way (CONTRIBUTING.md, "Layout"),
and that the system-specific code of core/ stays in core/src/platform/.

    scripts/check-layout.py              check core/src (and that core/, tests/, bench/ name the folder)
    scripts/check-layout.py --self-test  plant lines that break the rules in a copy and expect them caught

A source in core/src/FOLDER/ may include the internal headers of its own folder and of the folders
ALLOWED[FOLDER] names; c_api.cpp, at the top, may include any. An internal header is always included
by its folder ("files/atomic_file.hpp", relative to core/src), from core/src as from core/cli, tests/ and
bench/. The public headers (core/include/dqjulia/, "dqjulia/...") are the installed API: any folder may
include them. Outside core/src/platform/, no line of core/ (core/src, core/cli, core/include) tests
_WIN32 unless the comment right above it (or on it) says why, with "why:" (platform/platform.hpp
holds what differs between the systems). Run by scripts/check-style.sh. Exit status: 0 clean, 1 findings.
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
SYSTEM_TEST = re.compile(r"^\s*#\s*(if|ifdef|ifndef|elif)\b.*\b_WIN32\b")
COMMENT = re.compile(r"^\s*(//|/\*|\*)")
SOURCES = (".c", ".cpp", ".h", ".hpp")


def folder_of(source: pathlib.Path, src: pathlib.Path) -> str:
    parts = source.relative_to(src).parts
    return parts[0] if len(parts) > 1 else TOP


def system_tests(root: pathlib.Path) -> list[str]:
    """Lines of core/ outside core/src/platform/ that test _WIN32 with no "why:" comment above or on them."""
    platform = root / "core" / "src" / "platform"
    findings = []
    for path in sorted((root / "core").rglob("*")):
        if path.suffix not in SOURCES or platform in path.parents:
            continue
        lines = path.read_text(errors="replace").splitlines()
        for index, line in enumerate(lines):
            if not SYSTEM_TEST.match(line):
                continue
            above = index - 1
            comment = [line]
            while above >= 0 and COMMENT.match(lines[above]):
                comment.append(lines[above])
                above -= 1
            if not any("why:" in text for text in comment):
                findings.append(
                    f"{path.relative_to(root)}:{index + 1}: tests _WIN32 outside core/src/platform/: put the "
                    "system's step behind platform/platform.hpp, or say in a comment above it "
                    '("why: ...") why it cannot'
                )
    return findings


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
    findings += system_tests(root)
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
    """The check passes on the tree, catches lines planted in a copy of core/src, and lets pass a
    system test whose comment says why."""
    failures = []
    if check(root):
        failures.append("the tree itself has findings")
    # Where to plant, what, and the line of the one finding expected (0: none expected).
    plants = [
        ("files/atomic_file.cpp", '#include "render/image_writer.hpp"', 1),  # upwards: files -> render
        ("render/render.cpp", '#include "bake/level_set.hpp"', 1),  # sideways: render -> bake
        ("platform/threads.cpp", '#include "thread_scratch.hpp"', 1),  # no folder named
        ("kernel/slice.cpp", '#include "files/no_such_file.hpp"', 1),  # no such file
        ("bake/memory.cpp", "#ifdef _WIN32\n#endif", 1),  # a system test outside platform/, no reason
        ("render/image.cpp", "// A comment, but no reason.\n#if defined(_WIN32) && 1\n#endif", 2),
        ("kernel/slice.cpp", "// why: a reason, two lines\n// above the test.\n#ifndef _WIN32\n#endif", 0),
        ("platform/threads.cpp", "#ifdef _WIN32\n#endif", 0),  # inside platform/: allowed
    ]
    for target, text, line in plants:
        with tempfile.TemporaryDirectory() as scratch:
            copy = pathlib.Path(scratch)
            shutil.copytree(root / "core" / "src", copy / "core" / "src")
            for base in ("core/cli", "tests", "bench"):
                (copy / base).mkdir(parents=True, exist_ok=True)
            planted = copy / "core" / "src" / target
            planted.write_text(text + "\n" + planted.read_text())
            found = [f for f in check(copy) if f.startswith(f"core/src/{target}:")]
            expected = 1 if line else 0
            if len(found) != expected or (line and not found[0].startswith(f"core/src/{target}:{line}:")):
                failures.append(f"{text!r} in {target}: expected {expected} finding(s) at line {line}, got {found}")
    for failure in failures:
        print(f"check-layout self-test: FAIL: {failure}")
    if not failures:
        print(f"check-layout self-test: the tree is clean and all {len(plants)} planted lines were judged right")
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
