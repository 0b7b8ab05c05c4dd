#!/usr/bin/env python3
"""The documentation's pictures are the ones docs/make-pictures.sh makes (label `docs`):

pictures_test.py --build BUILD_DIR --work DIR

- `docs/make-pictures.sh --list` names each picture once, with a step it has;
- every picture a page (docs/*.md) or the README shows (Markdown `![..](..)`, HTML `<img src>`,
  MyST's image and figure directives) is in docs/images/ and on that list, and every picture on
  the list is shown somewhere; docs/images/ holds nothing else;
- each is a PNG of at most MAX_KB;
- the script's quick step (cli: the command's own renders, sheets and the paper's figures) runs
  into DIR and makes each of its pictures at the size of the one in docs/images/.
The other steps (POV-Ray, Blender) take minutes and are not run here.
"""

import argparse
import re
import shutil
import struct
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "common"))
from check_report import report, skip_or_fail  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
IMAGES = DOCS / "images"
SCRIPT = DOCS / "make-pictures.sh"
QUICK_STEP = "cli"
MAX_KB = 400

# ![alt](target "title"), <img ... src="target">, ```{image} target / ```{figure} target
SHOWN = (
    re.compile(r"!\[[^\]]*\]\(\s*<?([^)\s>]+)"),
    re.compile(r"<img\b[^>]*\bsrc\s*=\s*[\"']([^\"']+)[\"']", re.I),
    re.compile(r"^\s*(?:`{3,}|:{3,})\s*\{(?:image|figure)\}\s+(\S+)", re.M),
)


def targets(text):
    """The pictures a page's text shows, in the order of SHOWN's patterns."""
    return [target for pattern in SHOWN for target in pattern.findall(text)]


SAMPLE = (
    'A ![alt *text*](images/a.png "title") and <img alt="b" src="images/b.png"> in a line,\n'
    "```{figure} images/c.png\n:alt: c\n```\n:::{image} ../docs/images/d.png\n:::\n[a link](images/e.png)\n"
)


def shown_pictures():
    """{picture file under docs/images: [pages showing it]}, and the shown pictures that are not
    under docs/images (as 'page: target')."""
    shown, elsewhere = {}, []
    for page in [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]:
        text = page.read_text(encoding="utf-8")
        for target in targets(text):
            path = (page.parent / target.split("#")[0]).resolve()
            if re.match(r"[a-z]+:", target) or path.parent != IMAGES:
                elsewhere.append("%s: %s" % (page.name, target))
            else:
                shown.setdefault(path.name, []).append(page.name)
    return shown, elsewhere


def named(names):
    """': a, b' for a check's name, or nothing."""
    return ": " + ", ".join(names) if names else ""


def png_size(path):
    """(width, height) of a PNG file, or None if it is not one."""
    head = path.read_bytes()[:24]
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", head[16:24])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", required=True, help="the build tree (bin/dqjulia)")
    parser.add_argument("--work", required=True, help="a scratch folder (emptied first)")
    args = parser.parse_args()
    if not shutil.which("optipng"):
        skip_or_fail("optipng is not installed (scripts/install-deps.sh installs it)")
    checks = {}
    found = targets(SAMPLE)
    checks["the pictures of Markdown, HTML and MyST's directives are found, links are not: %s" % found] = found == [
        "images/a.png",
        "images/b.png",
        "images/c.png",
        "../docs/images/d.png",
    ]

    listed = subprocess.run([str(SCRIPT), "--list"], capture_output=True, text=True, check=False)
    checks["make-pictures.sh --list succeeds" + named([listed.stderr.strip()] if listed.returncode else [])] = (
        listed.returncode == 0
    )
    lines = [line.split() for line in listed.stdout.splitlines() if line.strip()]
    steps = {}
    for words in lines:
        if len(words) == 2:
            steps.setdefault(words[1], []).append(words[0])
    checks["--list gives a STEP FILE pair a line, each file once (%d pictures)" % len(lines)] = (
        bool(lines) and all(len(words) == 2 for words in lines) and all(len(s) == 1 for s in steps.values())
    )
    made = set(steps)

    shown, elsewhere = shown_pictures()
    checks["every picture the pages show is in docs/images" + named(elsewhere)] = not elsewhere
    unmade = ["%s (%s)" % (name, ", ".join(shown[name])) for name in sorted(set(shown) - made)]
    checks[
        "every picture the pages and the README show (%d) is one make-pictures.sh makes" % len(shown) + named(unmade)
    ] = bool(shown) and not unmade
    unshown = sorted(made - set(shown))
    checks["every picture make-pictures.sh makes is shown" + named(unshown)] = not unshown
    present = {path.name for path in IMAGES.iterdir()}
    odd = sorted(present ^ made)
    checks["docs/images holds exactly those pictures" + named(odd)] = not odd
    for name in sorted(made & present):
        path = IMAGES / name
        size_kb = path.stat().st_size / 1024
        checks["docs/images/%s is a PNG (%s) of %.0f KB (<= %d)" % (name, png_size(path), size_kb, MAX_KB)] = (
            png_size(path) is not None and size_kb <= MAX_KB
        )

    work = Path(args.work)
    if work.exists():
        shutil.rmtree(work)
    out = work / "images"
    done = subprocess.run(
        [str(SCRIPT), "--build", args.build, "--only", QUICK_STEP, "--out", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    print(done.stdout + done.stderr)
    checks["make-pictures.sh --only %s runs" % QUICK_STEP] = done.returncode == 0
    quick = sorted(name for name, owners in steps.items() if QUICK_STEP in owners)
    checks["the %s step makes pictures (%d)" % (QUICK_STEP, len(quick))] = bool(quick)
    for name in quick:
        made_size = png_size(out / name) if (out / name).is_file() else None
        committed = png_size(IMAGES / name) if (IMAGES / name).is_file() else None
        checks["%s: made %s, as docs/images has it (%s)" % (name, made_size, committed)] = (
            made_size is not None and made_size == committed
        )
    extra = sorted({path.name for path in out.iterdir()} - set(quick)) if out.is_dir() else []
    checks["--out holds nothing but the step's pictures" + named(extra)] = not extra
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
