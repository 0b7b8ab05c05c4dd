#!/usr/bin/env python3
"""Reproduces the figures of the paper "Dual-Quaternion Julia Fractals" with dqjulia.

    examples/reproduce_paper.py [--dqjulia build/bin/dqjulia] [--out out/paper] [--small]

Writes, under --out:
  detail.png   the "Level of Detail" / teaser sweep: the high-detail constant at N = 6 ... 15
  test2.png    the six "random parameter" tiles of "test2" (tile 1's -023 read as -0.23);
               a tile whose slice is empty says so, with the reason, instead of a picture
  highres.png, highres2.png   the two "High-Detail" figures (N = 15)
  voxels.png   "Voxel vs Ray-Traced": ray traced, then baked at 50^3 and 100^3 and rendered
  sheet.png    all of the above on one contact sheet
Every picture comes from the parameter files in examples/, so each can be re-rendered alone.
"""
import argparse
import json
import pathlib
import re
import subprocess
import sys

EXAMPLES = pathlib.Path(__file__).resolve().parent
ROOT = EXAMPLES.parent


def run(*args):
    print("+", " ".join(str(a) for a in args), flush=True)
    subprocess.run([str(a) for a in args], check=True)


def inspect(dqjulia, params, *flags):
    out = subprocess.run([str(dqjulia), "inspect", "--json", "--samples", "16", "-p", str(params), *flags],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def constant_text(params):
    c = json.loads(pathlib.Path(params).read_text())["fractal"]["c"]
    fmt = lambda part: "(" + ", ".join(f"{v:g}" for v in part) + ")"
    return "c = " + fmt(c[:4]) + fmt(c[4:])


def empty_note(report):
    """One short line for a tile whose slice is empty: which part is dust, and from which N."""
    found = re.search(r"empty for N >= (\d+)", report["empty_reason"])
    outside = [name for name in ("real", "dual") if not report[name]["in_mandelbrot"]]
    note = "EMPTY under the paper's rule"
    if outside:
        part = report[outside[-1]]["complex"]
        note += f": the {outside[-1]} part ({part[0]:.3g} + {part[1]:.3g}i) is outside the Mandelbrot set"
    if found:
        note += f", so with b fixed at 0 the slice is empty for N >= {found.group(1)}"
    return note + "."


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dqjulia", default=ROOT / "build" / "bin" / "dqjulia", type=pathlib.Path)
    parser.add_argument("--out", default=ROOT / "out" / "paper", type=pathlib.Path)
    parser.add_argument("--small", action="store_true", help="small, fast pictures (for tests and previews)")
    args = parser.parse_args()
    dq, out = args.dqjulia, args.out
    out.mkdir(parents=True, exist_ok=True)
    size = ["-W", "240", "-H", "180", "-s", "1"] if args.small else ["-W", "480", "-H", "360", "-s", "2"]
    big = ["-W", "320", "-H", "240", "-s", "1"] if args.small else ["-W", "800", "-H", "600", "-s", "3"]
    render = lambda params, target, *flags: run(dq, "render", "-q", "--force", "-p", params, *size, *flags, "-o", target)

    # Level of detail: the iteration count N changes the shape (math.md: the DE bounds the
    # distance to the limit set, not to the N-iteration set).
    tiles = []
    for n in (6, 8, 10, 12, 15):
        target = out / f"detail_n{n:02d}.png"
        render(EXAMPLES / "paper-teaser.json", target, "-n", str(n))
        tiles += ["-t", target, "-l", f"N = {n}"]
    run(dq, "sheet", "--force", "--columns", "5", *tiles, "-o", out / "detail.png")

    # test2: six constants; say on the tile when the maths shows the slice is empty.
    tiles = []
    for index in range(1, 7):
        params = EXAMPLES / f"paper-test2-{index}.json"
        target = out / f"test2_{index}.png"
        render(params, target)
        report = inspect(dq, params)
        label = f"test2 #{index}: {constant_text(params)}"
        if report["empty"]:
            label += "\n" + empty_note(report)
        tiles += ["-t", target, "-l", label]
    run(dq, "sheet", "--force", "--columns", "3", "--label-lines", "6", *tiles, "-o", out / "test2.png")

    # High detail, N = 15.
    for name in ("highres", "highres2"):
        run(dq, "render", "-q", "--force", "-p", EXAMPLES / f"paper-{name}.json", *big, "-o", out / f"{name}.png")

    # Voxel vs ray traced: the same constant and view, ray traced and baked at 50^3 and 100^3.
    params = EXAMPLES / "paper-highres.json"
    traced = out / "voxels_traced.png"
    render(params, traced)
    tiles = ["-t", traced, "-l", "ray traced (sphere tracing the distance estimate)"]
    for resolution in (50, 100):
        vdb = out / f"voxels_{resolution}.vdb"
        picture = out / f"voxels_{resolution}.png"
        run(dq, "bake", "-q", "--force", "-p", params, "--resolution", resolution, "-o", vdb)
        render(params, picture, "--voxels", vdb)
        tiles += ["-t", picture, "-l", f"baked at {resolution}^3 voxels, rendered as cubes"]
    run(dq, "sheet", "--force", "--columns", "3", *tiles, "-o", out / "voxels.png")

    sheet = []
    for name, label in (("detail", "Level of detail: N = 6, 8, 10, 12, 15"), ("test2", "test2: six constants"),
                        ("highres", "High-Detail 1"), ("highres2", "High-Detail 2"), ("voxels", "Voxel vs ray traced")):
        sheet += ["-t", out / f"{name}.png", "-l", label]
    run(dq, "sheet", "--force", "--columns", "1", *sheet, "-o", out / "sheet.png")
    print(f"wrote {out}/sheet.png and the figures beside it")
    return 0


if __name__ == "__main__":
    sys.exit(main())
