#!/usr/bin/env bash
# Makes every picture of the program's output that the documentation and the README show
# (docs/images/), from the build's own commands, so each can be made again:
#
#   docs/make-pictures.sh [--build DIR] [--out DIR] [--only STEP[,STEP...]]   make them (all steps)
#   docs/make-pictures.sh --list                                             list them, make nothing
#
#   --build DIR  a build tree with bin/dqjulia and dist/dqjulia_blender.zip (build)
#   --out DIR    where the pictures go (docs/images)
#   --only       some of the steps, comma-separated: cli (seconds), povray (5.5 minutes of CPU,
#                about 3 on 2 idle cores), blender-window and blender-renders (Debian's Blender
#                under xvfb-run: 3 to 4 minutes, and 1); all of them about 7 minutes on 2 cores
#   --list       one "STEP FILE" line for each picture (the docs tests compare it with the
#                pictures the pages show)
#
# Each step makes its pictures in a scratch folder; they are made smaller without loss
# (optipng) and only then moved into --out, so a failed step leaves the pictures it would have
# replaced as they were. Needs: the build; for povray POV-Ray, for the Blender steps Debian's
# blender and xvfb-run (scripts/install-deps.sh installs them), and optipng (apt-get install optipng).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

# The pictures, by the step that makes them.
PICTURES=(
  "cli default.png"
  "cli paper-detail.png"
  "cli paper-test2.png"
  "cli paper-voxels.png"
  "cli explore-seed7.png"
  "cli explore-around-highres2.png"
  "povray povray-materials.png"
  "blender-window blender-preview.png"
  "blender-window blender-bakes.png"
  "blender-window blender-variations.png"
  "blender-renders blender-default-preview.png"
  "blender-renders blender-default-volume.png"
  "blender-renders blender-default-mesh.png"
  "blender-renders baked-blender.png"
)
STEPS=(cli povray blender-window blender-renders)

usage() { sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; }
build=$root/build
out=$root/docs/images
only=
while [ $# -gt 0 ]; do
  case "$1" in
    --list) printf '%s\n' "${PICTURES[@]}"; exit 0 ;;
    --build | --out | --only)
      [ $# -ge 2 ] || { echo "make-pictures.sh: $1 needs a value" >&2; exit 2; }
      case "$1" in
        --build) build=$(cd "$2" && pwd) ;;
        --out) out=$2 ;;
        --only) only=$2 ;;
      esac
      shift 2 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "make-pictures.sh: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
steps=("${STEPS[@]}")
if [ -n "$only" ]; then
  IFS=, read -ra steps <<<"$only"
  for step in "${steps[@]}"; do
    [[ " ${STEPS[*]} " == *" $step "* ]] || { echo "make-pictures.sh: no step '$step' (steps: ${STEPS[*]})" >&2; exit 2; }
  done
fi

die() { echo "make-pictures.sh: $*" >&2; exit 1; }
need() { command -v "$1" >/dev/null || die "$1 is missing: $2"; }
wants() { [[ " ${steps[*]} " == *" $1 "* ]]; }
dqjulia=$build/bin/dqjulia
addon=$build/dist/dqjulia_blender.zip
[ -x "$dqjulia" ] || die "$dqjulia is missing: build first (scripts/build.sh)"
need optipng "apt-get install optipng"
if wants povray; then need povray "scripts/install-deps.sh installs it"; fi
if wants blender-window || wants blender-renders; then
  need blender "scripts/install-deps.sh installs Debian's blender"
  need xvfb-run "scripts/install-deps.sh installs it"
  [ -f "$addon" ] || die "$addon is missing: build first (scripts/build.sh)"
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/dqjulia-pictures.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Blender with fresh user folders in the scratch folder, in a virtual display:
# blender_run NAME SCRIPT BLENDER_ARGS SCRIPT_ARGS (the last two ;-separated lists).
blender_run() {
  cmake -DBLENDER="$(command -v blender)" -DXVFB_RUN="$(command -v xvfb-run)" -DUSER="$work/$1/user" \
    "-DBLENDER_ARGS=$3" -DSCRIPT="$2" "-DSCRIPT_ARGS=$4" -P "$root/tests/blender/run_blender.cmake" \
    >"$work/$1.log" 2>&1 || { tail -n 30 "$work/$1.log" >&2; die "Blender failed (its log above)"; }
}

# Moves the step's pictures from the scratch folder into --out, each made smaller first.
deliver() {
  local step=$1 line file
  for line in "${PICTURES[@]}"; do
    [ "${line%% *}" = "$step" ] || continue
    file=${line#* }
    [ -s "$work/pictures/$file" ] || die "step $step made no $file"
    optipng -quiet -o2 -strip all "$work/pictures/$file"
  done
  for line in "${PICTURES[@]}"; do
    [ "${line%% *}" = "$step" ] || continue
    file=${line#* }
    mv -f "$work/pictures/$file" "$out/$file"
    echo "  $out/$file ($(($(stat -c %s "$out/$file") / 1024)) KB)"
  done
}

mkdir -p "$work/pictures"
cd "$work"
for step in "${steps[@]}"; do
  echo "make-pictures.sh: $step"
  started=$SECONDS
  case "$step" in
    cli)
      # The default fractal, as `dqjulia render` draws it (640 x 480).
      "$dqjulia" render -q -o pictures/default.png
      # The paper's figures, small (examples/reproduce_paper.py --small: tiles of 240 x 180).
      python3 "$root/examples/reproduce_paper.py" --dqjulia "$dqjulia" --out paper --small >paper.log 2>&1 ||
        { tail -n 20 paper.log >&2; die "examples/reproduce_paper.py failed (its log above)"; }
      for figure in detail test2 voxels; do cp "paper/$figure.png" "pictures/paper-$figure.png"; done
      # A contact sheet of random constants, and variations around the paper's second figure.
      "$dqjulia" explore -q --seed 7 --count 8 -o explore
      cp explore/sheet.png pictures/explore-seed7.png
      "$dqjulia" explore -q --around "$root/examples/paper-highres2.json" --seed 1 --tile-width 160 \
        --tile-height 120 -o around
      cp around/sheet.png pictures/explore-around-highres2.png
      ;;
    povray)
      # examples/povray/materials.pov: glass, copper and glowing media (smaller than its 960 x 400).
      (cd "$root/examples/povray" && povray +L../../povray +W768 +H320 +A0.3 -D +FN \
        "+O$work/pictures/povray-materials.png" materials.pov) >povray.log 2>&1 ||
        { tail -n 20 povray.log >&2; die "povray failed (its log above)"; }
      ;;
    blender-window)
      # The add-on in a real window: the preview with the sidebar, the bakes beside it, the
      # Variations panel (tests/blender/preview_test.py, which checks as it goes, --screenshots).
      blender_run window "$root/tests/blender/preview_test.py" "--factory-startup;--enable-event-simulate" \
        "--zip;$addon;--work;$work/window/work;--cli;$dqjulia;--screenshots;$work/pictures"
      ;;
    blender-renders)
      # Cycles renders of the default scene's preview and bakes, and of the command's VDB in the
      # add-on's Surface look (docs/blender_pictures.py).
      "$dqjulia" bake -q -r 256 -o baked.vdb
      blender_run renders "$root/docs/blender_pictures.py" "--factory-startup" \
        "--zip;$addon;--work;$work/renders/work;--out;$work/pictures;--vdb;$work/baked.vdb;--resolution;256"
      ;;
  esac
  deliver "$step"
  echo "make-pictures.sh: $step took $((SECONDS - started)) s"
done
