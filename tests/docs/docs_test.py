#!/usr/bin/env python3
"""The documentation site tested like code (label `docs`):

docs_test.py build       --sphinx SPHINX_BUILD --cli DQJULIA --out DIR
    the site builds with warnings as errors (MyST's heading anchors: every internal link and
    anchor resolves, every page is in the table of contents); the figures it prints are the
    closing note's: pages and their sizes, links checked, the build time
docs_test.py references  --cli DQJULIA --out DIR
    the generated references the build wrote (DIR/_generated) equal what the command says now:
    `dqjulia schema`, `dqjulia --help` and every subcommand's `--help`; every schema key and
    every subcommand is on its page
docs_test.py examples    --cli DQJULIA --work DIR
    every shell example marked runnable (a `% runnable` line right above a ```sh fence) on the
    Command line, Baking and farms and POV-Ray pages runs with the built command and succeeds
docs_test.py c-examples  --cc CC --include DIR... --lib LIBDIR --work DIR
    every ```c example of the C and C++ API page compiles (-Wall -Wextra -Werror) and runs
docs_test.py extract-cpp --out DIR
    writes every ```cpp example of the C and C++ API page to DIR/example_LINE.cpp (at configure
    time; a file is rewritten only when its text changed), which CMake builds against
    libdqjulia.a like the tests
docs_test.py cpp-examples --program PROGRAM...
    every such example, built, runs and succeeds, printing its results
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "common"))
from check_report import report, skip_or_fail  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
RUNNABLE_PAGES = ("command-line.md", "baking.md", "povray.md")


def fences(page, language, marker=None):
    """The ```LANGUAGE blocks of a page (their text and first line number); with `marker`, only
    those right below a `% MARKER` line."""
    lines = page.read_text(encoding="utf-8").splitlines()
    blocks, index = [], 0
    while index < len(lines):
        if lines[index].strip() == "```" + language:
            start = index
            index += 1
            body = []
            while lines[index].strip() != "```":
                body.append(lines[index])
                index += 1
            above = lines[start - 1].strip() if start > 0 else ""
            if marker is None or above == "% " + marker:
                blocks.append((start + 1, "\n".join(body) + "\n"))
        index += 1
    return blocks


def internal_links():
    """The Markdown links of the pages that point into the site, as (page, target) pairs:
    [text](page.md#anchor), [text](#anchor)."""
    found = []
    for page in sorted(DOCS.glob("*.md")):
        text = page.read_text(encoding="utf-8")
        text = re.sub(r"^ *(`{3,}).*?^ *\1\s*$", "", text, flags=re.S | re.M)  # fenced blocks: code, not links
        text = re.sub(r"`[^`\n]*`", "", text)  # code spans likewise
        found += [
            (page.name, target)
            for target in re.findall(r"\]\(([^)\s]+)\)", text)
            if not re.match(r"[a-z]+:", target) and not target.startswith("images/")
        ]
    return found


def unresolved(out, links):
    """The links whose page or anchor the built site lacks (read from its HTML, beside Sphinx's
    own check)."""
    missing = []
    for page, target in links:
        name, _, anchor = target.partition("#")
        html = out / (Path(name or page).stem + ".html")
        if not html.is_file() or (anchor and 'id="%s"' % anchor not in html.read_text(encoding="utf-8")):
            missing.append("%s -> %s" % (page, target))
    return missing


def build(args):
    out = Path(args.out)
    if out.exists():
        shutil.rmtree(out)
    doctrees = out.parent / (out.name + ".doctrees")
    env = dict(os.environ, DQJ_CLI=args.cli, PYTHONDONTWRITEBYTECODE="1")
    started = time.monotonic()
    done = subprocess.run(
        [args.sphinx, "-b", "html", "-W", "--keep-going", "-E", "-q", "-d", str(doctrees), str(DOCS), str(out)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    seconds = time.monotonic() - started
    print(done.stdout + done.stderr)
    checks = {"sphinx-build -W succeeds (no warning: links, anchors, toctree, references)": done.returncode == 0}
    pages = sorted(DOCS.glob("*.md"))
    for page in pages:
        checks["%s built" % page.name] = (out / (page.stem + ".html")).is_file()
    links = internal_links()
    anchors = [link for link in links if "#" in link[1]]
    missing = unresolved(out, links)
    checks[
        "every internal link (%d, %d to anchors) finds its page and anchor in the site%s"
        % (len(links), len(anchors), ": " + ", ".join(missing) if missing else "")
    ] = bool(links) and not missing
    for page in pages:
        print("page %s: %d bytes" % (page.name, page.stat().st_size))
    print("links checked: %d (%d to anchors); build time %.1f s" % (len(links), len(anchors), seconds))
    return report(checks)


def run_cli(cli, *args):
    return subprocess.run([cli, *args], capture_output=True, text=True, check=True).stdout


def references(args):
    generated = Path(args.out) / "_generated"
    if not generated.is_dir():
        return report({"the site was built (docs.build) with its generated references": False})
    checks = {}
    schema = run_cli(args.cli, "schema")
    checks["the parameter table was made from today's `dqjulia schema`"] = (generated / "schema.json").read_text(
        encoding="utf-8"
    ) == schema
    table = (Path(args.out) / "parameter-file.html").read_text(encoding="utf-8")
    keys = [field["key"] for field in json.loads(schema)["fields"]]
    missing = [
        key
        for key in keys
        if '<code class="docutils literal notranslate"><span class="pre">%s</span></code>' % key not in table
    ]
    checks[
        "every key of the schema (%d) is in the Parameter file page's table%s"
        % (len(keys), ": missing " + ", ".join(missing) if missing else "")
    ] = not missing
    top = run_cli(args.cli, "--help")
    checks["the reference holds today's `dqjulia --help`"] = (generated / "cli" / "dqjulia.txt").read_text(
        encoding="utf-8"
    ) == top
    names = [line.split()[0] for line in top.split("Subcommands:", 1)[1].splitlines() if re.match(r"^  \S", line)]
    page = (Path(args.out) / "command-line.html").read_text(encoding="utf-8")
    for name in names:
        kept = generated / "cli" / (name + ".txt")
        checks["`dqjulia %s --help` is the reference's" % name] = kept.is_file() and kept.read_text(
            encoding="utf-8"
        ) == run_cli(args.cli, name, "--help")
        checks["`dqjulia %s` has its section on the Command line page" % name] = 'id="dqjulia-%s"' % name in page
    checks["the C API page was made from today's header"] = (generated / "dqjulia.h").read_text(encoding="utf-8") == (
        ROOT / "core/include/dqjulia/dqjulia.h"
    ).read_text(encoding="utf-8")
    api = (Path(args.out) / "c-api.html").read_text(encoding="utf-8")
    functions = re.findall(
        r"DQJ_API [^;]*?\b(dqj_\w+)\(", (ROOT / "core/include/dqjulia/dqjulia.h").read_text(encoding="utf-8")
    )
    missing = [name for name in functions if name not in api]
    checks[
        "every function of the header (%d) is on the C API page%s"
        % (len(functions), ": missing " + ", ".join(missing) if missing else "")
    ] = not missing
    names = subprocess.run(
        [sys.executable, "-c", "import dqjulia; print(' '.join(dqjulia.__all__))"],
        env=dict(os.environ, PYTHONPATH=str(ROOT / "python")),
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    python = (Path(args.out) / "python.html").read_text(encoding="utf-8")
    missing = [name for name in names if not name.startswith("_") and 'id="dqjulia.%s"' % name not in python]
    checks[
        "every public name of the Python package (%d) is on the Python API page%s"
        % (len(names), ": missing " + ", ".join(missing) if missing else "")
    ] = bool(names) and not missing
    return report(checks)


def examples(args):
    work = Path(args.work)
    if work.exists():
        shutil.rmtree(work)
    bin_dir = work / "build" / "bin"  # examples name the command `dqjulia` or `build/bin/dqjulia`
    bin_dir.mkdir(parents=True)
    (bin_dir / "dqjulia").symlink_to(Path(args.cli).resolve())
    for name in ("examples", "povray", "scripts"):
        (work / name).symlink_to(ROOT / name)
    (work / "out").mkdir()
    env = dict(os.environ, PATH="%s:%s" % (bin_dir, os.environ.get("PATH", "")))
    checks, count = {}, 0
    for page_name in RUNNABLE_PAGES:
        page = DOCS / page_name
        blocks = fences(page, "sh", "runnable")
        checks["%s has runnable examples" % page_name] = bool(blocks)
        for line, script in blocks:
            count += 1
            if "povray " in script and not shutil.which("povray"):
                skip_or_fail("povray is not installed (scripts/install-deps.sh installs it): %s:%d" % (page_name, line))
            done = subprocess.run(
                ["bash", "-e", "-o", "pipefail", "-c", script],
                cwd=work,
                env=env,
                capture_output=True,
                text=True,
                check=False,
            )
            ok = done.returncode == 0
            if not ok:
                print(
                    "%s:%d failed (exit %d):\n%s\n%s%s"
                    % (page_name, line, done.returncode, script, done.stdout, done.stderr)
                )
            checks["%s:%d runs and succeeds" % (page_name, line)] = ok
    written = [path for path in (work / "out").rglob("*") if path.is_file() and path.stat().st_size > 0]
    checks["the examples wrote files (%d)" % len(written)] = len(written) > 0
    print("runnable examples: %d" % count)
    return report(checks)


def c_examples(args):
    work = Path(args.work)
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    blocks = fences(DOCS / "c-api.md", "c")
    checks = {"the C and C++ API page has C examples": bool(blocks)}
    for line, source in blocks:
        program = work / ("example_%d" % line)
        (work / ("example_%d.c" % line)).write_text(source, encoding="utf-8")
        flags = ["-std=c11", "-Wall", "-Wextra", "-pedantic", "-Werror"] + ["-I" + path for path in args.include]
        built = subprocess.run(
            [
                args.cc,
                *flags,
                str(work / ("example_%d.c" % line)),
                "-o",
                str(program),
                "-L" + args.lib,
                "-ldqjulia",
                "-Wl,-rpath," + args.lib,
            ],
            capture_output=True,
            text=True,
            check=False,
        )
        checks["c-api.md:%d compiles" % line] = built.returncode == 0
        if built.returncode != 0:
            print(built.stdout + built.stderr)
            continue
        run_example(program, "c-api.md:%d" % line, checks, cwd=work)
    return report(checks)


def run_example(program, label, checks, cwd=None):
    """Runs an example program of the C and C++ API page: it succeeds and prints its results
    (the render's size and the refused input's message)."""
    ran = subprocess.run([str(program)], capture_output=True, text=True, check=False, cwd=cwd)
    print(ran.stdout + ran.stderr)
    checks["%s runs and succeeds" % label] = ran.returncode == 0
    checks["%s printed its results" % label] = "rendered 64x48" in ran.stdout and "refused:" in ran.stdout


def extract_cpp(args):
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    wanted = {}
    for line, source in fences(DOCS / "c-api.md", "cpp"):
        wanted[out / ("example_%d.cpp" % line)] = source
    for stale in set(out.glob("example_*.cpp")) - set(wanted):
        stale.unlink()
    for path, source in wanted.items():
        if not path.exists() or path.read_text(encoding="utf-8") != source:
            path.write_text(source, encoding="utf-8")
    return 0


def cpp_examples(args):
    checks = {"the C and C++ API page has C++ examples, built": bool(args.program)}
    for program in args.program:
        run_example(program, Path(program).name, checks)
    return report(checks)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "what", choices=("build", "references", "examples", "c-examples", "extract-cpp", "cpp-examples")
    )
    parser.add_argument("--sphinx")
    parser.add_argument("--cli")
    parser.add_argument("--out")
    parser.add_argument("--work")
    parser.add_argument("--cc")
    parser.add_argument("--include", action="append", default=[])
    parser.add_argument("--lib")
    parser.add_argument("--program", action="append", default=[])
    args = parser.parse_args()
    if args.what == "build" and not (args.sphinx and Path(args.sphinx).is_file()):
        skip_or_fail("Sphinx is not installed (scripts/tool-env.sh sphinx installs it)")
    return {
        "build": build,
        "references": references,
        "examples": examples,
        "c-examples": c_examples,
        "extract-cpp": extract_cpp,
        "cpp-examples": cpp_examples,
    }[args.what](args)


if __name__ == "__main__":
    sys.exit(main())
